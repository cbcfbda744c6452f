#!/usr/bin/python3
"""Kelvin's point force as an analytic check of the driver at any size, on a sphere centred at the
origin (the sphere family of scripts/gen_meshes.py).

The displacement and traction of Kelvin's solution for a point force F at a source s outside the
body are an exact elastostatic field inside it. `write` turns them into a mixed problem file:
traction (with the sphere's exact normal x/|x|) on every vertex, then displacement on the vertices
with z >= 0 (the later rule wins there), each as per-vertex rows; the tests' Kelvin mixed problem
(tests/common/solve_helpers.hpp), at any mesh size. `check` compares a result file of the driver
with the exact field: the relative L2 error of the displacement where it was unknown (z < 0) and of
the traction where it was unknown (z >= 0).

  scripts/kelvin_problem.py write --mesh sphere.msh --out kelvin.json [--output kelvin.h5]
  hssbem -problem kelvin.json ...
  scripts/kelvin_problem.py check --result kelvin.h5

Options of both: --E 1000, --nu 0.3, --source 1.2,0.9,1.0, --force 1,-2,0.5 (as the tests). The
mesh is read with gmsh's Python module, vertices in ascending node tag (the driver's order for
.msh files). Needs numpy (and h5py for check): run with Debian's /usr/bin/python3.
"""

import argparse
import json
import math
import os
import sys

import numpy as np


def triple(text):
    v = [float(x) for x in text.split(",")]
    if len(v) != 3:
        raise argparse.ArgumentTypeError("expected three comma-separated numbers, got %r" % text)
    return np.array(v)


def kelvin(points, normals, E, nu, s, F):
    """Displacement and traction (rows of points) of Kelvin's solution for force F at s."""
    mu = E / (2 * (1 + nu))
    d = points - s
    r = np.linalg.norm(d, axis=1)
    g = d / r[:, None]
    gF = g @ F
    u = ((3 - 4 * nu) * F[None, :] + g * gF[:, None]) / (16 * math.pi * mu * (1 - nu) * r[:, None])
    drdn = np.einsum("ij,ij->i", g, normals)
    gn = normals @ F  # n·F
    # t_k = -1/(8π(1-ν) r²) [drdn((1-2ν) F_k + 3 g_k (g·F)) - (1-2ν)((g·F) n_k - (n·F) g_k)]
    t = -(drdn[:, None] * ((1 - 2 * nu) * F[None, :] + 3 * g * gF[:, None])
          - (1 - 2 * nu) * (gF[:, None] * normals - gn[:, None] * g)) / (8 * math.pi * (1 - nu) * r[:, None] ** 2)
    return u, t


def sphere_normals(points):
    return points / np.linalg.norm(points, axis=1)[:, None]


def read_vertices(mesh):
    import gmsh
    gmsh.initialize(["", "-v", "0"])
    try:
        gmsh.open(mesh)
        tags, coords, _ = gmsh.model.mesh.getNodes()
    finally:
        gmsh.finalize()
    order = np.argsort(tags)
    return np.asarray(coords).reshape(-1, 3)[order]


def check_outside(points, s):
    if np.linalg.norm(s) <= np.max(np.linalg.norm(points, axis=1)):
        sys.exit("kelvin_problem.py: the source %s is not outside the sphere" % s.tolist())


def rows(a):
    return [[float("%.17g" % x) for x in row] for row in a]


def write(args):
    x = read_vertices(args.mesh)
    check_outside(x, args.source)
    u, t = kelvin(x, sphere_normals(x), args.E, args.nu, args.source, args.force)
    upper = np.nonzero(x[:, 2] >= 0)[0]
    problem = {
        "mesh": os.path.relpath(os.path.abspath(args.mesh), os.path.dirname(os.path.abspath(args.out))),
        "material": {"E": args.E, "nu": args.nu},
        "boundary": [
            {"where": "all", "traction": rows(t)},
            {"where": {"vertices": [int(v) for v in upper]}, "displacement": rows(u[upper])},
        ],
    }
    if args.output:
        problem["output"] = args.output
    tmp = args.out + ".tmp"
    with open(tmp, "w") as f:
        json.dump(problem, f, separators=(",", ":"))
    os.replace(tmp, args.out)
    print("%s: %d vertices, displacement on %d (z >= 0), traction on %d" % (args.out, len(x), len(upper), len(x) - len(upper)))


def check(args):
    import h5py
    with h5py.File(args.result, "r") as f:
        x = f["/mesh/vertices"][...]
        u_h = f["/fields/displacement"][...]
        t_h = f["/fields/traction"][...]
    check_outside(x, args.source)
    u, t = kelvin(x, sphere_normals(x), args.E, args.nu, args.source, args.force)
    lower, upper = x[:, 2] < 0, x[:, 2] >= 0

    def rel(a, b):
        return float(np.linalg.norm(a - b) / np.linalg.norm(b))

    out = {"vertices": int(len(x)), "displacement_error": rel(u_h[lower], u[lower]), "traction_error": rel(t_h[upper], t[upper])}
    print(json.dumps(out))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True)
    for name in ("write", "check"):
        q = sub.add_parser(name)
        q.add_argument("--E", type=float, default=1000.0)
        q.add_argument("--nu", type=float, default=0.3)
        q.add_argument("--source", type=triple, default=triple("1.2,0.9,1.0"))
        q.add_argument("--force", type=triple, default=triple("1,-2,0.5"))
        if name == "write":
            q.add_argument("--mesh", required=True)
            q.add_argument("--out", required=True, help="problem file to write")
            q.add_argument("--output", help="result file the problem names (as the driver reads it: relative to the working directory)")
        else:
            q.add_argument("--result", required=True, help="the driver's result file")
    args = p.parse_args()
    write(args) if args.command == "write" else check(args)


if __name__ == "__main__":
    main()
