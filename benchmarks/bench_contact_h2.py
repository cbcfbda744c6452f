#!/usr/bin/python3
"""Static sphere-on-plane contact on the H² path against a plain H² solve of the same mesh.

Issue 30's scale target: a static sphere-on-plane contact at 100k unknowns on the H² path in at
most 5x the time of a plain H² solve of the same mesh, set-up included on both sides. Both are
runs of the driver, side by side, alternating, with OMP_NUM_THREADS = OPENBLAS_NUM_THREADS = 2:

  plain    the Hertz hemisphere, its flat face pushed down by --delta, no contact:
           -bem_mat_type h2 (compression, PC h2's factorization, GMRES)
  contact  the same with a rigid table under the pole ("contact": a plane at z = 0):
           -bem_mat_type h2 (the H² reference: compression, factorization, W's candidate
           columns by blocked factor solves, the active set, corrections by accurate solves)

The wall time of each process is measured (mesh reading included on both sides; no result
file). One more contact run writes its result, and the contact radius and peak pressure fitted
to p^2 = p0^2 (1 - r^2/a^2) are compared with Hertz's for the force the solver reports.

  /usr/bin/python3 benchmarks/bench_contact_h2.py --driver build/bin/hssbem --mesh hertz_100k.msh \\
      --delta 0.01 --reach 0.005 --repeat 1 --csv out/bench/contact_h2.csv
"""
import argparse
import csv
import json
import math
import os
import re
import resource
import statistics
import subprocess
import sys
import time

import numpy as np


def run(driver, problem, extra, log):
    env = dict(os.environ, OMP_NUM_THREADS="2", OPENBLAS_NUM_THREADS="2")
    t, u0 = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
    r = subprocess.run([driver, "-problem", problem] + extra, env=env, capture_output=True, text=True)
    wall, u1 = time.perf_counter() - t, resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (u1.ru_utime + u1.ru_stime) - (u0.ru_utime + u0.ru_stime)
    with open(log, "w") as f:
        f.write(r.stdout + r.stderr)
    if r.returncode != 0:
        sys.exit("bench_contact_h2.py: %s failed (see %s):\n%s" % (problem, log, (r.stdout + r.stderr)[-2000:]))
    return wall, cpu, r.stdout


def hertz_fit(result, R, E, nu):
    import h5py
    with h5py.File(result, "r") as f:
        V, p = f["/mesh/vertices"][()], f["/contact/pressure"][()]
        F = float(np.linalg.norm(f["/contact/forces/table"][()]))
    r = np.hypot(V[:, 0], V[:, 1])

    def fit(within):
        sel = (p > 0) & (r < within) & (V[:, 2] < 0.5 * R)
        slope, c0 = np.polyfit(r[sel] ** 2, p[sel] ** 2, 1)
        return math.sqrt(-c0 / slope), math.sqrt(c0), int(sel.sum())
    a, _, _ = fit(1e9)
    a, p0, n = fit(0.8 * a)
    ah = (3 * F * R / (4 * E / (1 - nu * nu))) ** (1 / 3)
    return F, a, p0, ah, 3 * F / (2 * math.pi * ah * ah), n


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--driver", default="build/bin/hssbem")
    ap.add_argument("--mesh", required=True, help="a Hertz hemisphere (scripts/gen_meshes.py --hertz-size)")
    ap.add_argument("--delta", type=float, default=0.01, help="push of the flat face")
    ap.add_argument("--reach", type=float, default=0.005, help="-contact_reach: candidates within this gap")
    ap.add_argument("--repeat", type=int, default=1, help="runs of each (medians)")
    ap.add_argument("--workdir", default="out/bench/contact_h2")
    ap.add_argument("--csv", help="append one row per case")
    ap.add_argument("--extra", default="", help="more driver options for the contact run")
    args = ap.parse_args()
    os.makedirs(args.workdir, exist_ok=True)
    E, nu, R = 1000.0, 0.3, 1.0
    base = {"mesh": os.path.abspath(args.mesh), "material": {"E": E, "nu": nu},
            "boundary": [{"where": {"region": "flat"}, "displacement": [0, 0, -args.delta]}]}
    plain, contact = os.path.join(args.workdir, "plain.json"), os.path.join(args.workdir, "contact.json")
    with open(plain, "w") as f:
        json.dump(base, f)
    with open(contact, "w") as f:
        json.dump(dict(base, contact={"obstacles": [{"name": "table", "plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}}]}), f)
    copt = ["-bem_mat_type", "h2", "-contact_reach", str(args.reach)] + args.extra.split()
    tp, tc, cp, cc = [], [], [], []
    for k in range(args.repeat):
        w, c, _ = run(args.driver, plain, ["-bem_mat_type", "h2"], os.path.join(args.workdir, "plain_%d.log" % k))
        tp.append(w), cp.append(c)
        w, c, out = run(args.driver, contact, copt, os.path.join(args.workdir, "contact_%d.log" % k))
        tc.append(w), cc.append(c)
        print("run %d: plain %.1f s (CPU %.1f s), contact %.1f s (CPU %.1f s); load %.1f" % (k, tp[-1], cp[-1], tc[-1], cc[-1], os.getloadavg()[0]), flush=True)
    print(out)
    result = os.path.join(args.workdir, "contact.h5")
    run(args.driver, contact, copt + ["-o", result], os.path.join(args.workdir, "contact_out.log"))
    F, a, p0, ah, p0h, n = hertz_fit(result, R, E, nu)
    unknowns = re.search(r"(\d+) unknowns", out)
    mp, mc, mpc, mcc = statistics.median(tp), statistics.median(tc), statistics.median(cp), statistics.median(cc)
    print("plain H2 solve %.1f s (CPU %.1f s) | contact on H2 %.1f s (CPU %.1f s) | ratio %.2f wall, %.2f CPU (target <= 5)" % (mp, mpc, mc, mcc, mc / mp, mcc / mpc))
    print("Hertz: F = %.4g; a = %.4g (Hertz %.4g, %+.2f %%), p0 = %.4g (Hertz %.4g, %+.2f %%) from %d vertices"
          % (F, a, ah, 100 * (a / ah - 1), p0, p0h, 100 * (p0 / p0h - 1), n))
    if args.csv:
        new = not os.path.exists(args.csv)
        with open(args.csv, "a", newline="") as f:
            w = csv.writer(f)
            if new:
                w.writerow(["mesh", "unknowns", "delta", "reach", "repeat", "plain_s", "contact_s", "ratio", "plain_cpu_s", "contact_cpu_s", "cpu_ratio",
                            "force", "a", "a_hertz", "p0", "p0_hertz", "load"])
            w.writerow([os.path.basename(args.mesh), unknowns.group(1) if unknowns else "", args.delta, args.reach, args.repeat, "%.2f" % mp, "%.2f" % mc,
                        "%.3f" % (mc / mp), "%.2f" % mpc, "%.2f" % mcc, "%.3f" % (mcc / mpc), "%.5g" % F, "%.5g" % a, "%.5g" % ah, "%.5g" % p0, "%.5g" % p0h, "%.1f" % os.getloadavg()[0]])


if __name__ == "__main__":
    main()
