#!/usr/bin/python3
"""Command-line tests of -hssbem_save and -hssbem_load (docs/persistence.md).

Usage:
    /usr/bin/python3 test_persistence_cli.py --driver PATH/hssbem --meshes REPO/meshes [--mpiexec mpiexec]
                                             [unittest arguments, e.g. PersistenceTests]

The harness is test_cli.py's. A contact scene saved after its set-up and loaded instead of it
gives the cold run's frames to the bit, on one rank and on two (the contact is rank 0's); a
file made for another problem, a damaged file, a file that is not one, a save over an input and
the options on a job without a precomputation to keep each end with one "hssbem: error:" line
naming the problem, and leave no result file.
"""

import os
import sys
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_cli  # noqa: E402
from test_cli import TIMEOUT_RUN  # noqa: E402
import test_contact_cli  # noqa: E402
from test_contact_cli import ContactCase, TABLE  # noqa: E402

SAVED = "cube.pre"  # not .h5: the harness counts .h5 files as results left behind


class PersistenceTests(ContactCase):
    def scene(self, **kw):
        frames = [{"obstacles": {"table": {"translate": [0, 0, 0.002 * i]}}} for i in range(3)]
        return self.cube_contact({"obstacles": [TABLE]}, frames=frames, **kw)

    def saved(self, *args):
        self.scene()
        r = self.run_problem("problem.json", "-hssbem_save", SAVED, *args, timeout=TIMEOUT_RUN)
        self.assertSucceeds(r, self.out, self.path(SAVED))
        self.assertRegex(r.output, r"saved the precomputation to cube\.pre in [\d.]+ s")
        self.remove_result()
        return r

    def remove_result(self):
        os.remove(self.out)
        os.remove(os.path.splitext(self.out)[0] + ".xdmf")

    def frames(self, path):
        import h5py
        with h5py.File(path, "r") as f:
            return [[f["/frames/%d/%s" % (i, k)][()].tobytes() for k in ("displacement", "traction", "contact/pressure")]
                    for i in range(int(f.attrs["num_frames"]))]

    def test_loaded_frames_are_the_cold_ones_bitwise(self):
        self.saved()
        for np_ in (1, 2):
            cold = self.run_problem("problem.json", np=np_, timeout=TIMEOUT_RUN)
            self.assertSucceeds(cold, self.out)
            expected = self.frames(self.out)
            self.remove_result()
            warm = self.run_problem("problem.json", "-hssbem_load", SAVED, np=np_, timeout=TIMEOUT_RUN)
            self.assertSucceeds(warm, self.out)
            self.assertRegex(warm.output, r"loaded the precomputation from cube\.pre in [\d.]+ s")
            self.assertEqual(self.frames(self.out), expected, "%d ranks" % np_)
            self.remove_result()

    def refused(self, pattern, *args):
        r = self.run_problem("problem.json", *args, timeout=TIMEOUT_RUN)
        self.assertFailsCleanly(r, pattern)
        self.assertErrorLine(r)

    def test_another_material_is_refused(self):
        self.saved()
        self.refused(r"cannot load 'cube\.pre': the material differs: E 1000, nu 0\.3 in the file, E 2000, nu 0\.3 in the problem",
                     "-hssbem_load", SAVED, "-E", "2000")

    def test_another_option_is_refused(self):
        self.saved()
        self.refused(r"cannot load 'cube\.pre': the options differ: -contact_reach 0 in the file, 0\.2 in the problem",
                     "-hssbem_load", SAVED, "-contact_reach", "0.2")

    def test_damaged_files_are_refused(self):
        self.saved()
        data = open(self.path(SAVED), "rb").read()
        self.write("cut.pre", data[:len(data) // 2])
        self.refused(r"cannot load 'cut\.pre': the file is truncated or extended", "-hssbem_load", "cut.pre")
        flipped = bytearray(data)
        flipped[len(data) // 3] ^= 0x10
        self.write("flip.pre", bytes(flipped))
        self.refused(r"cannot load 'flip\.pre': (the file is damaged: its checksum does not match|its array '[^']+' is damaged: the checksum of a chunk does not match)",
                     "-hssbem_load", "flip.pre")
        self.refused(r"cannot load 'problem\.json': not a file hssbem saved", "-hssbem_load", "problem.json")
        self.refused(r"cannot load 'nothing\.pre': no such file", "-hssbem_load", "nothing.pre")

    def test_save_over_an_input_is_refused(self):
        self.scene()
        self.refused(r"cannot write output 'cube_l0\.msh': it is the input file", "-hssbem_save", "cube_l0.msh")
        self.assertTrue(os.path.getsize(self.path("cube_l0.msh")) > 0)

    def test_not_a_contact(self):
        self.write_cube()
        self.problem()
        self.refused(r"-hssbem_save: only a static solve on the H2 operator with PC h2", "-hssbem_save", SAVED, "-bem_mat_type", "dense")

    def plain_scene(self):
        """A scene without contact: cube_l0 clamped at z = 0, its top pressed down frame by frame."""
        frames = [{"boundary": [{"where": {"region": "z1"}, "displacement": [None, None, -0.002 * (i + 1)]}]} for i in range(3)]
        self.cube_l0_problem([{"where": {"region": "z0"}, "displacement": [0, 0, 0]}], frames=frames)

    def test_scene_loaded_frames_are_the_cold_ones_bitwise(self):
        self.plain_scene()
        strategy = ("-scene_strategy", "update")  # auto's choice follows measured times
        r = self.run_problem("problem.json", "-hssbem_save", SAVED, *strategy, timeout=TIMEOUT_RUN)
        self.assertSucceeds(r, self.out, self.path(SAVED))
        self.assertRegex(r.output, r"scene: saved the precomputation to cube\.pre in [\d.]+ s")
        expected = self.frames_of_scene(self.out)
        self.assertGreater(max(abs(f[-1]) for f in expected[-1]), 0.005)  # the top pressed: no test by doing nothing
        self.remove_result()
        warm = self.run_problem("problem.json", "-hssbem_load", SAVED, *strategy, timeout=TIMEOUT_RUN)
        self.assertSucceeds(warm, self.out)
        self.assertRegex(warm.output, r"scene: loaded the precomputation from cube\.pre in [\d.]+ s")
        self.assertEqual([f.tobytes() for f in self.frames_of_scene(self.out)], [f.tobytes() for f in expected])
        self.remove_result()
        self.refused(r"cannot load 'cube\.pre': the material differs: E 1000, nu 0\.3 in the file, E 2000, nu 0\.3 in the problem",
                     "-hssbem_load", SAVED, "-E", "2000", *strategy)

    def frames_of_scene(self, path):
        import h5py
        with h5py.File(path, "r") as f:
            return [f["/frames/%d/displacement" % i][()] for i in range(int(f.attrs["num_frames"]))]

    def test_h2_reference_is_not_saved_yet(self):
        self.scene()
        self.refused(r"-hssbem_save: only dense reference factorizations are saved and loaded yet; this contact takes the h2 one",
                     "-hssbem_save", SAVED, "-bem_mat_type", "h2")


if __name__ == "__main__":
    test_contact_cli.main()
