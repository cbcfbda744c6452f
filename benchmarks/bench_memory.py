#!/usr/bin/python3
"""The size model (core/size_limits.hpp) against the measured peak memory of the driver.

For each case (operator, mesh size, ranks, options) the script asks the driver for the model's
estimate (a run with -hssbem_memory_limit 1 is refused with "needs about X GB per node"), then
runs the case under /usr/bin/time on every rank and records each rank's maximum resident set
size. A node's measured need is the sum of its ranks' peaks (an upper bound of their
simultaneous use); the model must lie above it, by at most 25 %.

    export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1   # as root
    /usr/bin/python3 benchmarks/bench_memory.py --hssbem build/bin/hssbem --set h2 --csv out/mem/h2.csv

Sets: dense (dense + LU, spheres of 3k, 6k, 12k unknowns), hss (HSS + ULV at 1e-8, the same
spheres), h2 (H² + GMRES + PC h2, disk organs of 20k, 80k, 150k unknowns; --big adds 300k),
h2opt (the 80k organ with other tolerances, double precision, Jacobi, larger tops), hssopt
(the 6k sphere with other HSS tolerances).
Every case runs on 1 and 2 ranks (--ranks). Before a run, MemAvailable must be at least twice
the estimate (the machine is shared): the script waits up to --wait seconds, then skips the
case and says so.
"""

import argparse
import csv
import json
import os
import re
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)

# (set, mesh kind, unknowns, options); meshes: sphere (pure traction under pressure) or disk
# organ (bottom clamped, top under pressure).
SETS = {
    "dense": [("sphere", n, ["-bem_mat_type", "dense"]) for n in (3000, 6000, 12000)],
    "hss": [("sphere", n, ["-bem_mat_type", "hss"]) for n in (3000, 6000, 12000)],
    "h2": [("disk", n, ["-bem_mat_type", "h2"]) for n in (20000, 80000, 150000)],
    "h2opt": [("disk", 80000, ["-bem_mat_type", "h2"] + o) for o in (
        ["-mat_h2_rel_tol", "1e-4"], ["-mat_h2_rel_tol", "1e-6"], ["-mat_h2_single_precision", "false"],
        ["-pc_h2_rel_tol", "1e-4"], ["-pc_type", "jacobi"], ["-pc_h2_top_size", "10000"],
        ["-pc_h2_top_size", "20000"], ["-pc_h2_top_size", "10000", "-pc_h2_mixed_top", "0"],
        ["-ksp_type", "preonly", "-pc_h2_rel_tol", "1e-7"])],
    "hssopt": [("sphere", 6000, ["-bem_mat_type", "hss"] + o) for o in (["-mat_hss_rel_tol", "1e-6"], ["-mat_hss_rel_tol", "1e-4"], ["-mat_hss_rel_tol", "1e-10"])],
}


def mem_available():
    with open("/proc/meminfo") as f:
        for line in f:
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    return 0


def mesh_for(kind, n, workdir):
    """A sphere or a disk organ of about n unknowns (n = 1.5 T for T triangles), cached."""
    triangles = int(round(2 * (n / 3 - 2)))
    path = os.path.join(workdir, "%s_%d.msh" % (kind, n))
    if not os.path.exists(path):
        flag = "--sphere-triangles" if kind == "sphere" else "--disk-triangles"
        subprocess.run([sys.executable, os.path.join(REPO, "scripts", "gen_meshes.py"), flag, str(triangles), "--out", path], check=True,
                       stdout=subprocess.DEVNULL)
    return path


def problem_for(kind, mesh, workdir):
    path = os.path.join(workdir, os.path.basename(mesh).replace(".msh", ".json"))
    if kind == "sphere":
        rules = [{"where": "all", "pressure": 1.0}]
    else:
        rules = [{"where": {"region": "bottom"}, "displacement": [0, 0, 0]}, {"where": {"region": "top"}, "pressure": 1.0}]
    with open(path, "w") as f:
        json.dump({"mesh": os.path.basename(mesh), "material": {"E": 1.0, "nu": 0.3}, "boundary": rules}, f)
    return path


def launcher(args, ranks):
    return [args.mpiexec, "-n", str(ranks), "--bind-to", "none"]


def estimate(args, problem, ranks, opts):
    """The model's bytes per node, from the refusal of a run given 1 byte of memory."""
    cmd = launcher(args, ranks) + [args.hssbem, "-problem", problem, "-hssbem_memory_limit", "1"] + opts
    out = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True).stdout
    m = re.search(r"needs about ([0-9.e+]+) GB per node", out)
    if not m:
        raise RuntimeError("no estimate in:\n" + out[-2000:])
    return float(m.group(1)) * 1e9  # printed to 3 digits


def measure(args, problem, ranks, opts):
    """Each rank's peak resident memory (bytes) and the wall time of the run."""
    env = dict(os.environ, OMP_NUM_THREADS=str(max(1, 2 // ranks)), OPENBLAS_NUM_THREADS="1")
    cmd = launcher(args, ranks) + ["/usr/bin/time", "-f", "hssbem-maxrss-kb %M", args.hssbem, "-problem", problem] + opts
    start = time.time()
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True, env=env, cwd=os.path.dirname(problem))
    wall = time.time() - start
    peaks = [int(k) * 1024 for k in re.findall(r"hssbem-maxrss-kb (\d+)", p.stdout)]
    if p.returncode != 0 or len(peaks) != ranks:
        raise RuntimeError("run failed:\n" + p.stdout[-3000:])
    its = re.search(r"solved with (\S+): (\d+) iterations", p.stdout)
    return peaks, wall, (its.group(1) + " " + its.group(2)) if its else ""


def remodel(args):
    """The rows of args.remodel with the model of args.hssbem (the measurements kept)."""
    with open(args.remodel) as f:
        rows = list(csv.DictReader(f))
    with open(args.csv, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        for row in rows:
            kind, n, ranks, opts = row["mesh"], int(row["unknowns"]), int(row["ranks"]), row["options"].split()
            problem = problem_for(kind, mesh_for(kind, n, args.workdir), args.workdir)
            need = estimate(args, problem, ranks, opts)
            row["model_GB_per_node"] = "%.3f" % (need / 1e9)
            row["model_over_measured"] = "%.2f" % (need / 1e9 / float(row["measured_GB_per_node"]))
            w.writerow(row)
            print(" ".join(row[k] for k in ("mesh", "unknowns", "ranks", "options", "model_GB_per_node", "measured_GB_per_node", "model_over_measured")), flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--hssbem", default=os.path.join(REPO, "build", "bin", "hssbem"))
    ap.add_argument("--mpiexec", default="mpiexec")
    ap.add_argument("--set", action="append", choices=sorted(SETS), default=[])
    ap.add_argument("--ranks", default="1,2")
    ap.add_argument("--big", action="store_true", help="h2: add the 300k organ (about 10 GB on one rank)")
    ap.add_argument("--workdir", default=os.path.join(REPO, "out", "mem"))
    ap.add_argument("--csv", required=True)
    ap.add_argument("--wait", type=float, default=600, help="seconds to wait for memory before skipping a case")
    ap.add_argument("--need-factor", type=float, default=2.0, help="MemAvailable needed, in estimates (the estimate itself may be generous)")
    ap.add_argument("--remodel", metavar="CSV", help="recompute the model's columns of an earlier CSV with this --hssbem (no run) into --csv")
    args = ap.parse_args()
    args.hssbem = os.path.abspath(args.hssbem)
    os.makedirs(args.workdir, exist_ok=True)
    if args.remodel:
        return remodel(args)
    if not args.set:
        ap.error("--set is needed (or --remodel)")
    cases = [c for s in args.set for c in SETS[s]]
    if args.big and "h2" in args.set:
        cases.append(("disk", 300000, ["-bem_mat_type", "h2"]))
    fields = ["mesh", "unknowns", "ranks", "options", "model_GB_per_node", "measured_GB_per_node", "model_over_measured", "rank_peaks_GB", "wall_s", "solve"]
    new = not os.path.exists(args.csv)
    with open(args.csv, "a", newline="") as f:
        w = csv.writer(f)
        if new:
            w.writerow(fields)
        for kind, n, opts in cases:
            mesh = mesh_for(kind, n, args.workdir)
            problem = problem_for(kind, mesh, args.workdir)
            for ranks in (int(r) for r in args.ranks.split(",")):
                need = estimate(args, problem, ranks, opts)
                deadline = time.time() + args.wait
                while mem_available() < args.need_factor * need and time.time() < deadline:
                    time.sleep(10)
                if mem_available() < args.need_factor * need:
                    print("skipped %s %d %d %s: %.1f GB available, model %.1f GB" % (kind, n, ranks, " ".join(opts), mem_available() / 1e9, need / 1e9), flush=True)
                    continue
                peaks, wall, solve = measure(args, problem, ranks, opts)
                row = [kind, n, ranks, " ".join(opts), "%.3f" % (need / 1e9), "%.3f" % (sum(peaks) / 1e9), "%.2f" % (need / sum(peaks)),
                       "/".join("%.3f" % (p / 1e9) for p in peaks), "%.0f" % wall, solve]
                w.writerow(row)
                f.flush()
                print(" ".join(str(x) for x in row), flush=True)


if __name__ == "__main__":
    main()
