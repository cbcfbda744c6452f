#!/usr/bin/env python3
"""A static solve's H2 precomputation saved and loaded (-hssbem_save, -hssbem_load on the default
H2 path: the H2 operator and PC h2's factors; docs/persistence.md), side by side with the cold
run, through the driver. Two problems on one organ share the pattern and differ in their loads
(A: the top pressed 0.03 down, B: 0.01 down and 0.01 sideways). Run i solves its problem cold
and saves (A for odd i, B for even i), then solves the other problem from the file it just
saved (new loads); the loaded answers are compared with the other problem's cold answers of
the neighbouring run, bit for bit, iterations included.

Per run: the cold precomputation and solve (the result file's timings "assembly" — the H2
compression — plus "solve" — PC h2's factorization and GMRES), the save, the load and solve
("load" — the files read, checked and the matrix unpacked — plus "solve" — the factors
unpacked and GMRES), their ratio (target <= 20 %), the process's wall and CPU time, the files'
size and the load average.

  OMP_NUM_THREADS=2 OPENBLAS_NUM_THREADS=2 bench_h2_persistence.py --driver build/bin/hssbem \\
      --mesh organ100k.msh --runs 2 --csv out.csv [--np 2]

The mesh: scripts/gen_meshes.py --disk-triangles N (region "bottom" clamped). Needs h5py.
"""
import argparse
import csv
import glob
import json
import os
import tempfile

from bench_common import figure, timed_run


def problem(mesh, name, push, side, out_dir):
    spec = {"mesh": os.path.abspath(mesh), "material": {"E": 3000, "nu": 0.45},
            "boundary": [{"where": {"region": "bottom"}, "displacement": [0, 0, 0]},
                         {"where": {"sphere": {"center": [0, 0, 0.3], "radius": 0.3}}, "displacement": [side, None, -push]}]}
    path = os.path.join(out_dir, name + ".json")
    with open(path, "w") as f:
        json.dump(spec, f, indent=1)
    return path


def answer(path):
    """The fields (bytes), the iterations and the timings of a result file."""
    import h5py
    with h5py.File(path, "r") as f:
        fields = tuple(f[k][()].tobytes() for k in ("fields/displacement", "fields/traction"))
        return fields, int(f.attrs["iterations"]), {k: float(v) for k, v in f["/timings"].attrs.items()}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--driver", required=True)
    ap.add_argument("--mesh", required=True)
    ap.add_argument("--np", type=int, default=1)
    ap.add_argument("--runs", type=int, default=2)
    ap.add_argument("--dir", default=None, help="where the files go (default: a new temporary directory)")
    ap.add_argument("--csv", required=True)
    a = ap.parse_args()
    d = a.dir or tempfile.mkdtemp(prefix="bench-h2-persistence-")
    probs = {"A": problem(a.mesh, "A", 0.03, 0.0, d), "B": problem(a.mesh, "B", 0.01, 0.01, d)}
    print("bench_h2_persistence: %s, %d ranks; OMP_NUM_THREADS=%s; load %s" % (a.mesh, a.np, os.environ.get("OMP_NUM_THREADS"), os.getloadavg()), flush=True)
    rows, cold, warm = [], {}, {}
    for i in range(1, a.runs + 1):
        mine, other = ("A", "B") if i % 2 else ("B", "A")
        saved = os.path.join(d, "organ_%d.pre" % i)
        out = os.path.join(d, "out.h5")
        wall_c, cpu_c, out_c = timed_run(a.driver, probs[mine], out, ["-hssbem_save", saved], a.np)
        cold[mine] = answer(out)
        size = sum(os.path.getsize(p) for p in [saved] + glob.glob(saved + ".rank*"))
        wall_l, cpu_l, out_l = timed_run(a.driver, probs[other], out, ["-hssbem_load", saved], a.np)
        warm[other] = answer(out)
        t_c, t_l = cold[mine][2], warm[other][2]
        cold_s = t_c.get("assembly", 0) + t_c.get("solve", 0)
        load_s = t_l.get("load", 0) + t_l.get("solve", 0)
        row = {"run": i, "ranks": a.np, "unknowns": int(figure(r"(\d+) unknowns", out_c)), "cold_problem": mine, "loaded_problem": other,
               "cold_compress_s": t_c.get("assembly", 0), "cold_factor_solve_s": t_c.get("solve", 0), "cold_s": cold_s,
               "save_s": figure(r"saved the precomputation to .* in ([\d.]+) s", out_c),
               "load_read_s": t_l.get("load", 0), "load_factor_solve_s": t_l.get("solve", 0), "load_s": load_s, "load_over_cold": load_s / cold_s,
               "cold_iterations": cold[mine][1], "load_iterations": warm[other][1],
               "cold_wall_s": wall_c, "cold_cpu_s": cpu_c, "load_wall_s": wall_l, "load_cpu_s": cpu_l, "files_mb": size / 1e6, "loadavg_1min": os.getloadavg()[0]}
        rows.append(row)
        print(" ".join("%s=%s" % (k, ("%.3f" % v) if isinstance(v, float) else v) for k, v in row.items()), flush=True)
        for p in [saved] + glob.glob(saved + ".rank*"):
            os.remove(p)
    for name in sorted(warm):
        if name in cold:
            same = warm[name][0] == cold[name][0] and warm[name][1] == cold[name][1]
            print("problem %s: loaded answer and iterations bitwise the cold run's: %s (%d iterations)" % (name, "yes" if same else "NO", cold[name][1]), flush=True)
            for r in rows:
                if r["loaded_problem"] == name:
                    r["bitwise"] = same
    with open(a.csv, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[-1]) + ([] if "bitwise" in rows[-1] else ["bitwise"]))
        w.writeheader()
        w.writerows(rows)


if __name__ == "__main__":
    main()
