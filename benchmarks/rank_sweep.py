#!/usr/bin/env python3
"""The driver's default solver at 1..P ranks on generated meshes: every rank count must solve, and
the answers must agree with the 1-rank answer to the compression tolerance.

For each mesh family (disk organ, sphere, cardioid; about --unknowns unknowns each) a problem is
written beside the mesh (the disk organ clamped on its bottom and indented from above, the sphere
and the cardioid clamped on one region and pressed on another), then `hssbem` runs it with the
default options at each rank count (oversubscribed beyond the cores, one thread per rank). Prints
one line per run: ranks, iterations, the driver's residual, wall seconds (mpirun included), and the
relative L2 difference of the displacement and the traction against the 1-rank run.

    /usr/bin/python3 benchmarks/rank_sweep.py --driver build/bin/hssbem --ranks 1-8 --unknowns 20000
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)

# family -> (gen_meshes.py option, boundary rules)
FAMILIES = {
    "disk_organ": ("--disk-triangles", [
        {"where": {"region": "bottom"}, "displacement": [0, 0, 0]},
        {"where": {"sphere": {"center": [0, 0, 0.3], "radius": 0.3}}, "displacement": [None, None, -0.03]}]),
    "sphere": ("--sphere-triangles", [
        {"where": {"region": "south"}, "displacement": [0, 0, 0]},
        {"where": {"region": "north"}, "pressure": 100.0}]),
    "cardioid": ("--cardioid-triangles", [
        {"where": {"region": "base"}, "displacement": [0, 0, 0]},
        {"where": {"region": "body"}, "pressure": 50.0}]),
}


def parse_ranks(text):
    if "-" in text:
        lo, hi = (int(v) for v in text.split("-"))
        return list(range(lo, hi + 1))
    return [int(v) for v in text.split(",")]


def make_problem(family, triangles, workdir):
    option, rules = FAMILIES[family]
    mesh = os.path.join(workdir, family + ".msh")
    if not os.path.exists(mesh):
        subprocess.run([sys.executable, os.path.join(REPO, "scripts", "gen_meshes.py"), option, str(triangles), "--out", mesh],
                       check=True, stdout=subprocess.DEVNULL)
    problem = os.path.join(workdir, family + ".json")
    with open(problem, "w") as f:
        json.dump({"mesh": mesh, "material": {"E": 3000.0, "nu": 0.49}, "boundary": rules}, f)
    return problem


def run(driver, problem, ranks, out, extra):
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    cmd = ["mpirun", "--oversubscribe", "-n", str(ranks), driver, "-problem", problem, "-o", out] + extra
    start = time.time()
    r = subprocess.run(cmd, env=env, capture_output=True, text=True)
    seconds = time.time() - start
    text = r.stdout + r.stderr
    m = re.search(r"solved with (\S+): (\d+) iterations, relative residual (\S+)", text)
    err = re.search(r"hssbem: error: .*", text)
    return {"ok": r.returncode == 0, "seconds": seconds, "solver": m.group(1) if m else "-",
            "iterations": int(m.group(2)) if m else -1, "residual": m.group(3) if m else "-",
            "error": err.group(0) if err else ("" if r.returncode == 0 else text[-300:])}


def fields(path):
    with h5py.File(path, "r") as f:
        return f["fields/displacement"][()], f["fields/traction"][()]


def rel(a, b):
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--driver", default=os.path.join(REPO, "build", "bin", "hssbem"))
    p.add_argument("--ranks", type=parse_ranks, default=parse_ranks("1-8"), help="e.g. 1-8 or 1,3,6")
    p.add_argument("--unknowns", type=int, default=20000, help="about this many unknowns per mesh")
    p.add_argument("--families", default="disk_organ,sphere,cardioid")
    p.add_argument("--workdir", help="keep meshes and results here (default: a temporary directory)")
    p.add_argument("extra", nargs="*", help="options passed to the driver (after --)")
    a = p.parse_args()
    workdir = a.workdir or tempfile.mkdtemp(prefix="rank_sweep_")
    os.makedirs(workdir, exist_ok=True)
    triangles = 2 * int(round(a.unknowns / 3 - 2))  # even (a closed genus-0 surface: T = 2 (V - 2))
    failures = 0
    print("%-10s %5s %-10s %5s %10s %8s %10s %10s  %s" % ("mesh", "ranks", "solver", "its", "residual", "seconds", "du", "dt", "error"))
    for family in a.families.split(","):
        problem = make_problem(family, triangles, workdir)
        ref = None
        for ranks in a.ranks:
            out = os.path.join(workdir, "%s_np%d.h5" % (family, ranks))
            r = run(a.driver, problem, ranks, out, a.extra)
            du = dt = float("nan")
            if r["ok"]:
                u, t = fields(out)
                if ref is None:
                    ref = (u, t)
                du, dt = rel(u, ref[0]), rel(t, ref[1])
            else:
                failures += 1
            print("%-10s %5d %-10s %5d %10s %8.1f %10.2e %10.2e  %s" % (family, ranks, r["solver"], r["iterations"], r["residual"], r["seconds"], du, dt, r["error"]),
                  flush=True)
    print("workdir:", workdir)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
