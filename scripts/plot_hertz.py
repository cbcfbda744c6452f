#!/usr/bin/python3
"""Draw the contact pressure of a Hertz problem (a sphere pressed on a plane) from an hssbem result
file: the pressure disc seen from below, and the pressure against the distance from the pole
beside Hertz's p0 sqrt(1 - r^2/a^2) for the force the solver reports (docs/contact.md).

Usage:
    /usr/bin/python3 scripts/plot_hertz.py RESULT.h5 --out hertz.png [--radius 1] [--obstacle NAME]

The result is a single solve with /contact (its pressure and the force of the obstacle NAME,
default the only one); E and nu come from the file's attributes, the sphere's radius from
--radius (the pole at the lowest point of the mesh, the plane below it).  Needs numpy, h5py and
matplotlib (Debian's python3-*, hence /usr/bin/python3).
"""

import argparse
import math
import sys

import numpy as np

try:
    import h5py
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.tri as mtri
except ImportError as exc:
    sys.exit("plot_hertz.py: error: %s (install python3-h5py and python3-matplotlib)" % exc)


def load(path, obstacle):
    with h5py.File(path, "r") as f:
        if "contact" not in f:
            raise SystemExit("plot_hertz.py: error: %s has no /contact (not a contact problem's single solve)" % path)
        forces = {k: f["/contact/forces"][k][()] for k in f["/contact/forces"]}
        name = obstacle or (list(forces)[0] if len(forces) == 1 else None)
        if name not in forces:
            raise SystemExit("plot_hertz.py: error: give --obstacle, one of %s" % ", ".join(forces))
        return (f["/mesh/vertices"][()], f["/mesh/triangles"][()], f["/contact/pressure"][()],
                float(np.linalg.norm(forces[name])), float(f.attrs["E"]), float(f.attrs["nu"]))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("result")
    ap.add_argument("--out", required=True)
    ap.add_argument("--radius", type=float, default=1.0)
    ap.add_argument("--obstacle")
    args = ap.parse_args()
    V, T, p, F, E, nu = load(args.result, args.obstacle)
    pole = V[np.argmin(V[:, 2])]
    r = np.hypot(V[:, 0] - pole[0], V[:, 1] - pole[1])
    a = (3 * F * args.radius / (4 * E / (1 - nu * nu))) ** (1 / 3)
    p0 = 3 * F / (2 * math.pi * a * a)
    near = (r < 1.6 * a) & (V[:, 2] < pole[2] + 0.5 * args.radius)  # the contact side only
    keep = near[T].all(axis=1)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(8.4, 3.6), dpi=100)
    tri = mtri.Triangulation(V[:, 0] - pole[0], V[:, 1] - pole[1], T[keep])
    im = ax1.tripcolor(tri, p, shading="gouraud", cmap="viridis", vmin=0)
    ax1.add_patch(plt.Circle((0, 0), a, fill=False, ls="--", color="w", lw=1))
    ax1.set_aspect("equal")
    ax1.set_xlim(-1.5 * a, 1.5 * a)
    ax1.set_ylim(-1.5 * a, 1.5 * a)
    ax1.set_title("contact pressure (Hertz radius dashed)", fontsize=9)
    fig.colorbar(im, ax=ax1, shrink=0.85, label="p")
    rr = np.linspace(0, a, 200)
    ax2.plot(rr, p0 * np.sqrt(1 - (rr / a) ** 2), "k-", lw=1.2, label="Hertz, F = %.3g" % F)
    ax2.plot(r[near], p[near], ".", ms=3, label="hssbem (vertices)")
    ax2.set_xlabel("distance from the pole")
    ax2.set_ylabel("pressure")
    ax2.set_xlim(0, 1.5 * a)
    ax2.legend(fontsize=8)
    ax2.set_title("a = %.4g, p0 = %.4g (Hertz)" % (a, p0), fontsize=9)
    fig.tight_layout()
    fig.savefig(args.out)
    print("plot_hertz.py: wrote %s (F = %.4g, Hertz a = %.4g, p0 = %.4g)" % (args.out, F, a, p0))


if __name__ == "__main__":
    main()
