#!/usr/bin/env python3
"""Two builds of the hssbem driver side by side on the same problems: runs them in turn (new,
old, new, old, ...), one warm-up each then --runs counted runs each, and reports for every case
the medians of the whole process's CPU seconds (user + system, /usr/bin/time) and wall seconds,
and the median of the pair-by-pair ratios new/old, with the phases each run wrote in its result
file's /timings (medians). On a shared machine the CPU seconds are the comparison.

  bench_drivers.py --new build/bin/hssbem --old ../base/build/bin/hssbem \\
      --case "disk20k=disk20k.json" --case "scene=scene.json;-scene_strategy;auto" --runs 5 --csv out.csv

A case is NAME=PROBLEM[;ARG;ARG...]: the problem file and extra driver options. PROBLEM may be
NEW_PROBLEM|OLD_PROBLEM: two problem files, one per side (the same build as --new and --old then
compares two problems, e.g. with and without gravity). Needs h5py.
"""
import argparse
import csv
import os
import statistics
import subprocess
import sys
import tempfile


def run_once(driver, problem, extra, out):
    """(wall s, CPU s, max RSS kB, {phase: s}) of one run of `driver`."""
    cmd = ["/usr/bin/time", "-f", "%e %U %S %M", driver, "-problem", problem, "-o", out] + extra
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True)
    if p.returncode != 0:
        sys.exit("failed: %s\n%s\n%s" % (" ".join(cmd), p.stdout, p.stderr))
    wall, user, system, rss = p.stderr.strip().splitlines()[-1].split()
    import h5py
    with h5py.File(out, "r") as f:
        phases = {k: float(v) for k, v in f["/timings"].attrs.items()}
    return float(wall), float(user) + float(system), int(rss), phases


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--new", required=True)
    ap.add_argument("--old", required=True)
    ap.add_argument("--case", action="append", required=True)
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--csv", required=True)
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="bench-drivers-")
    rows = []
    for case in a.case:
        name, spec = case.split("=", 1)
        problem, *extra = spec.split(";")
        problems = dict(zip(("new", "old"), problem.split("|") if "|" in problem else (problem, problem)))
        for i in range(a.runs + 1):
            for which, driver in (("new", a.new), ("old", a.old)):
                wall, cpu, rss, phases = run_once(driver, problems[which], extra, os.path.join(tmp, which + ".h5"))
                if i == 0:
                    continue  # the warm-up
                rows.append({"case": name, "driver": which, "run": i, "wall_s": wall, "cpu_s": cpu, "max_rss_kb": rss,
                             "phases": " ".join("%s=%.4g" % kv for kv in sorted(phases.items()))})
                print("%s %s run %d: wall %.2f s, CPU %.2f s, %s" % (name, which, i, wall, cpu, rows[-1]["phases"]), flush=True)
    with open(a.csv, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print("\n| case | CPU s new | CPU s old | CPU new/old (median of pairs; range) | wall new/old |")
    print("|---|---:|---:|---:|---:|")
    for case in a.case:
        name = case.split("=", 1)[0]
        new = [r for r in rows if r["case"] == name and r["driver"] == "new"]
        old = [r for r in rows if r["case"] == name and r["driver"] == "old"]
        ratios = [n["cpu_s"] / o["cpu_s"] for n, o in zip(new, old)]
        walls = [n["wall_s"] / o["wall_s"] for n, o in zip(new, old)]
        print("| %s | %.2f | %.2f | %.3f (%.3f–%.3f) | %.3f |" % (name, statistics.median(r["cpu_s"] for r in new), statistics.median(r["cpu_s"] for r in old),
                                                             statistics.median(ratios), min(ratios), max(ratios), statistics.median(walls)))


if __name__ == "__main__":
    main()
