#!/usr/bin/python3
"""Tests of scripts/render.py and scripts/make_scenes.py (no hssbem driver needed).

Usage:
    /usr/bin/python3 test_render.py [--scripts REPO/scripts] [--meshes REPO/meshes]
                                    [unittest arguments, e.g. RenderTests or SceneTests]

RenderTests write small synthetic result files with h5py (an octahedron, with and without three
frames) into a temporary directory, run render.py on them and check the PNGs and the GIF (count,
size, frames counted with Pillow), the colour values of --field (per-vertex datasets looked up in
/fields, /contact or a frame's group, vectors by their norm), and that every error case exits
non-zero with a message naming the fault and writes no picture. SceneTests run make_scenes.py on meshes/cardioid_832.msh
and check the problem file it writes (and the shipped scenes): frame count, well-formed per-vertex
rules, the contact fraction, and a patch centre that moves from frame to frame.

Needs numpy, h5py and matplotlib (Debian: python3-numpy, python3-h5py, python3-matplotlib).
"""

import argparse
import glob
import json
import math
import os
import subprocess
import sys
import tempfile
import unittest

import h5py
import numpy as np
from PIL import Image

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPTS = os.path.normpath(os.path.join(HERE, "..", "..", "scripts"))
MESHES = os.path.normpath(os.path.join(HERE, "..", "..", "meshes"))
TIMEOUT = 300

# Regular octahedron, outward triangles.
OCTA_VERTICES = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]],
                         dtype=float)
OCTA_TRIANGLES = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4],
                           [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]], dtype=np.int32)


def write_result(path, frames=3, fields=True, frame_displacement=True, extra=None):
    """A result file shaped like the driver's: /mesh, /fields and, if frames > 0, /frames/<i>;
    `extra` maps further dataset paths to their values."""
    with h5py.File(path, "w") as f:
        f["/mesh/vertices"] = OCTA_VERTICES
        f["/mesh/triangles"] = OCTA_TRIANGLES
        if fields:
            f["/fields/displacement"] = 0.01 * OCTA_VERTICES
            f["/fields/traction"] = OCTA_VERTICES
        for i in range(frames):
            group = f.create_group("/frames/%d" % i)
            u = np.zeros_like(OCTA_VERTICES)
            u[i] = -0.02 * (i + 1) * OCTA_VERTICES[i]  # frame i pushes vertex i in
            if frame_displacement:
                group["displacement"] = u
            group["traction"] = np.ones_like(u)
            group.attrs["seconds"] = 0.01 * (i + 1)
            group.attrs["strategy"] = "refactor" if i == 0 else "update"
            group.attrs["iterations"] = np.int32(3)
        f.create_group("/timings").attrs["solve"] = 0.1
        for name, value in (extra or {}).items():
            f[name] = value


def run_script(name, *args):
    """Run scripts/<name> with this interpreter; the CompletedProcess (text output)."""
    return subprocess.run([sys.executable, os.path.join(SCRIPTS, name)] + list(args),
                          capture_output=True, text=True, timeout=TIMEOUT)


def describe(r):
    return "exit %d\nstdout:\n%s\nstderr:\n%s" % (r.returncode, r.stdout, r.stderr)


class TempDirTest(unittest.TestCase):
    def setUp(self):
        self._tmp = tempfile.TemporaryDirectory(prefix="hssbem_render_")
        self.tmp = self._tmp.name

    def tearDown(self):
        self._tmp.cleanup()

    def path(self, *parts):
        return os.path.join(self.tmp, *parts)


class RenderTests(TempDirTest):
    def render(self, result, *args):
        return run_script("render.py", self.path(result), "-o", self.path("png"), *args)

    def pictures(self):
        return sorted(os.listdir(self.path("png"))) if os.path.isdir(self.path("png")) else []

    def assertPng(self, name, size=(960, 720)):
        path = self.path("png", name)
        self.assertGreater(os.path.getsize(path), 1000, path)
        with Image.open(path) as image:
            self.assertEqual(image.format, "PNG")
            self.assertEqual(image.size, size)

    def assertGif(self, path, frames):
        self.assertGreater(os.path.getsize(path), 1000, path)
        with Image.open(path) as image:
            self.assertEqual(image.format, "GIF")
            self.assertEqual(image.n_frames, frames)

    def test_frames_png_and_gif(self):
        write_result(self.path("r.h5"))
        r = self.render("r.h5", "--gif", self.path("anim.gif"))
        self.assertEqual(r.returncode, 0, describe(r))
        self.assertRegex(r.stdout, r"scale \S+ \(largest \|u\| 0\.06")
        self.assertEqual(self.pictures(), ["frame_0000.png", "frame_0001.png", "frame_0002.png"])
        for name in self.pictures():
            self.assertPng(name)
        self.assertGif(self.path("anim.gif"), 3)

    def test_selected_frames_size_view_scale(self):
        write_result(self.path("r.h5"))
        r = self.render("r.h5", "--frames", "2,0", "--gif", self.path("a.gif"), "--size",
                        "400x300", "--view", "10,30", "--scale", "5", "--fps", "2")
        self.assertEqual(r.returncode, 0, describe(r))
        self.assertNotIn("scale", r.stdout.split("wrote")[0])  # no default scale printed
        self.assertEqual(self.pictures(), ["frame_0000.png", "frame_0002.png"])
        for name in self.pictures():
            self.assertPng(name, (400, 300))
        self.assertGif(self.path("a.gif"), 2)

    def test_result_without_frames(self):
        write_result(self.path("one.h5"), frames=0)
        r = self.render("one.h5")
        self.assertEqual(r.returncode, 0, describe(r))
        self.assertEqual(self.pictures(), ["displacement.png"])
        self.assertPng("displacement.png")

    def test_default_outdir(self):
        write_result(self.path("scene.h5"), frames=2)
        r = run_script("render.py", self.path("scene.h5"))
        self.assertEqual(r.returncode, 0, describe(r))
        self.assertEqual(sorted(os.listdir(self.path("scene_render"))),
                         ["frame_0000.png", "frame_0001.png"])

    def test_titles_and_shared_colour_scale(self):
        sys.path.insert(0, SCRIPTS)
        import render
        write_result(self.path("r.h5"))
        vertices, triangles, frames = render.load_result(self.path("r.h5"), None)
        self.assertEqual([f.index for f in frames], [0, 1, 2])
        self.assertEqual(frames[1].title(), "frame 1, update, 0.02 s")
        scale, largest = render.default_scale(vertices, frames)
        self.assertAlmostEqual(largest, 0.06)
        self.assertAlmostEqual(scale * largest, 0.1 * 2.0)  # 10 % of the size 2

    def assertFails(self, r, pattern, status=1):
        self.assertEqual(r.returncode, status, describe(r))
        self.assertRegex(r.stderr, pattern)
        self.assertEqual(self.pictures(), [], "no picture expected on error")

    def test_missing_file(self):
        self.assertFails(self.render("absent.h5"), r"render\.py: error: .*absent\.h5: no such file")

    def test_not_hdf5(self):
        with open(self.path("text.h5"), "w") as f:
            f.write("not an HDF5 file\n")
        self.assertFails(self.render("text.h5"), r"text\.h5: not a readable HDF5 file")

    def test_no_displacement(self):
        write_result(self.path("r.h5"), frames=0, fields=False)
        self.assertFails(self.render("r.h5"), r"r\.h5: no dataset /fields/displacement")

    def test_frame_without_displacement(self):
        write_result(self.path("r.h5"), frame_displacement=False)
        self.assertFails(self.render("r.h5"), r"no dataset /frames/0/displacement")

    def test_frame_that_does_not_exist(self):
        write_result(self.path("r.h5"))
        self.assertFails(self.render("r.h5", "--frames", "1,7"),
                         r"frame 7 does not exist \(the file has frames 0\.\.2\)")

    def test_frames_on_a_file_without_frames(self):
        write_result(self.path("r.h5"), frames=0)
        self.assertFails(self.render("r.h5", "--frames", "0"), r"no /frames group")

    def test_field_von_mises_and_contact_fallback(self):
        von_mises = np.arange(6, dtype=float)
        write_result(self.path("r.h5"), frames=0,
                     extra={"/fields/von_mises": von_mises, "/contact/pressure": 2 * von_mises})
        r = self.render("r.h5", "--field", "von_mises")
        self.assertEqual(r.returncode, 0, describe(r))
        self.assertEqual(self.pictures(), ["fields_von_mises.png"])
        self.assertPng("fields_von_mises.png")
        r = self.render("r.h5", "--field", "pressure")  # not in /fields: /contact/pressure
        self.assertEqual(r.returncode, 0, describe(r))
        self.assertIn("contact_pressure.png", self.pictures())

    def test_field_values_vectors_and_paths(self):
        sys.path.insert(0, SCRIPTS)
        import render
        stress = np.zeros((6, 6))
        stress[:, 2] = 3.0
        stress[:, 3] = 4.0
        extra = {"/fields/stress": stress, "/fields/von_mises": np.array([1, np.nan, 2, 3, 4, 5.0])}
        write_result(self.path("r.h5"), frames=0, extra=extra)
        _, _, frames = render.load_result(self.path("r.h5"), None, "stress")
        self.assertEqual(frames[0].field, "/fields/stress")
        np.testing.assert_allclose(frames[0].colour, 5.0)  # rows colour by their norm
        _, _, frames = render.load_result(self.path("r.h5"), None, "/fields/von_mises")
        np.testing.assert_allclose(frames[0].colour, [1, 0, 2, 3, 4, 5])  # NaN counts as 0
        _, _, frames = render.load_result(self.path("r.h5"), None, None)
        np.testing.assert_allclose(frames[0].colour, 0.01)  # default: |u|

    def test_field_columns(self):
        sys.path.insert(0, SCRIPTS)
        import render
        stress = np.tile(np.arange(6, dtype=float), (6, 1))  # column k holds k
        principal = np.tile([3.0, 2.0, -1.0], (6, 1))
        write_result(self.path("r.h5"), frames=0,
                     extra={"/fields/stress": stress, "/fields/principal_stress": principal})
        for spec, value in (("stress:xx", 0), ("stress:zz", 2), ("stress:yz", 3), ("stress:xy", 5),
                            ("stress:4", 4), ("principal_stress:1", 3), ("principal_stress:3", -1),
                            ("displacement", 0.01), ("displacement:z", 0.01 * OCTA_VERTICES[:, 2])):
            _, _, frames = render.load_result(self.path("r.h5"), None, spec)
            np.testing.assert_allclose(frames[0].colour, value, err_msg=spec)
        self.assertEqual(frames[0].field, "/fields/displacement:z")
        for spec, pattern in (("stress:zx", r"/fields/stress has 6 columns: no column 'zx' \(a "
                               "number from 0, or xx"),
                              ("principal_stress:0", r"r\.h5: /fields/principal_stress: no column "
                               "'0' \(1, 2 or 3"),
                              ("stress:6", r"no column '6'"),
                              ("displacement:xx", r"has 3 columns: no column 'xx'")):
            with self.assertRaisesRegex(render.RenderError, pattern):
                render.load_result(self.path("r.h5"), None, spec)
        r = self.render("r.h5", "--field", "stress:zz")
        self.assertEqual(r.returncode, 0, describe(r))
        self.assertEqual(self.pictures(), ["fields_stress_zz.png"])

    def test_field_in_frames(self):
        extra = {"/frames/%d/von_mises" % i: np.full(6, float(i)) for i in range(3)}
        extra.update({"/frames/%d/contact/pressure" % i: np.full(6, 2.0 * i) for i in range(3)})
        write_result(self.path("r.h5"), extra=extra)
        sys.path.insert(0, SCRIPTS)
        import render
        _, _, frames = render.load_result(self.path("r.h5"), None, "pressure")
        self.assertEqual([f.field for f in frames], ["/frames/%d/contact/pressure" % i for i in range(3)])
        self.assertEqual(frames[2].colour[0], 4.0)
        r = self.render("r.h5", "--field", "von_mises", "--gif", self.path("a.gif"))
        self.assertEqual(r.returncode, 0, describe(r))
        self.assertEqual(self.pictures(), ["frame_0000.png", "frame_0001.png", "frame_0002.png"])
        self.assertGif(self.path("a.gif"), 3)

    def test_field_errors(self):
        write_result(self.path("r.h5"), frames=0, extra={"/fields/bad": np.ones(4)})
        self.assertFails(self.render("r.h5", "--field", "nope"),
                         r"r\.h5: no dataset /fields/nope or /contact/nope")
        self.assertFails(self.render("r.h5", "--field", "bad"),
                         r"/fields/bad has shape \(4,\), expected \(6,\) or \(6, k\)")
        self.assertFails(self.render("r.h5", "--field", "/no/such"), r"no dataset /no/such")
        write_result(self.path("s.h5"))
        self.assertFails(self.render("s.h5", "--field", "von_mises"),
                         r"no dataset /frames/0/von_mises or /frames/0/contact/von_mises")

    def test_bad_arguments(self):
        write_result(self.path("r.h5"))
        for args, pattern in ((["--frames", "x"], r"--frames: expected 'all'"),
                              (["--size", "800"], r"--size: expected WxH"),
                              (["--view", "1"], r"--view: expected elev,azim"),
                              (["--scale", "-1"], r"--scale: must be > 0")):
            self.assertFails(self.render("r.h5", *args), pattern, status=2)

    def contact_result(self):
        """Three frames of the octahedron touching a table (a 2-triangle patch at z = -1.2) and a
        tool (a triangle) that moves by 0.1 in x per frame; vertex 5 (the bottom) touches."""
        tool = np.array([[0, 0, 1.5], [1, 0, 1.5], [0, 1, 1.5]])
        extra = {"/obstacles/table/vertices": np.array([[-2, -2, -1.2], [2, -2, -1.2], [2, 2, -1.2], [-2, 2, -1.2]]),
                 "/obstacles/table/triangles": np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32),
                 "/obstacles/tool/vertices": tool,
                 "/obstacles/tool/triangles": np.array([[0, 2, 1]], dtype=np.int32)}
        for i in range(3):
            extra["/frames/%d/obstacles/tool/vertices" % i] = tool + [0.1 * i, 0, 0]
            extra["/frames/%d/contact/pressure" % i] = np.array([0, 0, 0, 0, 0, 10.0 * (i + 1)])
        write_result(self.path("c.h5"), extra=extra)
        with h5py.File(self.path("c.h5"), "a") as f:
            f["/obstacles/table"].attrs["shape"] = "plane"
            f["/obstacles/tool"].attrs["shape"] = "mesh"

    def test_obstacles_and_contact_pressure(self):
        # The obstacles are read where each frame places them; the body is coloured by the
        # contact pressure where it touches (the triangles at vertex 5) and neutral elsewhere.
        sys.path.insert(0, SCRIPTS)
        import render
        self.contact_result()
        _, triangles, frames = render.load_result(self.path("c.h5"), None)
        self.assertEqual([shape for _, _, shape in frames[2].obstacles], ["plane", "mesh"])
        np.testing.assert_allclose(frames[2].obstacles[1][0][:, 0], [0.2, 1.2, 0.2])
        np.testing.assert_allclose(frames[0].obstacles[0][0][:, 2], -1.2)
        self.assertEqual(list(frames[1].touching), [False] * 5 + [True])
        self.assertEqual(frames[1].colour[5], 20.0)
        r = self.render("c.h5", "--gif", self.path("c.gif"))
        self.assertEqual(r.returncode, 0, describe(r))
        self.assertEqual(len(self.pictures()), 3)
        self.assertGif(self.path("c.gif"), 3)
        with Image.open(self.path("png", "frame_0002.png")) as image:
            pixels = np.asarray(image.convert("RGB")).reshape(-1, 3).astype(int)
        neutral = np.array([int(255 * c) for c in render.NEUTRAL[:3]])
        self.assertGreater(np.sum(np.all(np.abs(pixels - neutral) <= 3, axis=1)), 1000)  # the body, not touching
        _, _, bare = render.load_result(self.path("c.h5"), None, None, obstacles=False)
        self.assertEqual(bare[0].obstacles, [])
        r = self.render("c.h5", "--no-obstacles", "--field", "displacement")
        self.assertEqual(r.returncode, 0, describe(r))

    def test_obstacles_clipped_to_the_picture(self):
        # A triangle across the box keeps its part inside; one outside is dropped; the limits
        # take the tool in (a mesh) but not the table's patch (a plane).
        sys.path.insert(0, SCRIPTS)
        import render
        lo, hi = np.zeros(3), np.ones(3)
        part = render.clip_polygon(np.array([[-1.0, 0.5, 0.5], [2.0, 0.5, 0.5], [0.5, 2.0, 0.5]]), lo, hi)
        self.assertTrue(np.all(part >= -1e-12) and np.all(part <= 1 + 1e-12))
        self.assertGreaterEqual(len(part), 3)
        self.assertIsNone(render.clip_polygon(np.array([[2.0, 2, 2], [3, 2, 2], [2, 3, 2]]), lo, hi))
        self.contact_result()
        vertices, _, frames = render.load_result(self.path("c.h5"), None)
        lo, hi = render.axis_limits(vertices, frames, 1.0)
        self.assertGreater(hi[2], 1.5)   # the tool at z = 1.5
        self.assertGreater(lo[2], -1.2)  # the table's patch is clipped, not taken in

    def test_the_title_fits_the_picture(self):
        # The README's GIF was 420 x 300 with its title cut off: the title is the figure's and
        # wraps to its width, at the default size and at that small one.
        sys.path.insert(0, SCRIPTS)
        import render
        self.contact_result()
        vertices, triangles, frames = render.load_result(self.path("c.h5"), None)
        frames[0].strategy = "a long strategy name that would not fit a small picture on one line"
        for size in (render.DEFAULT_SIZE, (420, 300)):
            renderer = render.Renderer(vertices, triangles, render.axis_limits(vertices, frames, 1.0),
                                       (0.0, 30.0), (25.0, -60.0), size, "contact pressure")
            try:
                renderer.draw(frames[0], 1.0)
                renderer.figure.canvas.draw()
                box = renderer.figure._suptitle.get_window_extent()
                self.assertGreaterEqual(box.x0, 0, size)
                self.assertLessEqual(box.x1, size[0], size)
                self.assertLessEqual(box.y1, size[1], size)
            finally:
                renderer.close()
        self.assertGreater(render.DEFAULT_SIZE[0], 420)


# ---------------------------------------------------------------------------------------------


def load_problem(path):
    """A problem file whose comments are whole `//` lines (as make_scenes.py writes them)."""
    with open(path) as f:
        text = f.read()
    return text, json.loads("".join(l for l in text.splitlines(True)
                                    if not l.lstrip().startswith("//")))


def msh_vertex_count(path):
    """The node count in a Gmsh 4.1 file's $Nodes header, read independently of the script."""
    with open(path) as f:
        lines = f.read().split("\n")
    return int(lines[lines.index("$Nodes") + 1].split()[1])


class SceneTests(TempDirTest):
    MESH = "cardioid_832.msh"

    def setUp(self):
        super().setUp()
        sys.path.insert(0, SCRIPTS)
        import make_scenes
        self.mesh = make_scenes.read_msh(os.path.join(MESHES, self.MESH))
        self.base = set(self.mesh.region_vertices("base").tolist())

    def make(self, frames, fraction, *extra):
        out = self.path("scene.json")
        r = run_script("make_scenes.py", "--mesh", os.path.join(MESHES, self.MESH), "--frames",
                       str(frames), "--fraction", str(fraction), "--out", out, *extra)
        self.assertEqual(r.returncode, 0, describe(r))
        self.assertRegex(r.stdout, r"%d frames, patch \d+ of %d vertices = [\d.]+ %%"
                         % (frames, len(self.mesh.vertices)))
        return out

    def check_scene(self, path, mesh_file, frames, fraction):
        """Every property of a scene file; returns the patch centres (|u|-weighted)."""
        text, problem = load_problem(path)
        self.assertTrue(text.startswith("//"), "the file opens with a comment")
        self.assertEqual(set(problem), {"mesh", "material", "boundary", "frames", "output"})
        mesh_path = os.path.normpath(os.path.join(os.path.dirname(path), problem["mesh"]))
        self.assertTrue(os.path.samefile(mesh_path, os.path.join(MESHES, mesh_file)))
        self.assertTrue(problem["output"].endswith(".h5"))
        self.assertEqual(problem["boundary"],
                         [{"where": {"region": "base" if "cardioid" in mesh_file else "bottom"},
                           "displacement": [0, 0, 0]}])
        self.assertEqual(len(problem["frames"]), frames)
        nv = msh_vertex_count(mesh_path)
        return [self.check_frame(frame, nv, fraction) for frame in problem["frames"]]

    def check_frame(self, frame, nv, fraction):
        """One frame: one well-formed per-vertex rule; returns its |u|-weighted centre."""
        self.assertEqual(list(frame), ["boundary"])
        self.assertEqual(len(frame["boundary"]), 1)
        rule = frame["boundary"][0]
        self.assertEqual(set(rule), {"where", "displacement"})
        vertices = rule["where"]["vertices"]
        self.assertTrue(all(isinstance(v, int) and 0 <= v < nv for v in vertices))
        self.assertEqual(vertices, sorted(set(vertices)), "ascending, no repeats")
        rows = np.array(rule["displacement"], dtype=float)
        self.assertEqual(rows.shape, (len(vertices), 3))
        self.assertTrue(np.all(np.isfinite(rows)))
        self.assertAlmostEqual(len(vertices) / nv, fraction, delta=0.02)
        weight = np.linalg.norm(rows, axis=1)
        self.assertGreater(weight.max(), 0.0)
        return (weight[:, None] * self.mesh.vertices[vertices]).sum(axis=0) / weight.sum()

    def assertMovesWestward(self, centres):
        steps = [np.linalg.norm(b - a) for a, b in zip(centres, centres[1:])]
        self.assertGreater(min(steps), 0.02, "the patch centre moves every frame")
        azimuth = np.unwrap([math.atan2(c[1], c[0]) for c in centres])
        self.assertTrue(np.all(np.diff(azimuth) < 0), "westward: decreasing azimuth")

    def test_cardioid_scene(self):
        out = self.make(12, 0.2)
        centres = self.check_scene(out, self.MESH, 12, 0.2)
        self.assertMovesWestward(centres)
        _, problem = load_problem(out)
        for frame in problem["frames"]:
            self.assertFalse(self.base & set(frame["boundary"][0]["where"]["vertices"]),
                             "the patch leaves the clamped base alone")

    def test_small_fraction_and_depth(self):
        out = self.make(5, 0.05, "--depth", "0.03", "--turn", "0.25")
        self.check_scene(out, self.MESH, 5, 0.05)
        _, problem = load_problem(out)
        largest = max(np.linalg.norm(np.array(f["boundary"][0]["displacement"]), axis=1).max()
                      for f in problem["frames"])
        size = np.max(np.ptp(self.mesh.vertices, axis=0))
        self.assertAlmostEqual(largest, 0.03 * size, delta=0.1 * 0.03 * size)

    def test_shipped_scenes(self):
        for name, mesh in (("cardioid_moving_contact", "cardioid_832.msh"),
                           ("disk_organ_equator_wave", "disk_organ_4k.msh")):
            path = os.path.join(MESHES, "examples", name + ".json")
            if mesh != self.MESH:
                sys.path.insert(0, SCRIPTS)
                import make_scenes
                self.mesh = make_scenes.read_msh(os.path.join(MESHES, mesh))
            with self.subTest(scene=name):
                self.assertLess(os.path.getsize(path), 600 * 1024)
                self.assertMovesWestward(self.check_scene(path, mesh, 40, 0.2))

    def test_msh22_reader(self):
        # The octahedron in Gmsh 2.2 with node tags 10..15 in reverse order: vertex i is the
        # i-th node by ascending tag; the lower half is "base" (tag 1), the upper "body" (2).
        import make_scenes
        lines = ["$MeshFormat", "2.2 0 8", "$EndMeshFormat", "$PhysicalNames", "2",
                 '2 1 "base"', '2 2 "body"', "$EndPhysicalNames", "$Nodes", "6"]
        lines += ["%d %g %g %g" % ((10 + i,) + tuple(OCTA_VERTICES[i])) for i in range(5, -1, -1)]
        lines += ["$EndNodes", "$Elements", "9", "1 15 2 0 1 10"]  # a point element: ignored
        lines += ["%d 2 2 %d 1 %d %d %d" % ((k + 2, 1 if k >= 4 else 2) + tuple(10 + t))
                  for k, t in enumerate(OCTA_TRIANGLES)]
        lines += ["$EndElements"]
        with open(self.path("octa.msh"), "w") as f:
            f.write("\n".join(lines) + "\n")
        mesh = make_scenes.read_msh(self.path("octa.msh"))
        np.testing.assert_array_equal(mesh.vertices, OCTA_VERTICES)
        np.testing.assert_array_equal(mesh.triangles, OCTA_TRIANGLES)
        self.assertEqual(mesh.region_vertices("base").tolist(), [0, 1, 2, 3, 5])

    def test_errors(self):
        mesh = os.path.join(MESHES, self.MESH)
        out = self.path("x.json")
        for args, pattern in (
                (["--mesh", self.path("absent.msh"), "--out", out], r"\S*absent\.msh: no such file"),
                (["--mesh", mesh, "--out", out, "--clamp", "bsae"],
                 r"no region 'bsae' in the mesh \(known: base, body\)"),
                (["--mesh", mesh, "--out", out, "--height", "5"], r"misses the surface")):
            r = run_script("make_scenes.py", *args)
            self.assertEqual(r.returncode, 1, describe(r))
            self.assertRegex(r.stderr, r"^make_scenes\.py: error: .*" + pattern)
            self.assertFalse(os.path.exists(out))
        for args, pattern in ((["--mesh", mesh, "--fraction", "1.5", "--out", out],
                               r"--fraction: must be in"),
                              (["--mesh", mesh, "--nu", "0.5", "--out", out], r"--nu: must be in"),
                              (["--frames", "3"], r"--frames: only with --mesh"),
                              (["--mesh", mesh], r"--mesh and --out go together")):
            r = run_script("make_scenes.py", *args)
            self.assertEqual(r.returncode, 2, describe(r))
            self.assertRegex(r.stderr, pattern)
            self.assertFalse(os.path.exists(out))


def main():
    global SCRIPTS, MESHES
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scripts", default=SCRIPTS, help="the repository's scripts/ directory")
    parser.add_argument("--meshes", default=MESHES, help="the repository's meshes/ directory")
    args, rest = parser.parse_known_args()
    SCRIPTS, MESHES = os.path.abspath(args.scripts), os.path.abspath(args.meshes)
    unittest.main(argv=[sys.argv[0]] + rest, verbosity=1)


if __name__ == "__main__":
    main()
