#!/usr/bin/python3
"""Command-line tests of -hssbem_save and -hssbem_load on a static solve's H2 path
(docs/persistence.md): the H2 operator and PC h2's factors, one file per rank.

Usage:
    /usr/bin/python3 test_h2_persistence_cli.py --driver PATH/hssbem --meshes REPO/meshes [--mpiexec mpiexec]
                                                [unittest arguments, e.g. H2PersistenceTests]

The harness is test_cli.py's. A static solve saved after its solve and loaded instead of the
compression and the factorization gives the cold run's iterations and answer to the bit, with
the same loads and with new ones, on one rank and on two; a file made for another mesh,
material, pattern, options or number of ranks, a truncated or altered file, and a save of a
solve not on the H2 path each end with one "hssbem: error:" line naming the problem, and leave
no result file.
"""

import os
import sys
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_cli  # noqa: E402
from test_cli import CliTestCase, TIMEOUT_RUN  # noqa: E402

SAVED = "organ.pre"  # not .h5: the harness counts .h5 files as results left behind
# Small leaves and a small top, so that the 1k organ's factorization has levels of steps.
H2 = ("-bem_mat_type", "h2", "-mat_h2_leaf_size", "16", "-pc_h2_top_size", "120")


class H2PersistenceTests(CliTestCase):
    def organ(self, name="problem.json", push=-0.03, free_y=True, mesh="disk_organ_1k.msh", E=3000.0):
        """The disk organ clamped below and indented from above (meshes/examples/disk_organ_indent.json)."""
        return self.problem(mesh=self.copy_mesh(mesh), material={"E": E, "nu": 0.49}, name=name, boundary=[
            {"where": {"region": "bottom"}, "displacement": [0, 0, 0]},
            {"where": {"sphere": {"center": [0, 0, 0.3], "radius": 0.3}}, "displacement": [None, None if free_y else 0, push]}])

    def solve(self, problem, *args, np=1):
        r = self.run_problem(problem, *(H2 + args), np=np, timeout=TIMEOUT_RUN)
        self.assertSucceeds(r, self.out)
        import h5py
        with h5py.File(self.out, "r") as f:
            answer = {k: f[k][()].tobytes() for k in ("fields/displacement", "fields/traction")}
            answer["iterations"] = int(f.attrs["iterations"])
        for name in (self.out, os.path.splitext(self.out)[0] + ".xdmf"):
            if os.path.exists(name):
                os.remove(name)
        return r, answer

    def saved(self, np=1):
        self.organ()
        r, answer = self.solve("problem.json", "-hssbem_save", SAVED, np=np)
        self.assertRegex(r.output, r"saved the precomputation to organ\.pre in [\d.]+ s")
        for rank in range(1, np):
            self.assertTrue(os.path.isfile(self.path("%s.rank%d" % (SAVED, rank))), r.describe())
        return answer

    def test_loaded_solve_is_the_cold_one_bitwise(self):
        for np_ in (1, 2):
            with self.subTest(ranks=np_):
                cold = self.saved(np=np_)
                self.assertGreater(cold["iterations"], 1)  # GMRES with PC h2, not a direct solve
                r, warm = self.solve("problem.json", "-hssbem_load", SAVED, np=np_)
                self.assertRegex(r.output, r"loaded the H2 operator from organ\.pre in [\d.]+ s")
                self.assertEqual(warm, cold)
                # new loads: the same pattern, another indentation
                self.organ("other.json", push=-0.01)
                _, other_cold = self.solve("other.json", np=np_)
                _, other_warm = self.solve("other.json", "-hssbem_load", SAVED, np=np_)
                self.assertNotEqual(other_cold["fields/displacement"], cold["fields/displacement"])
                self.assertEqual(other_warm, other_cold)

    def refused(self, pattern, problem="problem.json", *args, np=1):
        r = self.run_problem(problem, *(H2 + args), np=np, timeout=TIMEOUT_RUN)
        self.assertFailsCleanly(r, pattern)
        self.assertErrorLine(r)

    def test_each_difference_is_refused(self):
        self.saved()
        load = ("-hssbem_load", SAVED)
        self.organ("mesh.json", mesh="disk_organ_4k.msh")
        self.refused(r"cannot load 'organ\.pre': the mesh differs: \d+ vertices and \d+ triangles in the file, \d+ vertices and \d+ triangles in the problem",
                     "mesh.json", *load)
        self.organ("material.json", E=2000.0)
        self.refused(r"cannot load 'organ\.pre': the material differs: E 3000, nu 0\.49 in the file, E 2000, nu 0\.49 in the problem", "material.json", *load)
        self.organ("pattern.json", free_y=False)
        self.refused(r"cannot load 'organ\.pre': the pattern of prescribed components differs", "pattern.json", *load)
        self.refused(r"cannot load 'organ\.pre': the options differ: -mat_h2_rel_tol 1e-05 in the file, 0\.0001 in the problem", "problem.json", *load,
                     "-mat_h2_rel_tol", "1e-4")
        self.refused(r"cannot load 'organ\.pre': the options differ: -pc_h2_top_size 120 in the file, 200 in the problem", "problem.json", *load,
                     "-pc_h2_top_size", "200")
        self.refused(r"cannot load 'organ\.pre': the number of ranks differs: 1 in the file, 2 in the problem", "problem.json", *load, np=2)

    def test_file_of_two_ranks_is_refused_on_one(self):
        self.saved(np=2)
        self.refused(r"cannot load 'organ\.pre': the number of ranks differs: 2 in the file, 1 in the problem", "problem.json", "-hssbem_load", SAVED)

    def test_damaged_files_are_refused(self):
        self.saved()
        data = open(self.path(SAVED), "rb").read()
        self.write("cut.pre", data[:len(data) // 2])
        self.refused(r"cannot load 'cut\.pre': the file is truncated or extended", "problem.json", "-hssbem_load", "cut.pre")
        for at in (len(data) // 3, len(data) - 100):
            flipped = bytearray(data)
            flipped[at] ^= 0x10
            self.write("flip.pre", bytes(flipped))
            self.refused(r"cannot load 'flip\.pre': (the file is damaged: its checksum does not match|its array '[^']+' is damaged: the checksum of a chunk does not match)",
                         "problem.json", "-hssbem_load", "flip.pre")
        self.refused(r"cannot load 'problem\.json': not a file hssbem saved", "problem.json", "-hssbem_load", "problem.json")

    def test_only_the_h2_path_is_saved(self):
        self.organ()
        for pattern, args in ((r"-hssbem_save: only a static solve on the H2 operator with PC h2", ("-bem_mat_type", "h2", "-pc_type", "jacobi", "-hssbem_save", SAVED)),
                              (r"-hssbem_load: a saved static precomputation is the H2 operator's and PC h2's; this solve takes the dense operator",
                               ("-bem_mat_type", "dense", "-hssbem_load", SAVED))):
            r = self.run_problem("problem.json", *args, timeout=TIMEOUT_RUN)
            self.assertFailsCleanly(r, pattern)
            self.assertErrorLine(r)


if __name__ == "__main__":
    test_cli.run_suite(__doc__)
