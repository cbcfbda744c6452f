#!/usr/bin/python3
"""Command-line tests of contact problems (a problem file with "contact"; docs/contact.md).

Usage:
    /usr/bin/python3 test_contact_cli.py --driver PATH/hssbem --meshes REPO/meshes [--mpiexec mpiexec]
                                         [unittest arguments, e.g. ContactErrorTests]

The harness (a temporary directory per case, the clean-failure assertions) is test_cli.py's.
ContactErrorTests: every bad contact input ends with one "hssbem: error:" line naming the
problem and leaves no file. ContactRunTests: the result layout (/contact, the frames' contact,
the sidecar's pressure, the bodies' forces), a contact scene's frames against static runs of the
same obstacle positions, and the same file from 1 and 2 ranks.
"""

import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_cli  # noqa: E402
from test_cli import CliTestCase, TIMEOUT_RUN, off_text  # noqa: E402

NAN = None  # JSON null: a component left as it was

TABLE = {"name": "table", "plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}}


class ContactCase(CliTestCase):
    def cube_contact(self, contact, boundary=None, frames=None, name="problem.json", **extra):
        """The shipped cube pushed down at its top, rollers on x0 and y0, over `contact`."""
        if boundary is None:
            boundary = [{"where": {"region": "z1"}, "displacement": [NAN, NAN, -0.01]},
                        {"where": {"region": "x0"}, "displacement": [0, NAN, NAN]},
                        {"where": {"region": "y0"}, "displacement": [NAN, 0, NAN]}]
        if frames is not None:
            extra["frames"] = frames
        return self.problem(mesh=self.copy_mesh("cube_l0.msh"), boundary=boundary, contact=contact, name=name,
                            **extra)


class ContactErrorTests(ContactCase):
    def test_frame_names_an_unknown_obstacle(self):
        self.cube_contact({"obstacles": [TABLE]}, frames=[{"obstacles": {"table": {"translate": [0, 0, 0]}}},
                                                          {"obstacles": {"tool": {"translate": [0, 0, 1]}}}])
        r = self.run_problem()
        self.assertFailsCleanly(r, r"problem\.json: frames\[1\]\.obstacles: no obstacle named 'tool' \(known: table\)")
        self.assertErrorLine(r)

    def test_zero_rotation_axis(self):
        self.cube_contact({"obstacles": [TABLE]}, frames=[{"obstacles": {"table": {"rotate": {"axis": [0, 0, 0], "angle": 5}}}}])
        r = self.run_problem()
        self.assertFailsCleanly(r, r"problem\.json: frames\[0\]\.obstacles\.table\.rotate\.axis: the rotation axis is zero")
        self.assertErrorLine(r)

    def test_duplicate_obstacle_name(self):
        self.cube_contact({"obstacles": [TABLE, TABLE]})
        self.assertFailsCleanly(self.run_problem(), r"contact\.obstacles\[1\]\.name: duplicate obstacle name 'table'")

    def test_zero_normal(self):
        self.cube_contact({"obstacles": [{"name": "t", "plane": {"point": [0, 0, 0], "normal": [0, 0, 0]}}]})
        self.assertFailsCleanly(self.run_problem(), r"contact\.obstacles\[0\]\.plane\.normal: the normal is zero")

    def test_negative_friction(self):
        self.cube_contact({"obstacles": [TABLE], "friction": -0.2})
        self.assertFailsCleanly(self.run_problem(), r"contact\.friction: the friction coefficient must be >= 0")

    def test_negative_obstacle_friction(self):
        self.cube_contact({"obstacles": [dict(TABLE, friction=-1)]})
        self.assertFailsCleanly(self.run_problem(), r"contact\.obstacles\[0\]\.friction: the friction coefficient must be >= 0")

    def test_radius_not_positive(self):
        self.cube_contact({"obstacles": [{"name": "tool", "sphere": {"center": [0, 0, 2], "radius": 0}}]})
        self.assertFailsCleanly(self.run_problem(), r"contact\.obstacles\[0\]\.sphere\.radius: the radius must be > 0")

    def test_obstacle_mesh_cannot_be_read(self):
        self.cube_contact({"obstacles": [{"name": "wall", "mesh": "no_such_wall.off"}]})
        self.assertFailsCleanly(self.run_problem(), r"problem\.json: contact\.obstacles\[0\]\.mesh: cannot open mesh file .*no_such_wall\.off")

    def test_obstacle_mesh_with_a_degenerate_triangle(self):
        self.write("wall.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n2 0 0\n3 0 1 2\n")
        self.cube_contact({"obstacles": [{"name": "wall", "mesh": "wall.off"}]})
        self.assertFailsCleanly(self.run_problem(), r"contact\.obstacles\[0\].*wall\.off.*degenerate")

    def test_a_body_that_would_fly_away(self):
        # Pressed onto a frictionless table by a load that also pulls it sideways: nothing it
        # touches resists the pull. One line naming the body and the force, on 1 and 2 ranks.
        self.cube_contact({"obstacles": [TABLE]}, boundary=[{"where": {"region": "z1"}, "traction": [1, 0, -10]}])
        self.fails_on_one_and_two_ranks(r"hssbem: error: contact: frame 0: body 0 \(the surface of vertex \d+\) would fly away: "
                                        r"nothing it touches balances the force \(1, 0, 0\)")

    def test_a_body_pulled_off_the_table(self):
        # A load that lifts the cube off the table: no contact point closes along it.
        self.cube_contact({"obstacles": [TABLE]}, boundary=[{"where": {"region": "z1"}, "traction": [0, 0, 1]}])
        self.fails_on_one_and_two_ranks(r"contact: frame 0: body 0 .*would fly away: nothing it touches balances the force \(0, 0, 1\)")

    def test_compressed_operator_refused(self):
        self.cube_contact({"obstacles": [TABLE]})
        self.assertFailsCleanly(self.run_problem("problem.json", "-bem_mat_type", "hss"),
                                r"contact runs on the dense or the H2 reference factorization")

    def test_frame_that_changes_the_pattern(self):
        self.cube_contact({"obstacles": [TABLE]},
                          frames=[{"boundary": [{"where": {"region": "x1"}, "displacement": [0, 0, 0]}]}])
        self.assertFailsCleanly(self.run_problem(), r"frames\[0\]\.boundary: a contact scene's frames may change the values")

    def test_bad_contact_option(self):
        self.cube_contact({"obstacles": [TABLE]})
        self.assertFailsCleanly(self.run_problem("problem.json", "-contact_tol", "2"), r"-contact_tol must lie in \(0, 1\)")

    def fails_on_one_and_two_ranks(self, *patterns):
        for np_ in (1, 2):
            r = self.run_problem(np=np_)
            self.assertFailsCleanly(r, *patterns)
            self.assertEqual(len(re.findall(r"hssbem: error: ", r.output)), 1, "one error line\n" + r.describe())

    def test_obstacle_named_like_a_bodys_force(self):
        # With "bodies", /contact/forces/body_<k> is body k's: an obstacle of that name used to
        # lose its force there. Refused while the file is read.
        self.cube_contact({"bodies": True, "obstacles": [dict(TABLE, name="body_0")]})
        self.fails_on_one_and_two_ranks(r"problem\.json: contact\.obstacles\[0\]\.name: the name 'body_0' is that of a body's force in the result")

    def test_obstacle_name_that_cannot_name_a_dataset(self):
        # Used to be refused only when the result was written, after the whole solve.
        self.cube_contact({"obstacles": [dict(TABLE, name="tool/tip")]})
        self.fails_on_one_and_two_ranks(r"problem\.json: contact\.obstacles\[0\]\.name: the name \"tool/tip\" cannot name the result's datasets .*it holds '/'")

    def test_obstacle_mesh_facing_away(self):
        # A plate 0.01 under the cube whose triangles face down, away from it: refused (not
        # flipped: which side of a sheet is solid is the file's to say).
        self.write("wall.off", off_text([(-1, -1, -0.01), (2, -1, -0.01), (2, 2, -0.01), (-1, 2, -0.01)], [(0, 2, 1), (0, 3, 2)]))
        self.cube_contact({"obstacles": [{"name": "wall", "mesh": "wall.off"}]})
        self.fails_on_one_and_two_ranks(r"problem\.json: contact\.obstacles\[0\] \(.*wall\.off\): obstacle 'wall': its triangles face away from the bodies "
                                        r"\(25 of the 25 body vertices within reach of its faces face their back\).*reverse the vertex order")

    def test_obstacle_mesh_inconsistently_oriented(self):
        self.write("wall.off", off_text([(-1, -1, -0.01), (2, -1, -0.01), (2, 2, -0.01), (-1, 2, -0.01)], [(0, 1, 2), (0, 3, 2)]))
        self.cube_contact({"obstacles": [{"name": "wall", "mesh": "wall.off"}]})
        self.assertFailsCleanly(self.run_problem(), r"contact\.obstacles\[0\].*wall\.off.*inconsistent orientation: triangles 0 and 1")

    def test_too_few_iterations(self):
        # The cube on the table takes two active-set iterations (the bottom edges' side nodes let go).
        self.cube_contact({"obstacles": [TABLE]})
        r = self.run_problem("problem.json", "-contact_max_it", "1")
        self.assertFailsCleanly(r, r"the active set did not settle in 1 iterations \(-contact_max_it\)")
        self.assertErrorLine(r)

    def test_a_frame_that_does_not_converge_on_one_and_two_ranks(self):
        # Friction's Newton stopped after one iteration (the cube pushed sideways on a rough
        # table): one line naming the frame and the residual, on 1 and 2 ranks, no file.
        top = [{"where": {"region": "z1"}, "displacement": [0.05, 0, -0.01]}]
        self.cube_contact({"obstacles": [TABLE], "friction": 0.3}, boundary=top)
        for np_ in (1, 2):
            r = self.run_driver("-problem", "problem.json", "-o", self.out, "-contact_max_it", "1", np=np_)
            self.assertFailsCleanly(r, r"hssbem: error: contact: frame 0: friction did not converge in 1 Newton iterations "
                                       r"\(-contact_max_it\): residual \d\.\d+e[-+]\d+ of the traction scale")
            self.assertEqual(r.output.count("hssbem: error:"), 1, r.describe())


class ContactRunTests(ContactCase):
    def read(self, name):
        import h5py
        data = test_cli.datasets(self.path(name))
        with h5py.File(self.path(name), "r") as f:
            attrs = {k: f.attrs[k] for k in f.attrs}
            contact = {k: f["/contact"].attrs[k] for k in f["/contact"].attrs} if "contact" in f else {}
        return data, attrs, contact

    def test_single_solve_layout_and_monitor(self):
        import numpy as np
        self.cube_contact({"obstacles": [TABLE]})
        r = self.run_problem("problem.json", "-contact_monitor", timeout=TIMEOUT_RUN)
        self.assertSucceeds(r, self.out, self.path("out.xdmf"))
        self.assertRegex(r.stdout, r"contact: frame 0 iteration 1: \d+ touching")
        data, attrs, contact = self.read("out.h5")
        p, status, gap = data["contact/pressure"], data["contact/status"], data["contact/gap"]
        x = data["mesh/vertices"]
        bottom = np.abs(x[:, 2]) < 1e-12
        self.assertEqual(int(contact["active_vertices"]), int(bottom.sum()))
        self.assertGreaterEqual(int(contact["iterations"]), 1)
        self.assertLess(np.max(np.abs(p[bottom] - 10.0)), 1e-3)  # E delta = 1000 * 0.01
        self.assertTrue(np.all(p[~bottom] == 0) and np.all(status[bottom] == 2) and np.all(status[~bottom] == 0))
        self.assertTrue(np.all(np.isnan(gap[x[:, 2] > 0.5])))
        self.assertLess(np.max(np.abs(data["contact/forces/table"] - [0, 0, 10.0])), 1e-3)
        self.assertEqual(attrs["solver"], "contact")
        with open(self.path("out.xdmf")) as f:
            xdmf = f.read()
        self.assertIn("/contact/pressure", xdmf)
        self.assertIn("/contact/status", xdmf)

    def test_h2_reference(self):
        # The cube on the table on the H² path: the same uniform pressure E delta as the dense
        # reference, after corrections by accurate H² solves.
        import numpy as np
        self.cube_contact({"obstacles": [TABLE]})
        r = self.run_problem("problem.json", "-bem_mat_type", "h2", timeout=TIMEOUT_RUN)
        self.assertSucceeds(r, self.out)
        self.assertRegex(r.stdout, r"on the H2 reference factorization")
        self.assertRegex(r.stdout, r"contact: [1-9]\d* corrections by accurate H2 solves")
        data, attrs, contact = self.read("out.h5")
        bottom = np.abs(data["mesh/vertices"][:, 2]) < 1e-12
        self.assertLess(np.max(np.abs(data["contact/pressure"][bottom] - 10.0)), 2e-3)  # measured 7.1e-4
        self.assertLess(np.max(np.abs(data["contact/forces/table"] - [0, 0, 10.0])), 2e-4)  # measured 3.9e-5
        self.assertEqual(attrs["mat_type"], "h2")

    def test_stress_on_the_surface_and_inside(self):
        # The cube pressed onto the table is in uniaxial stress: sigma_zz = -E delta = -10 and
        # nothing else, on the surface (face vertices), at interior points and on a grid; a
        # contact run writes them as any other run does.
        import numpy as np
        self.cube_contact({"obstacles": [TABLE]},
                          interior_points={"points": [[0.5, 0.5, 0.5], [0.3, 0.6, 0.02]],
                                           "grid": {"box": [[0.1, 0.1, 0.1], [0.9, 0.9, 0.9]], "cells": [2, 2, 2]}})
        self.assertSucceeds(self.run_problem("problem.json", timeout=TIMEOUT_RUN), self.out)
        data, _, _ = self.read("out.h5")
        exact = np.array([0, 0, -10.0, 0, 0, 0])
        x = data["mesh/vertices"]
        on_face = ((np.abs(x) < 1e-9) | (np.abs(x - 1) < 1e-9)).sum(axis=1) == 1
        self.assertGreater(on_face.sum(), 40)
        self.assertLess(np.max(np.abs(data["fields/stress"][on_face] - exact)), 1e-3)  # measured 2.0e-4
        self.assertLess(np.max(np.abs(data["fields/von_mises"][on_face] - 10.0)), 1e-3)
        self.assertEqual(data["interior/stress"].shape, (2, 6))
        self.assertLess(np.max(np.abs(data["interior/stress"] - exact)), 1.5e-4)  # measured 4.6e-5
        self.assertTrue(np.all(data["interior/grid/inside"]))
        self.assertLess(np.max(np.abs(data["interior/grid/stress"] - exact)), 3.5e-4)  # measured 1.2e-4

    def test_interior_stress_of_a_pressed_face_under_a_tool(self):
        # A pressure on the top face and a tool (sphere) pressed into it: at the pressure-loaded
        # nodes the interior evaluation takes the pressure on each face plus the node's contact
        # traction. The same problem with the pressure given as the traction [0, 0, -p] (the top
        # is flat: the same loads) is an independent path (no pressure nodes): the interior
        # stress must agree to round-off; without the tool it differs by the tool's share.
        import h5py
        import numpy as np
        points = [[0.5, 0.5, 0.75], [0.42, 0.55, 0.9], [0.6, 0.45, 0.95], [0.3, 0.3, 0.5]]
        tool = {"name": "tool", "sphere": {"center": [0.5, 0.5, 1.28], "radius": 0.3}}
        cases = {"pressure": ({"pressure": 1.0}, [tool]), "traction": ({"traction": [0, 0, -1.0]}, [tool]),
                 "no_tool": ({"pressure": 1.0}, [])}
        stress = {}
        for name, (load, obstacles) in cases.items():
            boundary = [{"where": {"region": "z0"}, "displacement": [0, 0, 0]}, dict({"where": {"region": "z1"}}, **load)]
            self.cube_contact({"obstacles": obstacles}, boundary=boundary, name=name + ".json",
                              interior_points={"points": points})
            out = self.path(name + ".h5")
            self.assertSucceeds(self.run_driver("-problem", name + ".json", "-o", out, timeout=TIMEOUT_RUN), out)
            with h5py.File(out, "r") as f:
                stress[name] = f["/interior/stress"][()]
                if obstacles:
                    self.assertLess(f["/contact/forces/tool"][()][2], -1.0)  # the tool presses down (measured -5.9)
        scale = np.max(np.abs(stress["traction"]))
        tool_share = np.max(np.abs(stress["traction"] - stress["no_tool"]))
        self.assertGreater(tool_share, 0.3 * scale)  # the tool matters here (measured 0.97 of the largest)
        # measured 0 (the same loads; before the fix, 0.12 of the largest: the tool's share dropped)
        self.assertLess(np.max(np.abs(stress["pressure"] - stress["traction"])), 1e-9 * scale)

    def test_a_cube_held_by_the_table_alone_on_one_and_two_ranks(self):
        # The cube with nothing prescribed, pressed onto a frictionless table by a load of 10 on
        # its top (unit area): the table carries the load, the cube is in uniaxial compression
        # (sigma_zz = -10) and its surface moves down on average by E eps / 2 = 0.005 (its
        # centroid; eps = 10 / E). The same file from 1 and 2 ranks.
        import h5py
        import numpy as np
        self.cube_contact({"obstacles": [TABLE]}, boundary=[{"where": {"region": "z1"}, "traction": [0, 0, -10]}])
        results = []
        for np_ in (1, 2):
            r = self.run_problem(np=np_, timeout=TIMEOUT_RUN)
            self.assertSucceeds(r, self.out)
            with h5py.File(self.out, "r") as f:
                results.append({k: f["/contact/" + k][()] for k in ("forces/table", "bodies/0/translation", "bodies/0/rotation")})
                stress = f["/fields/stress"][()]
                x = f["/mesh/vertices"][()]
        for k in results[0]:
            self.assertTrue(np.allclose(results[0][k], results[1][k], rtol=1e-12, atol=1e-15), k)
        res = results[0]
        self.assertLess(np.max(np.abs(res["forces/table"] - [0, 0, 10])), 1e-6 * 10)  # measured 0
        self.assertLess(abs(res["bodies/0/translation"][2] + 0.005), 1e-2 * 0.005)
        inside_faces = ((np.abs(x) < 1e-9) | (np.abs(x - 1) < 1e-9)).sum(axis=1) == 1
        self.assertLess(np.max(np.abs(stress[inside_faces] - [0, 0, -10, 0, 0, 0])), 1e-2 * 10)

    def test_a_cube_resting_on_the_table_under_gravity(self):
        # Nothing prescribed, density 2 and gravity 5 down: the cube rests on a frictionless table,
        # which carries its weight rho g V = 10 (the balance takes the exact weight; the lumped
        # particular traction would leave a lateral force of 1e-4 that no frictionless table
        # balances). The pressure is not uniform: the table holds the base flat, where the free
        # column's base would bulge by Poisson's ratio.
        import h5py
        import numpy as np
        self.problem(mesh=self.copy_mesh("cube_l0.msh"), material={"E": 1000.0, "nu": 0.3, "density": 2.0}, boundary=[],
                     gravity=[0, 0, -5], contact={"obstacles": [TABLE]})
        r = self.run_problem(timeout=TIMEOUT_RUN)
        self.assertSucceeds(r, self.out)
        with h5py.File(self.out, "r") as f:
            F = f["/contact/forces/table"][()]
            p = f["/contact/pressure"][()]
            x = f["/mesh/vertices"][()]
        self.assertLess(np.max(np.abs(F - [0, 0, 10])), 1e-6 * 10)
        base = np.abs(x[:, 2]) < 1e-12
        self.assertTrue(np.all(p[base] > 5) and np.all(p[~base] == 0))  # the whole base touches, nothing else

    def test_scene_frames_equal_static_runs(self):
        # The table rises under the cube frame by frame; each frictionless frame is the static
        # problem with the table at that frame's place (its own run, -bem_mat_type dense).
        import h5py
        import numpy as np
        rises = [0.0, 0.004, 0.008, 0.002]
        self.cube_contact({"obstacles": [dict(TABLE, plane={"point": [0, 0, -0.005], "normal": [0, 0, 1]})]},
                          frames=[{"obstacles": {"table": {"translate": [0, 0, z]}}} for z in rises], name="scene.json")
        r = self.run_driver("-problem", "scene.json", "-o", self.out, timeout=TIMEOUT_RUN)
        self.assertSucceeds(r, self.out)
        with h5py.File(self.out, "r") as f:
            self.assertEqual(int(f.attrs["num_frames"]), len(rises))
            frames = [(f["/frames/%d/displacement" % i][()], f["/frames/%d/contact/pressure" % i][()]) for i in range(len(rises))]
            self.assertIn("/frames/%d/stress" % (len(rises) - 1), f)
        with open(self.path("out.xdmf")) as f:
            self.assertIn("/frames/3/contact/pressure", f.read())
        for i, z in enumerate(rises):
            self.cube_contact({"obstacles": [dict(TABLE, plane={"point": [0, 0, -0.005 + z], "normal": [0, 0, 1]})]},
                              name="static%d.json" % i)
            out = self.path("static%d.h5" % i)
            r = self.run_driver("-problem", "static%d.json" % i, "-o", out, "-bem_mat_type", "dense", timeout=TIMEOUT_RUN)
            self.assertSucceeds(r, out)
            with h5py.File(out, "r") as f:
                u, p = f["/fields/displacement"][()], f["/contact/pressure"][()]
            self.assertLess(np.max(np.abs(frames[i][0] - u)), 1e-6 * np.max(np.abs(u)), "frame %d" % i)
            self.assertLess(np.max(np.abs(frames[i][1] - p)), 1e-6 * max(np.max(p), 1e-12), "frame %d" % i)
        self.assertGreater(np.max(frames[2][1]), np.max(frames[0][1]))  # the higher table presses harder

    def test_a_turned_obstacle_equals_the_obstacle_given_at_the_turned_place(self):
        # A frame's "rotate" (and "translate") of a plane, a sphere and a mesh obstacle, against
        # a single solve with the obstacle described at the turned place: x -> R (x - c) + c + t,
        # c = "about" or the default centre (the plane's point, the mesh's centroid).
        import h5py
        import numpy as np
        from test_cli import off_text

        def turn(axis, deg):
            k = np.array(axis, float) / np.linalg.norm(axis)
            K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
            a = np.radians(deg)
            return np.eye(3) + np.sin(a) * K + (1 - np.cos(a)) * K @ K

        wall = [(-1, -1, 0), (2, -1, 0), (2, 2, 0), (-1, 2, 0)]
        self.write("wall.off", off_text(wall, [(0, 1, 2), (0, 2, 3)]))
        R, t = turn([1, 0.2, 0], 0.3), np.array([0, 0, 0.002])
        centroid = np.mean(np.array(wall, float), axis=0)
        self.write("wall_turned.off", off_text([tuple(R @ (np.array(v) - centroid) + centroid + t) for v in wall], [(0, 1, 2), (0, 2, 3)]))
        clamped = [{"where": {"region": "z0"}, "displacement": [0, 0, 0]}]
        Rs, about = turn([0, 1, 0], 1.0), np.array([0.5, 0.5, 0.5])
        centre = np.array([0.5, 0.5, 1.95])
        cases = {
            "plane": (None, dict(TABLE), {"translate": list(t), "rotate": {"axis": [1, 0.2, 0], "angle": 0.3}},
                      dict(TABLE, plane={"point": list(t), "normal": list(R @ [0, 0, 1])})),
            "sphere": (clamped, {"name": "table", "sphere": {"center": list(centre), "radius": 1.0}},
                       {"rotate": {"axis": [0, 1, 0], "angle": 1.0, "about": list(about)}},
                       {"name": "table", "sphere": {"center": list(Rs @ (centre - about) + about), "radius": 1.0}}),
            "mesh": (None, {"name": "table", "mesh": "wall.off"}, {"translate": list(t), "rotate": {"axis": [1, 0.2, 0], "angle": 0.3}},
                     {"name": "table", "mesh": "wall_turned.off"}),
        }
        for name, (boundary, base, place, turned) in cases.items():
            self.cube_contact({"obstacles": [base]}, boundary=boundary, frames=[{"obstacles": {"table": place}}], name=name + "_scene.json")
            self.cube_contact({"obstacles": [turned]}, boundary=boundary, name=name + "_static.json")
            for run in ("scene", "static"):
                out = self.path("%s_%s.h5" % (name, run))
                self.assertSucceeds(self.run_driver("-problem", "%s_%s.json" % (name, run), "-o", out, timeout=TIMEOUT_RUN), out)
            with h5py.File(self.path(name + "_scene.h5"), "r") as f:
                u, p = f["/frames/0/displacement"][()], f["/frames/0/contact/pressure"][()]
            with h5py.File(self.path(name + "_static.h5"), "r") as f:
                ur, pr = f["/fields/displacement"][()], f["/contact/pressure"][()]
            self.assertGreaterEqual(np.count_nonzero(pr), 3, name)  # a real contact (measured 25, 3, 25 vertices)
            self.assertLess(np.max(np.abs(u - ur)), 1e-9 * np.max(np.abs(ur)), name)  # measured 4.7e-15 at most (pressure 6.0e-15)
            self.assertLess(np.max(np.abs(p - pr)), 1e-9 * np.max(pr), name)

    def test_two_bodies_forces(self):
        self.check_two_bodies()

    def test_two_bodies_on_h2(self):
        # The same on an H2 reference per body (a composite reference: no integral across the
        # bodies), corrected by accurate solves to the dense answer.
        self.check_two_bodies("-bem_mat_type", "h2", mat_type="h2")

    def check_two_bodies(self, *args, mat_type="dense"):
        # Two unit cubes (12 triangles each), the upper g above the lower, pushed together by
        # delta at the top: each side of the contact carries E (delta - g) / 2 (the engine's
        # test measures the same on finer cubes, tests/verification/test_contact.cpp).
        import numpy as np
        from test_cli import CUBE_TRIANGLES, CUBE_VERTICES, off_text
        g, delta = 0.001, 0.01
        upper = [(x, y, z + 1 + g) for x, y, z in CUBE_VERTICES]
        tris = CUBE_TRIANGLES + [tuple(i + 8 for i in t) for t in CUBE_TRIANGLES]
        self.write("two.off", off_text(CUBE_VERTICES + upper, tris))
        box = lambda lo, hi: {"box": [lo, hi]}  # noqa: E731
        boundary = [{"where": box([-1, -1, -1e-9], [2, 2, 1e-9]), "displacement": [NAN, NAN, 0]},
                    {"where": box([-1, -1, 2 + g - 1e-9], [2, 2, 3]), "displacement": [NAN, NAN, -delta]},
                    {"where": box([-1e-9, -1, -1], [1e-9, 2, 3]), "displacement": [0, NAN, NAN]},
                    {"where": box([-1, -1e-9, -1], [2, 1e-9, 3]), "displacement": [NAN, 0, NAN]}]
        self.problem(mesh="two.off", boundary=boundary, contact={"bodies": True})
        r = self.run_problem("problem.json", *args, timeout=TIMEOUT_RUN)
        self.assertSucceeds(r, self.out)
        data, attrs, contact = self.read("out.h5")
        f0, f1 = data["contact/forces/body_0"], data["contact/forces/body_1"]
        load = 0.5 * 1000.0 * (delta - g)
        p = data["contact/pressure"]
        self.assertLess(np.max(np.abs(f0 + f1)), 1e-9 * load)
        self.assertLess(np.max(np.abs(f1 - [0, 0, load])), 5e-5 * load)  # measured 1.2e-5
        self.assertTrue(np.all(data["contact/status"][4:12] == 2) and np.all(p[4:12] > 0.5 * load))
        self.assertEqual(attrs["solver"], "contact")
        self.assertEqual(attrs["mat_type"], mat_type)
        self.assertGreaterEqual(int(contact["iterations"]), 1)

    def test_obstacles_in_the_result_and_the_sidecar(self):
        # The table's patch, the tool's sphere and a wall mesh are written per frame, placed as the
        # frame places them; the sidecar shows them beside the body and stays readable by meshio
        # (which takes the last temporal collection: the body's).
        import h5py
        import meshio
        import numpy as np
        self.write("wall.off", off_text([(1.02, -1, -1), (1.02, 2, -1), (1.02, 2, 2), (1.02, -1, 2)], [(0, 2, 1), (0, 3, 2)]))  # facing -x, the cube
        tool = {"name": "tool", "sphere": {"center": [0.5, 0.5, 1.35], "radius": 0.3}}
        moves = [[0, 0, -0.06], [0.1, 0, -0.06]]
        self.cube_contact({"obstacles": [TABLE, tool, {"name": "wall", "mesh": "wall.off"}]},
                          boundary=[{"where": {"region": "z0"}, "displacement": [0, 0, 0]}],
                          frames=[{"obstacles": {"tool": {"translate": m}}} for m in moves])
        r = self.run_problem(timeout=TIMEOUT_RUN)
        self.assertSucceeds(r, self.out)
        with h5py.File(self.out, "r") as f:
            self.assertEqual(sorted(f["/obstacles"]), ["table", "tool", "wall"])
            self.assertEqual(f["/obstacles/tool"].attrs["shape"], "sphere")
            table, sphere = f["/obstacles/table/vertices"][()], f["/obstacles/tool/vertices"][()]
            self.assertLess(np.max(np.abs(table[:, 2])), 1e-12)  # in the plane
            self.assertLess(np.max(np.abs(table[:, :2].mean(axis=0) - 0.5)), 1e-12)  # under the cube
            self.assertLess(np.max(np.abs(np.linalg.norm(sphere - [0.5, 0.5, 1.35], axis=1) - 0.3)), 1e-12)
            self.assertEqual(f["/obstacles/wall/triangles"].shape, (2, 3))
            for i, m in enumerate(moves):
                np.testing.assert_allclose(f["/frames/%d/obstacles/tool/vertices" % i][()], sphere + m, atol=1e-15)
                np.testing.assert_array_equal(f["/frames/%d/obstacles/table/vertices" % i][()], table)
            self.assertGreater(np.max(f["/frames/0/contact/pressure"][()]), 0)
        with open(self.path("out.xdmf")) as f:
            xdmf = f.read()
        self.assertIn('<Grid Name="obstacle tool" GridType="Collection" CollectionType="Temporal">', xdmf)
        self.assertIn("out.h5:/frames/1/obstacles/tool/vertices", xdmf)
        with meshio.xdmf.TimeSeriesReader(self.path("out.xdmf")) as reader:
            points, cells = reader.read_points_cells()
            self.assertEqual(points.shape, (98, 3))
            self.assertEqual(reader.num_steps, 2)
            t, point_data, _ = reader.read_data(1)
            self.assertEqual(t, 1.0)
            self.assertEqual(point_data["pressure"].shape, (98,))
            self.assertEqual(point_data["stress"].shape, (98, 6))

    def test_a_plate_the_cube_lies_behind_is_noted_once(self):
        # A plate over the cube facing up, away from it: every candidate lies behind it deeper than
        # the depth (the reach: 0.087). Not in contact with it, and said once, not per frame.
        import h5py
        import numpy as np
        self.write("plate.off", off_text([(-1, -1, 1.2), (2, -1, 1.2), (2, 2, 1.2), (-1, 2, 1.2)], [(0, 1, 2), (0, 2, 3)]))
        self.cube_contact({"obstacles": [{"name": "plate", "mesh": "plate.off"}]},
                          frames=[{"obstacles": {"plate": {"translate": [0, 0, -0.01 * k]}}} for k in range(3)])
        r = self.run_problem(timeout=TIMEOUT_RUN)
        self.assertSucceeds(r, self.out)
        notes = re.findall(r"hssbem: contact: note: frame (\d+) starts with (\d+) vertices deeper than 0\.0866 \(-contact_depth\) behind obstacle 'plate': "
                           r"not in contact with it", r.stdout)
        self.assertEqual(notes, [("0", "97")], r.describe())  # every candidate: all but the corner held in x, y and z
        with h5py.File(self.out, "r") as f:
            self.assertTrue(all(np.all(f["/frames/%d/contact/pressure" % i][()] == 0) for i in range(3)))

    def test_same_file_from_one_and_two_ranks(self):
        import numpy as np
        self.cube_contact({"obstacles": [TABLE], "friction": 0.5})
        for np_ in (1, 2):
            r = self.run_driver("-problem", "problem.json", "-o", self.path("r%d.h5" % np_), np=np_, timeout=TIMEOUT_RUN)
            self.assertSucceeds(r, self.path("r%d.h5" % np_))
        a, attrs_a, ca = self.read("r1.h5")
        b, attrs_b, cb = self.read("r2.h5")
        self.assertEqual(sorted(a), sorted(b))
        self.assertIn("contact/forces/table", a)
        for name in a:
            self.assertTrue(np.array_equal(a[name], b[name], equal_nan=True), name)
        self.assertEqual(ca, cb)
        self.assertEqual((int(attrs_a["ranks"]), int(attrs_b["ranks"])), (1, 2))


def main():
    test_cli.run_suite(__doc__)


if __name__ == "__main__":
    main()
