#!/usr/bin/python3
"""Hostile runs of the hssbem driver (issue: no silent garbage, no clobbered file, no late
refusal, no geometry that is not a body, no option value that hangs or aborts a good run): each
ends with one clean error line (exit status 1, no result or temporary file) or a correct answer.

Usage:
    /usr/bin/python3 test_reliability.py --driver PATH/hssbem --meshes REPO/meshes [--mpiexec mpiexec]
                                         [unittest arguments, e.g. a class name]

The helpers (temporary directory per test, problem files, assertions) are test_cli.py's.
"""

import math
import os
import re
import socket
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_cli  # noqa: E402  (the CLI tests' helpers and option parsing)
from test_cli import CliTestCase, OneCleanError, off_text, CUBE_VERTICES, CUBE_TRIANGLES  # noqa: E402


def icosphere(level, scale=1.0, shift=0.0):
    """A unit sphere (subdivided icosahedron, outward triangles): 10·4^level + 2 vertices."""
    t = (1 + 5 ** 0.5) / 2
    verts = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
             (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    verts = [tuple(c / math.sqrt(sum(x * x for x in v)) for c in v) for v in verts]
    tris = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
            (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
            (8, 6, 7), (9, 8, 1)]
    for _ in range(level):
        mid, out = {}, []

        def middle(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                m = [(verts[a][k] + verts[b][k]) / 2 for k in range(3)]
                r = math.sqrt(sum(x * x for x in m))
                verts.append(tuple(x / r for x in m))
                mid[key] = len(verts) - 1
            return mid[key]
        for a, b, c in tris:
            ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
            out += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        tris = out
    return [tuple(scale * x + shift for x in v) for v in verts], tris


def host_tag():
    """This host's name as the driver puts it in temporary names (io/temp_files.cpp)."""
    return re.sub(r"[^A-Za-z0-9-]", "-", socket.gethostname()) or "host"


def dead_pid():
    """The id of a process that has just ended (and so is not alive)."""
    p = subprocess.Popen(["true"])
    p.wait()
    return p.pid


class SphereTestCase(OneCleanError, CliTestCase):
    """A 642-vertex sphere (1 926 unknowns: the dense path) under pressure."""

    def sphere_problem(self, scale=1.0, shift=0.0, name="sphere.off"):
        verts, tris = icosphere(3, scale, shift)
        self.write(name, off_text(verts, tris))
        return self.problem(mesh=name, boundary=[{"where": "all", "pressure": 1.0}])

    def run_failing(self, *args, np=None):
        return self.run_problem("problem.json", "-options_left", *args, np=np, timeout=test_cli.TIMEOUT_RUN)


# ---------------------------------------------------------------------------------------------
# No result without a solution


class GarbageTests(SphereTestCase):
    def test_sphere_scaled_by_1e120_is_refused(self):
        # Before: the dense path wrote a result with "relative residual -nan" and exited 0.
        self.sphere_problem(scale=1e120)
        self.assertOneCleanError(self.run_failing("-bem_mat_type", "dense"), r"sphere.off", r"extent|size")

    def test_sphere_shifted_by_1e15_is_refused(self):
        # Before: the same -nan result; the coordinates keep no digit of the triangles' shape.
        self.sphere_problem(shift=1e15)
        self.assertOneCleanError(self.run_failing("-bem_mat_type", "dense"), r"sphere.off", r"digits|precision")

    def test_preonly_with_a_loose_preconditioner_is_an_error(self):
        # Before: -ksp_type preonly -pc_type jacobi wrote a result with relative residual 6.8.
        # The bound on the true residual is the PETSc face's (HssbemSolveSystem,
        # -hssbem_residual_max): this case runs once the driver lists that option.
        if "-hssbem_residual_max" not in self.run_driver("-help").output:
            self.skipTest("the driver has no -hssbem_residual_max yet (the residual bound of HssbemSolveSystem)")
        self.sphere_problem()
        r = self.run_failing("-bem_mat_type", "dense", "-ksp_type", "preonly", "-pc_type", "jacobi")
        self.assertOneCleanError(r, r"residual")

    def test_material_and_loads_beyond_1e30_are_refused(self):
        # Before: -E 1e-300 wrote a result with relative residual -nan; so did a pressure of 1e300.
        self.sphere_problem()
        self.assertOneCleanError(self.run_failing("-bem_mat_type", "dense", "-E", "1e-300"), r"E = 1e-300 lies outside")
        self.problem(mesh="sphere.off", boundary=[{"where": "all", "pressure": 1e300}])
        self.assertOneCleanError(self.run_failing("-bem_mat_type", "dense"), r"boundary\[0\]\.pressure: value 1e\+300 exceeds")

    def test_the_same_sphere_unscaled_solves(self):
        # The guards above refuse the geometry, not the problem: the sphere itself solves.
        self.sphere_problem()
        r = self.run_problem("problem.json", "-bem_mat_type", "dense", timeout=test_cli.TIMEOUT_RUN)
        self.assertSucceeds(r, self.out)
        residual = float(re.search(r"relative residual (\S+)", r.stdout).group(1))
        self.assertBelow(residual, 3e-15, "residual")  # measured 1.1e-15 (dense LU)


# ---------------------------------------------------------------------------------------------
# Output safety: an input is never replaced, leftovers of dead processes are swept


class ClobberTests(OneCleanError, CliTestCase):
    def setUp(self):
        super().setUp()
        self.write_cube()
        self.problem()
        with open(self.path("problem.json")) as f:
            self.problem_text = f.read()
        with open(self.path("cube.off")) as f:
            self.mesh_text = f.read()

    def assertInputsIntact(self, r):
        with open(self.path("problem.json")) as f:
            self.assertEqual(f.read(), self.problem_text, r.describe())
        with open(self.path("cube.off")) as f:
            self.assertEqual(f.read(), self.mesh_text, r.describe())

    def refused(self, output, *extra):
        r = self.run_driver("-problem", "problem.json", "-o", output, "-options_left", *extra)
        # No .h5 or .xdmf may appear (the inputs are neither).
        self.assertOneCleanError(r, r"is the input file")
        self.assertInputsIntact(r)
        return r

    def test_output_naming_the_problem_file_is_refused(self):
        # Before: the problem file was replaced by the HDF5 result, exit status 0.
        self.refused("problem.json")
        self.refused(os.path.join(self.tmp, ".", "problem.json"))

    def test_output_naming_the_mesh_is_refused(self):
        # Before: the mesh was replaced by the HDF5 result, exit status 0.
        self.refused("cube.off")
        self.refused("./cube.off")
        os.mkdir(self.path("sub"))
        os.symlink(self.tmp, self.path("sub/up"))  # the same directory under another path
        self.refused("sub/up/cube.off")

    def test_output_naming_an_input_through_a_link_is_refused(self):
        os.link(self.path("cube.off"), self.path("hard.off"))
        self.problem(mesh="hard.off")
        with open(self.path("problem.json")) as f:
            self.problem_text = f.read()
        self.refused("cube.off")

    def test_sidecar_naming_an_input_is_refused(self):
        os.rename(self.path("problem.json"), self.path("run.xdmf"))
        r = self.run_driver("-problem", "run.xdmf", "-o", "run.h5", "-options_left")
        self.assertEqual(r.returncode, 1, r.describe())
        self.assertEqual(len(re.findall(r"hssbem: error: ", r.output)), 1, r.describe())
        self.assertRegex(r.output, r"XDMF sidecar .*run.xdmf.* is the input file", r.describe())
        self.assertEqual(self.leftovers(), ["run.xdmf"], r.describe())  # the input, unchanged
        with open(self.path("run.xdmf")) as f:
            self.assertEqual(f.read(), self.problem_text)

    def test_stale_temporaries_of_dead_processes_are_swept(self):
        # Before: a SIGKILLed run's out.h5.tmp.<pid> stayed for ever.
        host, dead, alive = host_tag(), dead_pid(), os.getpid()
        stale = ["out.h5.tmp.%s.%d.0badc0de" % (host, dead), "out.xdmf.tmp.%s.%d.0badc0de" % (host, dead),
                 "out.h5.bak.%s.%d.12345678" % (host, dead)]
        kept = ["out.h5.tmp.%s.%d.0badc0de" % (host, alive),             # a live process's
                "out.h5.tmp.other-host.%d.0badc0de" % dead,               # another host's
                "other.h5.tmp.%s.%d.0badc0de" % (host, dead)]             # another result's
        for name in stale + kept:
            self.write(name, "partial")
        r = self.run_problem(timeout=test_cli.TIMEOUT_RUN)
        self.assertEqual(r.returncode, 0, r.describe())
        left = sorted(os.listdir(self.tmp))
        for name in stale:
            self.assertNotIn(name, left, r.describe())
        for name in kept:
            self.assertIn(name, left, r.describe())


# ---------------------------------------------------------------------------------------------
# Scenes validated whole before frame 0; a frame that fails is an error


class SceneValidationTests(OneCleanError, CliTestCase):
    BASE = [{"where": {"region": "base"}, "displacement": [0, 0, 0]}]

    def scene(self, frames):
        mesh = self.copy_mesh("cardioid_832.msh")
        return self.problem(mesh=mesh, material={"lambda": 1000.0, "mu": 500.0}, boundary=self.BASE,
                            frames=[{"boundary": f} for f in frames], name="scene.json")

    @staticmethod
    def push(vertex, depth):
        return [{"where": {"vertices": [vertex]}, "displacement": [0, 0, -depth]}]

    def test_a_bad_40th_frame_is_refused_before_any_frame_is_solved(self):
        # Before: refused after 39 frames had been solved (the work lost).
        frames = [self.push(10 + i, 0.01) for i in range(39)] + [self.push(100000, 0.01)]
        self.scene(frames)
        r = self.run_problem("scene.json", "-options_left", "-scene_monitor", timeout=test_cli.TIMEOUT_RUN)
        self.assertOneCleanError(r, r"frames\[39\]\.boundary\[0\]", r"100000")
        self.assertNotRegex(r.output, r"scene: set up|frame 0:", "a frame was solved first\n" + r.describe())

    @staticmethod
    def patch(phi, depth):
        c = [0.45 * math.cos(phi), 0.45 * math.sin(phi), 0.5]
        return [{"where": {"sphere": {"center": c, "radius": 0.3}}, "displacement": [-depth * math.cos(phi), None, None]}]

    def frames_failing_at_1(self):
        # krylov with one GMRES iteration: frame 0 (the reference pattern) converges at once,
        # frame 1 (a contact patch switches about 40 unknowns) cannot.
        self.scene([[], self.patch(0.0, 0.04), self.patch(0.2, 0.045)])
        return ["-scene_strategy", "krylov", "-scene_ksp_max_it", "1"]

    def test_a_frame_that_does_not_converge_is_an_error(self):
        r = self.run_problem("scene.json", "-options_left", *self.frames_failing_at_1(), timeout=test_cli.TIMEOUT_RUN)
        self.assertOneCleanError(r, r"frames\[1\]", r"did not converge")

    def test_keep_partial_commits_the_frames_solved_before(self):
        import h5py
        r = self.run_problem("scene.json", *self.frames_failing_at_1(), "-scene_keep_partial", timeout=test_cli.TIMEOUT_RUN)
        self.assertEqual(r.returncode, 1, r.describe())
        self.assertRegex(r.output, r"hssbem: error: .*frames\[1\].*did not converge.*the 1 frames solved before it are in", r.describe())
        with h5py.File(self.out, "r") as f:
            self.assertEqual(int(f.attrs["num_frames"]), 1)
            self.assertEqual(int(f.attrs["complete"]), 0)
            self.assertEqual(int(f.attrs["failed_frame"]), 1)
            self.assertIn("/frames/0/displacement", f)
            self.assertNotIn("/frames/1", f)


# ---------------------------------------------------------------------------------------------
# Geometry that is not a body


def grid_cube(n, shift=0.0):
    """The unit cube + shift (along each axis) with n x n squares a face, outward triangles."""
    index, verts, tris = {}, [], []

    def vertex(k):
        if k not in index:
            index[k] = len(verts)
            verts.append(tuple(shift + c / n for c in k))
        return index[k]
    for a in range(3):
        u, v = (a + 1) % 3, (a + 2) % 3
        for side in (0, n):
            for p in range(n):
                for q in range(n):
                    def at(i, j):
                        k = [0, 0, 0]
                        k[a], k[u], k[v] = side, i, j
                        return vertex(tuple(k))
                    c00, c10, c11, c01 = at(p, q), at(p + 1, q), at(p + 1, q + 1), at(p, q + 1)
                    for t in ((c00, c10, c11), (c00, c11, c01)):
                        tris.append(t if side == n else (t[0], t[2], t[1]))
    return verts, tris


class GeometryTests(OneCleanError, CliTestCase):
    def run_mesh(self, verts, tris):
        self.write("mesh.off", off_text(verts, tris))
        self.problem(mesh="mesh.off")
        return self.run_problem("problem.json", "-options_left", timeout=test_cli.TIMEOUT_RUN)

    def test_interpenetrating_cubes_are_refused(self):
        # Before: the second cube was taken for a cavity of the first, flipped and solved.
        second = [(x + 0.5, y + 0.5, z + 0.5) for x, y, z in CUBE_VERTICES]
        tris = CUBE_TRIANGLES + [tuple(8 + i for i in t) for t in CUBE_TRIANGLES]
        r = self.run_mesh(CUBE_VERTICES + second, tris)
        self.assertOneCleanError(r, r"mesh.off", r"triangles \d+ \(.*\) and \d+ \(.*\) intersect", r"components 0 and 1")

    def test_cubes_whose_grids_line_up_crossing_along_edges_are_refused(self):
        # Before: accepted, the second cube taken for a cavity of the first and flipped. Two
        # cubes of 2 x 2 squares a face, the second shifted by half a side along each axis:
        # their faces meet only along grid lines, so no two triangles' interiors cross.
        first, tris = grid_cube(2)
        second, tris2 = grid_cube(2, shift=0.5)
        r = self.run_mesh(first + second, tris + [tuple(len(first) + i for i in t) for t in tris2])
        self.assertOneCleanError(r, r"mesh.off", r"the surfaces of component 0 and component 1 pass through each other along triangle edges or at vertices",
                                 r"vertex \d+ \(of component 0\) lies inside component 1, vertex \d+ outside it")

    def test_a_surface_through_itself_is_refused(self):
        # Before: accepted. The north pole of a sphere pushed out through the south pole.
        verts, tris = icosphere(2)
        pole = max(range(len(verts)), key=lambda v: verts[v][2])
        verts[pole] = (verts[pole][0], verts[pole][1], -1.5)
        r = self.run_mesh(verts, tris)
        self.assertOneCleanError(r, r"mesh.off", r"triangles \d+ .* intersect", r"passes through itself")

    def test_separate_cubes_and_a_cavity_are_accepted(self):
        far = [(x + 2.0, y, z) for x, y, z in CUBE_VERTICES]
        tris = CUBE_TRIANGLES + [tuple(8 + i for i in t) for t in CUBE_TRIANGLES]
        r = self.run_mesh(CUBE_VERTICES + far, tris)
        self.assertSucceeds(r, self.out)


# ---------------------------------------------------------------------------------------------
# Option values: out of range is an error, never a hang or an aborted good run


class OptionValueTests(OneCleanError, CliTestCase):
    def setUp(self):
        super().setUp()
        self.write_cube()
        self.problem()

    def test_error_timeout_must_be_positive_and_finite(self):
        # Before: nan or inf let an unguarded fault hang; 0 or -1 aborted a successful 2-rank run.
        for value in ("nan", "inf", "0", "-1"):
            for np in (None, 2):
                with self.subTest(value=value, np=np):
                    r = self.run_problem("problem.json", "-options_left", "-hssbem_error_timeout", value, np=np, timeout=60)
                    self.assertOneCleanError(r, r"-hssbem_error_timeout")

    def test_bounded_driver_options(self):
        for args, pattern in ((["-hssbem_memory_limit", "inf"], r"-hssbem_memory_limit"),
                              (["-mat_bem_near_ratio", "1e9"], r"-mat_bem_near_ratio"),
                              (["-bem_mat_type", "dense", "-mat_bem_far_ratio", "inf"], r"-mat_bem_far_ratio"),
                              (["-scene_refresh", "2000000000"], r"-scene_refresh")):
            with self.subTest(args=args):
                self.assertOneCleanError(self.run_problem("problem.json", "-options_left", *args), pattern)


def main():
    test_cli.run_suite(__doc__)


if __name__ == "__main__":
    main()
