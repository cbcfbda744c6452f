#!/usr/bin/python3
"""Command-line tests of the stress output: surface stress fields, interior points and grids
(masked outside the body, their XDMF view), malformed grids, ranks, and stress per frame.

Usage:
    /usr/bin/python3 test_stress_cli.py --driver PATH/hssbem --meshes REPO/meshes [--mpiexec mpiexec]
                                        [unittest arguments]

Built on test_cli.py's helpers (a fresh temporary directory per test, clean-failure checks).
The cube in uniaxial tension (cube_l0, rollers on z = 0, traction 10 on z = 1) has the exact
solution sigma = diag(0, 0, 10), u = (10 / E) (-nu x, -nu y, z), which every output must give.
"""

import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import test_cli as base  # noqa: E402

E, NU, S0 = 1000.0, 0.3, 10.0
ROLLERS = [{"where": {"region": "z0"}, "displacement": [None, None, 0]},
           {"where": {"vertices": [0]}, "displacement": [0, 0, 0]},
           {"where": {"vertices": [73]}, "displacement": [None, 0, None]}]


def tension(s0=S0):
    return ROLLERS + [{"where": {"region": "z1"}, "traction": [0, 0, s0]}]


class StressTests(base.CliTestCase):
    GRID = {"box": [[-0.1, -0.1, -0.1], [1.1, 1.1, 1.1]], "cells": [6, 6, 6]}
    POINTS = [[0.5, 0.5, 0.5], [0.5, 0.5, 0.99], [0.2, 0.7, 0.01]]

    def read(self, name):
        import h5py
        data = base.datasets(self.path(name))
        with h5py.File(self.path(name), "r") as f:
            data["grid_attrs"] = dict(f["/interior/grid"].attrs) if "/interior/grid" in f else {}
        return data

    def test_cube_surface_points_and_grid(self):
        import numpy as np
        self.cube_l0_problem(tension(), interior_points={"points": self.POINTS, "grid": self.GRID})
        r = self.run_problem(timeout=base.TIMEOUT_RUN)
        self.assertSucceeds(r, self.out, self.path("out.xdmf"))
        d = self.read("out.h5")
        exact = np.array([0, 0, S0, 0, 0, 0])
        nv = d["mesh/vertices"].shape[0]
        self.assertEqual(d["fields/stress"].shape, (nv, 6))
        self.assertEqual(d["fields/stress_corner"].shape, (d["mesh/triangles"].shape[0], 3, 6))
        # Exact at every vertex (measured 2.3e-5 of S0), edges and corners included.
        self.assertLess(np.abs(d["fields/stress"] - exact).max(), 1e-4 * S0)
        np.testing.assert_allclose(d["fields/von_mises"], S0, atol=1e-4 * S0)
        np.testing.assert_allclose(d["fields/principal_stress"], np.tile([S0, 0, 0], (nv, 1)), atol=1e-4 * S0)
        # Interior points: the centre, 0.01 below the loaded face, 0.01 above the rollers.
        self.assertEqual(d["interior/stress"].shape, (3, 6))
        self.assertLess(np.abs(d["interior/stress"] - exact).max(), 1e-4 * S0)  # measured 2e-6 of S0
        x = np.array(self.POINTS)
        u = (S0 / E) * np.stack([-NU * x[:, 0], -NU * x[:, 1], x[:, 2]], axis=1)
        self.assertLess(np.abs(d["interior/displacement"] - u).max(), 1e-4 * S0 / E)
        # The grid: points 7 x 7 x 7 at -0.1, 0.1, ..., 1.1; inside 5 x 5 x 5, NaN elsewhere.
        g = d["interior/grid/stress"]
        inside = d["interior/grid/inside"].astype(bool)
        self.assertEqual(g.shape, (7, 7, 7, 6))
        self.assertEqual(d["interior/grid/displacement"].shape, (7, 7, 7, 3))
        self.assertEqual(int(inside.sum()), 125)
        self.assertTrue(np.isnan(g[~inside]).all() and np.isnan(d["interior/grid/displacement"][~inside]).all())
        self.assertLess(np.abs(g[inside] - exact).max(), 1e-4 * S0)
        np.testing.assert_allclose(d["interior/grid/x"], -0.1 + 0.2 * np.arange(7), atol=1e-12)
        self.assertEqual(int(d["grid_attrs"]["points_z"]), 7)
        with open(self.path("out.xdmf")) as f:
            xdmf = f.read()
        for text in ('Name="interior_grid"', '"3DRectMesh" Dimensions="7 7 7"', 'GeometryType="VXVYVZ"',
                     "out.h5:/interior/grid/x", 'Name="stress" AttributeType="Matrix"', 'Name="von_mises"'):
            self.assertIn(text, xdmf)

    def test_direct_evaluation_agrees(self):
        # The fast evaluation against every point integrated against every triangle.
        import numpy as np
        self.cube_l0_problem(tension(), interior_points={"points": self.POINTS, "grid": self.GRID})
        for name, extra in (("fast.h5", ()), ("direct.h5", ("-bem_interior_direct",)), ("noband.h5", ("-bem_interior_band", "0"))):
            r = self.run_driver("-problem", "problem.json", "-o", self.path(name), *extra, timeout=base.TIMEOUT_RUN)
            self.assertSucceeds(r, self.path(name))
        fast, direct, noband = self.read("fast.h5"), self.read("direct.h5"), self.read("noband.h5")
        for key in ("interior/stress", "interior/grid/stress"):
            a, b = fast[key], direct[key]
            self.assertTrue((np.isnan(a) == np.isnan(b)).all())
            self.assertLess(np.nanmax(np.abs(a - b)), 1e-6 * S0, key)  # measured 1e-9
            self.assertLess(np.nanmax(np.abs(noband[key] - b)), 1e-4 * S0, key)

    def test_one_and_two_ranks_give_the_same_file(self):
        import numpy as np
        self.cube_l0_problem(tension(), interior_points={"points": self.POINTS, "grid": self.GRID})
        for np_ in (1, 2):
            r = self.run_driver("-problem", "problem.json", "-bem_mat_type", "dense", "-o", self.path("r%d.h5" % np_), np=np_, timeout=base.TIMEOUT_RUN)
            self.assertSucceeds(r, self.path("r%d.h5" % np_))
        one, two = self.read("r1.h5"), self.read("r2.h5")
        self.assertEqual(sorted(one), sorted(two))
        for key in [k for k in one if k.startswith("fields/stress") or k.startswith("interior")]:
            a, b = np.asarray(one[key], dtype=float), np.asarray(two[key], dtype=float)
            self.assertTrue((np.isnan(a) == np.isnan(b)).all(), key)
            scale = max(np.nanmax(np.abs(a)), 1e-300)
            self.assertLessEqual(np.nanmax(np.abs(a - b)) / scale, 1e-10, key)  # the LU's round-off only

    def test_malformed_grids(self):
        cases = [({"box": [[0, 0, 0], [1, 1, 1]], "cells": [4, 0, 4]}, [r"interior_points\.grid\.cells\[1\]", r"between 1 and 100000, got 0"]),
                 ({"box": [[0, 0, 1], [1, 1, 0]], "cells": [4, 4, 4]}, [r"interior_points\.grid\.box", r"upper corner must exceed the lower corner", r"component 2"]),
                 ({"box": [[0, 0, 0], [1, 0, 1]], "cells": [4, 4, 4]}, [r"interior_points\.grid\.box", r"component 1"]),
                 ({"box": [[0, 0, 0], [1, 1, 1]], "cells": [4, 2.5, 4]}, [r"cells\[1\]", r"whole number of cells, got 2\.5"]),
                 ({"box": [[0, 0, 0], [1, 1, 1]], "cells": [4, 4]}, [r"interior_points\.grid\.cells", r"\[nx, ny, nz\]"]),
                 ({"box": [[0, 0, 0], [1, 1, 1]]}, [r"interior_points\.grid", r"\"cells\""]),
                 ({"box": [[0, 0], [1, 1, 1]], "cells": [4, 4, 4]}, [r"interior_points\.grid\.box\[0\]", r"3 components"]),
                 ({"box": [[0, 0, 0], [1, 1, 1]], "cells": [4, 4, 4], "step": 2}, [r"unknown key 'step'"]),
                 ({"box": [[0, 0, 0], [1, 1, 1]], "cells": [1000, 1000, 1000]}, [r"more than 50000000"])]
        for grid, patterns in cases:
            with self.subTest(grid=grid):
                self.cube_l0_problem(tension(), interior_points={"grid": grid})
                r = self.run_problem()
                self.assertFailsCleanly(r, r"problem\.json", *patterns)
                self.assertErrorLine(r)
                self.assertEqual(len([l for l in r.stderr.splitlines() if l.strip()]), 1, r.describe())
        self.cube_l0_problem(tension(), interior_points={"grid": self.GRID, "pts": []})
        self.assertFailsCleanly(self.run_problem(), r"unknown key 'pts'")

    def test_scene_stress_per_frame(self):
        import h5py
        import numpy as np
        frames = [{"boundary": [{"where": {"region": "z1"}, "traction": [0, 0, s]}]} for s in (10.0, 20.0)]
        self.cube_l0_problem(ROLLERS, frames=frames)
        r = self.run_problem(timeout=base.TIMEOUT_RUN)
        self.assertSucceeds(r, self.out, self.path("out.xdmf"))
        with h5py.File(self.out, "r") as f:
            for i, s in enumerate((10.0, 20.0)):
                stress = f["/frames/%d/stress" % i][()]
                self.assertLess(np.abs(stress - [0, 0, s, 0, 0, 0]).max(), 1e-4 * s, "frame %d" % i)
                np.testing.assert_allclose(f["/frames/%d/von_mises" % i][()], s, atol=1e-4 * s)
                self.assertEqual(f["/frames/%d/principal_stress" % i].shape, (stress.shape[0], 3))
        with open(self.path("out.xdmf")) as f:
            xdmf = f.read()
        self.assertIn("out.h5:/frames/1/stress", xdmf)
        self.assertIn("out.h5:/frames/1/von_mises", xdmf)


def main():
    base.run_suite(__doc__)


if __name__ == "__main__":
    main()
