#!/usr/bin/python3
"""Scaling benchmark of the H² factorization (PC h2), driving bench_h2_factor on the mesh
families of bench_hss.py (unit sphere, disk organ) and, with --mesh, on any other mesh.

For every family and target size N it generates (or reuses) the mesh as bench_hss.py does,
runs

    bench_h2_factor --mesh FILE [--dense 1 when N <= --dense-max] [EXTRA ARGS]

(see benchmarks/bench_h2_factor.cpp: H² compression, factorization, GMRES(100) right-preconditioned
by it or one direct solve, a second pattern refactored, ||I - A F^-1|| by power iterations, dense
assembly + LU in the same run) and collects its CSV line. At the end it prints one table per mesh
family and the log-log slopes of the factorization time, memory and iterations against N over
[--fit-min, --fit-max].

Examples
  benchmarks/bench_h2_factor.py --sizes 10000,20000 --dense-max 20000           # PC mode, minutes
  benchmarks/bench_h2_factor.py --sizes 20000 --dense-max 20000 \\
      --extra "--mode direct --tol 1e-7 --ftol 1e-7 --single 0"                 # direct mode
  benchmarks/bench_h2_factor.py --sizes 10000,20000,40000,80000,160000,300000 --csv out/bench/h2f.csv
  benchmarks/bench_h2_factor.py --from-csv out/bench/h2f.csv
"""

import argparse
import csv
import math
import os
import shlex
import sys

import numpy as np

from bench_common import parse_int_list, triangles_for_unknowns
from bench_hss import FAMILIES, ensure_mesh, run_command

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def to_float(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return math.nan


def slope(xs, ys):
    pts = [(math.log(x), math.log(y)) for x, y in zip(xs, ys) if x > 0 and y > 0 and math.isfinite(y)]
    if len(pts) < 2:
        return math.nan
    a = np.array(pts)
    return float(np.polyfit(a[:, 0], a[:, 1], 1)[0])


def run_one(bench, mesh, dense, extra, timeout):
    cmd = [bench, "--header", "--mesh", mesh, "--dense", "1" if dense else "0"] + extra
    print("  $ " + " ".join(shlex.quote(c) for c in cmd), flush=True)
    rc, out, err, wall = run_command(cmd, timeout)
    lines = [l for l in out.strip().splitlines() if l]
    if rc != 0 or len(lines) < 2:
        print(f"  FAILED ({'timeout' if rc is None else f'exit {rc}'}):\n{err[-3000:]}", flush=True)
        return None
    for l in err.splitlines():
        print("    " + l, flush=True)
    row = dict(zip(lines[0].split(","), lines[-1].split(",")))
    row["wall_s"] = f"{wall:.1f}"
    return row


def fmt(x, digits=3):
    if not math.isfinite(x):
        return "–"
    if x == 0:
        return "0"
    return f"{x:.{digits}g}" if abs(x) < 1e4 else f"{x:.0f}"


def report(rows, fit_min, fit_max):
    for family in sorted({r["family"] for r in rows}):
        rs = sorted((r for r in rows if r["family"] == family), key=lambda r: to_float(r["N"]))
        print(f"\n### {family}\n")
        print("| N | H² compress s | factor s (sketch) | mode | its | solve s | one apply s | refactor s | ‖I − A F⁻¹‖ | top | factors MB | H² MB | peak RSS MB |"
              " dense assembly + LU s | vs dense LU |")
        print("|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
        for r in rs:
            f = {k: to_float(v) for k, v in r.items()}
            dense = f["dense_assembly_s"] + f["dense_lu_s"]
            print(f"| {int(f['N'])} | {fmt(f['compress_s'])} | {fmt(f['factor_s'])} ({fmt(f['sketch_s'])}) | {r['mode']} | {int(f['iterations'])} | {fmt(f['solve_s'])} |"
                  f" {fmt(f['pc_apply_s'])} | {fmt(f['refactor_s'])} | {fmt(f['inv_err'])} | {int(f['top'])} | {fmt(f['factor_mb'])} | {fmt(f['h2_mb'])} |"
                  f" {fmt(f['peak_rss_mb'])} | {fmt(dense)} | {fmt(f['rel_diff'])} |")
        fit = [r for r in rs if fit_min <= to_float(r["N"]) <= fit_max]
        n = [to_float(r["N"]) for r in fit]
        if len(fit) >= 2:
            print(f"\nslopes over N in [{fit_min}, {fit_max}]: factorization {slope(n, [to_float(r['factor_s']) for r in fit]):.2f}, "
                  f"factors memory {slope(n, [to_float(r['factor_mb']) for r in fit]):.2f}, one application {slope(n, [to_float(r['pc_apply_s']) for r in fit]):.2f}, "
                  f"iterations {slope(n, [max(1.0, to_float(r['iterations'])) for r in fit]):.2f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bench", default=os.path.join(REPO, "build", "bin", "bench_h2_factor"))
    ap.add_argument("--sizes", type=lambda t: parse_int_list(t, "--sizes"), default=[10000, 20000, 40000])
    ap.add_argument("--families", default="sphere,disk")
    ap.add_argument("--mesh", action="append", default=[], help="an extra mesh file (family 'mesh:<name>'); repeatable")
    ap.add_argument("--mesh-dir", default=os.path.join(REPO, "build", "bench-meshes"))
    ap.add_argument("--dense-max", type=int, default=20000, help="dense assembly + LU up to this many unknowns")
    ap.add_argument("--extra", default="", help="further bench_h2_factor arguments, e.g. \"--ftol 1e-3\"")
    ap.add_argument("--timeout", type=float, default=7200)
    ap.add_argument("--csv", default=os.path.join(REPO, "out", "bench", "h2_factor.csv"))
    ap.add_argument("--from-csv", help="only print the tables and slopes of an existing CSV file")
    ap.add_argument("--fit-min", type=float, default=40000)
    ap.add_argument("--fit-max", type=float, default=300000)
    args = ap.parse_args()
    if args.from_csv:
        with open(args.from_csv) as f:
            report(list(csv.DictReader(f)), args.fit_min, args.fit_max)
        return 0
    if not os.access(args.bench, os.X_OK):
        sys.exit(f"bench_h2_factor.py: {args.bench} is not an executable (build the target bench_h2_factor)")
    extra = shlex.split(args.extra)
    cases = []
    for family in [f for f in args.families.split(",") if f]:
        if family not in FAMILIES:
            sys.exit(f"bench_h2_factor.py: unknown family {family!r} (known: {', '.join(FAMILIES)})")
        for n in args.sizes:
            cases.append((family, n, None))
    for m in args.mesh:
        cases.append(("mesh:" + os.path.basename(m), None, os.path.abspath(m)))
    rows = []
    os.makedirs(os.path.dirname(os.path.abspath(args.csv)), exist_ok=True)
    for family, n, path in cases:
        if path is None:
            path, err = ensure_mesh(family, triangles_for_unknowns(n), os.path.abspath(args.mesh_dir), args.timeout)
            if err:
                print(f"{family} {n}: {err}", flush=True)
                continue
        print(f"{family} {n or ''}: {os.path.basename(path)}", flush=True)
        row = run_one(args.bench, path, n is not None and n <= args.dense_max, extra, args.timeout)
        if row is None:
            continue
        row["family"] = family
        rows.append(row)
        with open(args.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=["family"] + [k for k in rows[0] if k != "family"])
            w.writeheader()
            w.writerows(rows)
    report(rows, args.fit_min, args.fit_max)
    print(f"\nCSV: {args.csv}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
