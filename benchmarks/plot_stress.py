#!/usr/bin/python3
"""Plot the interior stress error against depth from bench_stress CSV files.

Usage:
    /usr/bin/python3 benchmarks/plot_stress.py out.png FILE.csv [FILE.csv ...] [--title TEXT]

Each CSV is what `bench_stress --csv FILE` writes: per method (plain: the identities integrated at
the point; band: interpolated along the normal within an element of the surface; subtract: the
reference with the linear field of the surface stress subtracted, every triangle) and depth (in
element sizes h, the mean edge) the largest and RMS error over the sample points, relative to the
stress scale. One panel per file (its case and mesh in the title): the largest error against depth,
log-log, one line per method, the RMS dashed, the surface stress error and the issue's targets as
horizontal guides. Needs matplotlib (python3-matplotlib).
"""

import argparse
import csv
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

COLOURS = {"plain": "tab:blue", "band": "tab:red", "subtract": "tab:green", "direct": "tab:purple"}


def read(path):
    """{method: [(depth, max, rms)]}, e_u, case, mesh, and the mid-chord errors."""
    rows, mid = {}, {}
    case = mesh = ""
    e_u = 0.0
    with open(path) as f:
        for r in csv.DictReader(f):
            case, mesh, e_u = r["case"], os.path.basename(r["mesh"]), float(r["e_u"])
            if r["depth_h"] == "mid":
                mid[r["method"]] = float(r["max_err"])
                continue
            rows.setdefault(r["method"], []).append((float(r["depth_h"]), float(r["max_err"]), float(r["rms_err"])))
    for v in rows.values():
        v.sort()
    return rows, mid, e_u, case, mesh


def panel(ax, path):
    rows, mid, e_u, case, mesh = read(path)
    b = max(1e-2, 2 * e_u)
    for method, pts in rows.items():
        d = [p[0] for p in pts]
        ax.loglog(d, [p[1] for p in pts], "o-", color=COLOURS.get(method), label="%s, largest" % method)
        ax.loglog(d, [p[2] for p in pts], "--", color=COLOURS.get(method), alpha=0.6, label="%s, RMS" % method)
    ax.axhline(3 * b + 1e-3, color="grey", lw=0.8, ls=":")
    ax.axhline(max(3e-2, 3 * b), color="black", lw=0.8, ls=":")
    ax.text(0.05, max(3e-2, 3 * b) * 1.1, "target below 1 h", fontsize=7)
    if mid:
        ax.axhline(max(mid.values()), color="tab:orange", lw=0.8)
        ax.text(0.05, max(mid.values()) * 1.1, "mid-chord", fontsize=7, color="tab:orange")
    ax.set_title("%s on %s (e_u %.1e)" % (case, mesh, e_u), fontsize=9)
    ax.set_xlabel("depth below the surface / h")
    ax.set_ylabel("stress error / stress scale")
    ax.grid(True, which="both", alpha=0.3)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("png")
    parser.add_argument("csv", nargs="+")
    parser.add_argument("--title", default="Interior stress error against depth")
    args = parser.parse_args(argv)
    n = len(args.csv)
    cols = min(n, 3)
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.6 * rows), squeeze=False)
    for i, path in enumerate(args.csv):
        panel(axes[i // cols][i % cols], path)
    for j in range(n, rows * cols):
        axes[j // cols][j % cols].axis("off")
    axes[0][0].legend(fontsize=7, loc="upper right")
    fig.suptitle(args.title)
    fig.tight_layout()
    fig.savefig(args.png, dpi=110)
    print("wrote %s" % args.png)
    return 0


if __name__ == "__main__":
    sys.exit(main())
