#!/usr/bin/python3
"""Scaling benchmark of the dense hssbem path: unit sphere under uniform pressure.

For each sphere size and MPI rank count this script generates the mesh (scripts/gen_meshes.py),
writes a problem file (sphere under external pressure 100, E 1000, nu 0.3, no interior points), runs

    mpirun -n P --bind-to none hssbem -problem sphere_T<T>.json -o sphere_T<T>_p<P>.h5 [PETSc options]

with OPENBLAS_NUM_THREADS = OMP_NUM_THREADS = threads per rank (default: cores // P), and reads the
phase timings from the result file's /timings group:

    assembly  /timings/assembly  (collocation matrix and right-hand side, rank 0's wall clock)
    LU        /timings/solve     (KSP preonly + LU: conversion to the factor format, factorization,
                                  triangular solves and the residual check, rank 0's wall clock)
    total     wall clock of the whole mpirun command (MPI start-up, mesh, setup, ..., output)

The displacement error is measured against the exact solution u = -p (1 - 2 nu) x / E after removing
the least-squares rigid motion (translation + rotation about the vertex centroid) of u - u_exact.
Peak memory: `RSS/rank` is the largest peak RSS of any single process of the run (exact: the
ru_maxrss that wait4 returns for mpirun is the maximum over the waited-for process tree, not a sum);
`RSS sum` is the sum over the ranks of their VmHWM polled from /proc every 0.05 s (a lower bound,
normally exact as the peak is held through the LU; with one rank it is the wait4 value).

Uses numpy and h5py (matplotlib for --plot): run with Debian's /usr/bin/python3.

Examples
  benchmarks/bench_dense.py --hssbem build/bin/hssbem --quick
  benchmarks/bench_dense.py --hssbem BIN --csv out/bench/dense.csv --plot out/bench/dense.png
  benchmarks/bench_dense.py --hssbem BIN --sizes 3000,6000 --ranks 1 --repeat 3 --threads 1
"""

import argparse
import datetime
import json
import math
import os
import platform
import shlex
import shutil
import signal
import subprocess
import sys
import threading
import time

import numpy as np

from bench_common import available_cores, cpu_model, parse_int_list, tail, triangles_for_unknowns

try:
    import h5py
except ImportError:  # pragma: no cover
    sys.exit("bench_dense.py: cannot import h5py; run it with /usr/bin/python3 (Debian python3-h5py)")

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
GEN_MESHES = os.path.join(REPO, "scripts", "gen_meshes.py")
DEFAULT_SIZES = (1500, 3000, 6000, 9000, 12000, 15000)  # target unknowns 3 (T/2 + 2)

PRESSURE, YOUNG, POISSON = 100.0, 1000.0, 0.3


# ------------------------------------------------------------------------------------------------
# helpers


def parse_threads(text, ranks, cores):
    """'auto' (cores // P), 'T' (all rank counts) or 'P:T,P:T' -> {P: T}."""
    out = {p: max(1, cores // p) for p in ranks}
    if text is None or text == "auto":
        return out
    try:
        if ":" in text:
            for item in text.split(","):
                p, t = item.split(":")
                out[int(p)] = int(t)
        else:
            out = {p: int(text) for p in ranks}
    except ValueError:
        raise SystemExit(f"bench_dense.py: error: --threads: expected 'auto', T or P:T[,P:T], got {text!r}")
    if any(t <= 0 for t in out.values()):
        raise SystemExit("bench_dense.py: error: --threads must be positive")
    return out


def git_revision():
    try:
        rev = subprocess.run(["git", "-C", REPO, "rev-parse", "--short", "HEAD"], capture_output=True,
                             text=True, timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "-C", REPO, "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=10).stdout.strip()
        return (rev or "unknown") + (" (+ uncommitted changes)" if dirty else "")
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def as_str(v):
    if isinstance(v, bytes):
        return v.decode(errors="replace")
    if isinstance(v, np.ndarray) and v.shape == ():
        return as_str(v[()])
    return str(v)


# ------------------------------------------------------------------------------------------------
# memory: poll the process tree below mpirun


def _children_map():
    kids = {}
    for name in os.listdir("/proc"):
        if not name.isdigit():
            continue
        try:
            with open(f"/proc/{name}/stat") as f:
                s = f.read()
        except OSError:
            continue
        # comm may contain spaces/parentheses: the fields after the last ')' are fixed
        rest = s[s.rfind(")") + 2:].split()
        kids.setdefault(int(rest[1]), []).append(int(name))
    return kids


def _vm_hwm_kib(pid):
    try:
        with open(f"/proc/{pid}/status") as f:
            name, hwm = "", None
            for line in f:
                if line.startswith("Name:"):
                    name = line.split()[1]
                elif line.startswith("VmHWM:"):
                    hwm = int(line.split()[1])
            return name, hwm
    except (OSError, ValueError, IndexError):
        return "", None


class TreePoller(threading.Thread):
    """Records the peak VmHWM of every process named like the solver below root_pid: the process
    tree is rescanned every `rescan` s until `expect` solver processes were found; the known ones
    are polled every `interval` s."""

    def __init__(self, root_pid, exe_name, expect, interval=0.05, rescan=0.5):
        super().__init__(daemon=True)
        self.root, self.exe, self.expect = root_pid, exe_name[:15], expect
        self.interval, self.rescan = interval, rescan
        self.peak = {}  # pid -> max VmHWM (KiB)
        self.stop = threading.Event()

    def _scan(self):
        kids = _children_map()
        todo, seen = [self.root], set()
        while todo:
            p = todo.pop()
            if p in seen:
                continue
            seen.add(p)
            todo.extend(kids.get(p, ()))
            if p != self.root and p not in self.peak:
                name, hwm = _vm_hwm_kib(p)
                if hwm is not None and name == self.exe:
                    self.peak[p] = hwm

    def run(self):
        last_scan = -1e30
        while not self.stop.is_set():
            now = time.monotonic()
            if len(self.peak) < self.expect and now - last_scan >= self.rescan:
                self._scan()
                last_scan = now
            for p in list(self.peak):
                _, hwm = _vm_hwm_kib(p)
                if hwm is not None:
                    self.peak[p] = max(self.peak[p], hwm)
            self.stop.wait(self.interval)

    def sum_mib(self):
        return sum(self.peak.values()) / 1024.0 if self.peak else float("nan")


# ------------------------------------------------------------------------------------------------
# machine load: other work on the same cores distorts the timings


def busy_cpu_seconds():
    """Busy CPU seconds of the whole machine so far (all cores; /proc/stat)."""
    with open("/proc/stat") as f:
        v = [int(x) for x in f.readline().split()[1:]]
    # user nice system idle iowait irq softirq steal (guest is included in user)
    busy = v[0] + v[1] + v[2] + v[5] + v[6] + (v[7] if len(v) > 7 else 0)
    return busy / os.sysconf("SC_CLK_TCK")


def wait_until_idle(max_wait, threshold=0.25, window=2.0):
    """Wait (up to max_wait s) until the machine's busy CPU over `window` s is below threshold
    cores; returns (waited seconds, last busy cores)."""
    t0 = time.monotonic()
    while True:
        b0 = busy_cpu_seconds()
        time.sleep(window)
        load = (busy_cpu_seconds() - b0) / window
        waited = time.monotonic() - t0
        if load < threshold or waited >= max_wait:
            return waited, load


# ------------------------------------------------------------------------------------------------
# one run


def rigid_free_error(x, u, p=PRESSURE, E=YOUNG, nu=POISSON):
    """Relative l2 and max errors of u vs u_exact = -p (1-2nu) x / E after subtracting the least-
    squares rigid motion a + w x (x - c) of the difference (c = vertex centroid)."""
    uex = -p * (1.0 - 2.0 * nu) / E * x
    d = u - uex
    r = x - x.mean(axis=0)
    n = len(x)
    A = np.zeros((n, 3, 6))
    A[:, :, :3] = np.eye(3)
    # w x r = -[r]_x w
    A[:, 0, 4], A[:, 0, 5] = r[:, 2], -r[:, 1]
    A[:, 1, 3], A[:, 1, 5] = -r[:, 2], r[:, 0]
    A[:, 2, 3], A[:, 2, 4] = r[:, 1], -r[:, 0]
    A = A.reshape(3 * n, 6)
    coef, *_ = np.linalg.lstsq(A, d.ravel(), rcond=None)
    e = (d.ravel() - A @ coef).reshape(n, 3)
    rel_l2 = np.linalg.norm(e) / np.linalg.norm(uex)
    rel_max = np.linalg.norm(e, axis=1).max() / np.linalg.norm(uex, axis=1).max()
    return float(rel_l2), float(rel_max)


def read_result(h5):
    with h5py.File(h5, "r") as f:
        t = f["timings"].attrs
        res = {
            "setup_s": float(t["setup"]), "assembly_s": float(t["assembly"]),
            "lu_s": float(t["solve"]), "post_s": float(t["post"]),
            "unknowns": int(f.attrs["num_dofs"]), "ranks_file": int(f.attrs["ranks"]),
            "solver": as_str(f.attrs.get("mat_solver_type", "")) or "-",
            "residual": float(f.attrs["residual"]),
        }
        x = np.asarray(f["mesh/vertices"], float)
        u = np.asarray(f["fields/displacement"], float)
    res["vertices"] = len(x)
    res["rel_err"], res["rel_err_max"] = rigid_free_error(x, u)
    return res


def run_once(args, exe, problem, h5, log, ranks, threads):
    """One mpirun; returns (result dict, None) or (None, error text)."""
    if os.path.exists(h5):
        os.remove(h5)
    env = dict(os.environ, OPENBLAS_NUM_THREADS=str(threads), OMP_NUM_THREADS=str(threads))
    cmd = [args.mpirun, "-n", str(ranks), "--bind-to", "none", exe, "-problem", problem, "-o", h5]
    cmd += shlex.split(args.petsc)
    err = log[:-4] + ".err"
    with open(log, "w") as fo, open(err, "w") as fe:
        fo.write("$ " + " ".join(shlex.quote(c) for c in cmd) + "\n")
        fo.flush()
        busy0 = busy_cpu_seconds()
        t0 = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=fo, stderr=fe, env=env, cwd=os.path.dirname(h5),
                                start_new_session=True)
        poller = TreePoller(proc.pid, os.path.basename(exe), ranks)
        poller.start()
        timed_out = False
        if args.timeout:
            def _kill():
                nonlocal timed_out
                timed_out = True
                try:
                    os.killpg(proc.pid, signal.SIGKILL)  # our own session only
                except ProcessLookupError:
                    pass
            timer = threading.Timer(args.timeout, _kill)
            timer.start()
        _, status, ru = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
        busy = busy_cpu_seconds() - busy0
        proc.returncode = os.waitstatus_to_exitcode(status)
        if args.timeout:
            timer.cancel()
        poller.stop.set()
        poller.join()
    rc = proc.returncode
    if timed_out:
        return None, f"timed out after {args.timeout:g} s (killed)\n" + tail(err, width=300) + tail(log, width=300)
    if rc != 0:
        msg = f"mpirun exited with status {rc}\n--- stderr ({err}) ---\n{tail(err, width=300)}--- stdout ({log}) ---\n{tail(log, width=300)}"
        if os.geteuid() == 0 and "run as root" in tail(err, 200, 10000):
            msg += "hint: as root set OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1\n"
        return None, msg
    try:
        res = read_result(h5)
    except (OSError, KeyError, ValueError) as e:
        return None, f"cannot read {h5}: {e}\n--- stderr ---\n{tail(err, width=300)}--- stdout ---\n{tail(log, width=300)}"
    if res["ranks_file"] != ranks:
        return None, f"{h5} says ranks = {res['ranks_file']}, expected {ranks}"
    res["total_s"] = wall
    own = ru.ru_utime + ru.ru_stime  # CPU of mpirun and the ranks
    res["cpu_s"] = own
    res["other_cores"] = max(0.0, (busy - own) / wall)  # average cores busy with anything else
    res["rss_rank_mib"] = ru.ru_maxrss / 1024.0  # KiB on Linux; max over the waited-for tree
    # the polled sum is only meaningful if every rank was seen; with one rank the exact wait4 value
    if ranks == 1:
        res["rss_sum_mib"] = res["rss_rank_mib"]
    else:
        res["rss_sum_mib"] = poller.sum_mib() if len(poller.peak) == ranks else float("nan")
    return res, None


# ------------------------------------------------------------------------------------------------
# mesh + problem


def make_mesh(tri, workdir, remesh):
    msh = os.path.join(workdir, f"sphere_T{tri}.msh")
    if os.path.exists(msh) and not remesh:
        return msh, None
    tmp = os.path.join(workdir, f".sphere_T{tri}.tmp.msh")
    cmd = [sys.executable, GEN_MESHES, "--sphere-triangles", str(tri), "--out", tmp]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0 or not os.path.exists(tmp):
        return None, f"mesh generation failed (status {p.returncode}): {' '.join(cmd)}\n{p.stdout[-2000:]}{p.stderr[-3000:]}"
    os.replace(tmp, msh)
    return msh, None


def write_problem(msh):
    path = msh[:-4] + ".json"
    spec = {
        "mesh": os.path.basename(msh),  # relative to the problem file
        "material": {"E": YOUNG, "nu": POISSON},
        "boundary": [{"where": "all", "pressure": PRESSURE}],
        "output": os.path.basename(msh)[:-4] + ".h5",
    }
    with open(path, "w") as f:
        json.dump(spec, f, indent=2)
        f.write("\n")
    return path


# ------------------------------------------------------------------------------------------------
# report


COLUMNS = [  # (csv name, table header, width, format)
    ("unknowns", "N", 7, "{:d}"),
    ("ranks", "ranks", 5, "{:d}"),
    ("threads", "thr", 3, "{:d}"),
    ("assembly_s", "assembly s", 10, "{:.3f}"),
    ("lu_s", "LU s", 9, "{:.3f}"),
    ("total_s", "total s", 9, "{:.3f}"),
    ("solver", "solver", 9, "{}"),
    ("rel_err", "rel err", 9, "{:.3e}"),
    ("rss_rank_mib", "RSS/rank MiB", 12, "{:.0f}"),
    ("rss_sum_mib", "RSS sum MiB", 11, "{:.0f}"),
    ("other_cores", "other", 5, "{:.2f}"),
]
CSV_EXTRA = ["triangles", "vertices", "setup_s", "post_s", "cpu_s", "residual", "rel_err_max", "repeats",
             "disturbed", "status"]


def fmt_row(r):
    cells = []
    for key, _, w, f in COLUMNS:
        v = r.get(key)
        if v is None or (isinstance(v, float) and math.isnan(v)):
            s = "-"
        else:
            s = f.format(v)
        cells.append(s.rjust(w))
    line = "  ".join(cells)
    if r.get("status", "ok") != "ok":
        line += "  " + r["status"]
    return line


def header_line():
    return "  ".join(h.rjust(w) for _, h, w, _ in COLUMNS)


def slope(rows, key, fit_min):
    pts = [(r["unknowns"], r[key]) for r in rows if r.get("status") == "ok" and r.get(key, 0) > 0]
    use = [p for p in pts if p[0] >= fit_min]
    note = f"N >= {fit_min}"
    if len({n for n, _ in use}) < 2:
        use, note = pts, "all sizes (fewer than 2 sizes >= %d)" % fit_min
    if len({n for n, _ in use}) < 2:
        return None, note, 0
    n, t = np.log([p[0] for p in use]), np.log([p[1] for p in use])
    return float(np.polyfit(n, t, 1)[0]), note, len(use)


RUN_KEYS = ["triangles", "unknowns", "ranks", "threads", "run", "setup_s", "assembly_s", "lu_s", "post_s",
            "total_s", "cpu_s", "other_cores", "rss_rank_mib", "rss_sum_mib", "solver", "residual", "rel_err",
            "rel_err_max", "status"]


def write_csv(path, rows, keys=None):
    import csv
    keys = keys or [c[0] for c in COLUMNS] + CSV_EXTRA
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(keys)
        for r in rows:
            out = []
            for k in keys:
                v = r.get(k)
                if v is None or (isinstance(v, float) and math.isnan(v)):
                    out.append("")
                elif isinstance(v, float):
                    out.append(f"{v:.6g}")
                else:
                    out.append(str(v))
            w.writerow(out)


def plot(path, rows, ranks, threads):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 5.5))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    nall = []
    last = {}
    any_bad = False
    for i, p in enumerate(ranks):
        ok = sorted((r for r in rows if r["ranks"] == p and r.get("status") == "ok"), key=lambda r: r["unknowns"])
        if not ok:
            continue
        n = np.array([r["unknowns"] for r in ok], float)
        nall.extend(n)
        c = colors[i % len(colors)]
        ta = np.array([r["assembly_s"] for r in ok])
        tl = np.array([r["lu_s"] for r in ok])
        ax.loglog(n, ta, "o-", color=c, label=f"assembly, {p} rank{'s' if p > 1 else ''} x {threads[p]} thr")
        ax.loglog(n, tl, "s--", color=c, label=f"LU, {p} rank{'s' if p > 1 else ''} x {threads[p]} thr")
        bad = np.array([bool(r.get("disturbed")) for r in ok])
        if bad.any():  # disturbed points: white-filled markers on top
            kw = dict(linestyle="none", markerfacecolor="white", markeredgecolor=c)
            ax.loglog(n[bad], ta[bad], "o", **kw)
            ax.loglog(n[bad], tl[bad], "s", **kw)
            any_bad = True
        last.setdefault("assembly", (n[-1], ta[-1]))
        last.setdefault("lu", (n[-1], tl[-1]))
    if nall:
        ng = np.geomspace(min(nall), max(nall), 50)
        if "assembly" in last:
            n0, t0 = last["assembly"]
            ax.loglog(ng, t0 * (ng / n0) ** 2, ":", color="0.45", lw=1.2, label=r"$\propto N^2$")
        if "lu" in last:
            n0, t0 = last["lu"]
            ax.loglog(ng, t0 * (ng / n0) ** 3, "-.", color="0.45", lw=1.2, label=r"$\propto N^3$")
    if any_bad:
        ax.plot([], [], "o", color="0.3", markerfacecolor="white", linestyle="none",
                label="open marker: disturbed by other load")
    ax.set_xlabel("unknowns N")
    ax.set_ylabel("wall time [s]")
    ax.set_title("hssbem dense path: unit sphere under pressure")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    fig.savefig(path, dpi=130)
    plt.close(fig)


# ------------------------------------------------------------------------------------------------


def main(argv=None):
    ap = argparse.ArgumentParser(
        description="Dense hssbem scaling benchmark (unit sphere under pressure): assembly and LU "
                    "time vs unknowns and MPI ranks.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    ap.add_argument("--hssbem", default=os.environ.get("HSSBEM", os.path.join(REPO, "build", "bin", "hssbem")),
                    help="solver binary (default: $HSSBEM or <repo>/build/bin/hssbem)")
    ap.add_argument("--mpirun", default="mpirun", help="MPI launcher")
    ap.add_argument("--sizes", type=lambda s: parse_int_list(s, "--sizes"), default=list(DEFAULT_SIZES),
                    help="target unknown counts 3 (T/2 + 2), comma-separated")
    ap.add_argument("--triangles", type=lambda s: parse_int_list(s, "--triangles"), default=None,
                    help="sphere triangle counts instead of --sizes")
    ap.add_argument("--ranks", type=lambda s: parse_int_list(s, "--ranks"), default=[1, 2],
                    help="MPI rank counts, comma-separated")
    ap.add_argument("--threads", default="auto",
                    help="BLAS threads per rank: 'auto' (cores // ranks), T, or P:T[,P:T]; sets "
                         "OPENBLAS_NUM_THREADS and OMP_NUM_THREADS")
    ap.add_argument("--repeat", type=int, default=1, help="runs per case; each time is the min over them")
    ap.add_argument("--quick", action="store_true", help="only the two smallest sizes (script check)")
    ap.add_argument("--workdir", default="out/bench", help="meshes, problem files, results, logs")
    ap.add_argument("--csv", default=None, help="write the table as CSV (default: WORKDIR/dense.csv)")
    ap.add_argument("--plot", default=None, help="write a log-log plot (PNG) of assembly and LU time vs N")
    ap.add_argument("--fit-min", type=int, default=2700,
                    help="fit the log-log slopes over sizes with N >= this (the nominal 3k size and up)")
    ap.add_argument("--petsc", default="", help="extra PETSc/hssbem options, one quoted string")
    ap.add_argument("--timeout", type=float, default=0, help="kill a run after this many seconds (0: never)")
    ap.add_argument("--wait-idle", type=float, default=0, metavar="SECONDS",
                    help="before each run wait up to this long for the machine to be idle (other "
                         "processes using < 0.25 cores over 2 s); 0: do not wait")
    ap.add_argument("--max-other", type=float, default=0.1, metavar="CORES",
                    help="a case whose fastest run saw other processes using more than this many cores "
                         "on average is marked (disturbed)")
    ap.add_argument("--retry-busy", type=int, default=0, metavar="N",
                    help="up to N extra runs per case while its fastest run is disturbed")
    ap.add_argument("--remesh", action="store_true", help="regenerate meshes that already exist in WORKDIR")
    args = ap.parse_args(argv)
    if args.repeat < 1:
        ap.error("--repeat must be >= 1")
    if args.retry_busy < 0:
        ap.error("--retry-busy must be >= 0")

    exe = os.path.abspath(args.hssbem)
    if not (os.path.isfile(exe) and os.access(exe, os.X_OK)):
        ap.error(f"solver binary not found or not executable: {exe} (give --hssbem)")
    if shutil.which(args.mpirun) is None:
        ap.error(f"MPI launcher not found: {args.mpirun}")
    workdir = os.path.abspath(args.workdir)
    os.makedirs(workdir, exist_ok=True)
    csv_path = args.csv or os.path.join(workdir, "dense.csv")

    tris = args.triangles or [triangles_for_unknowns(n) for n in args.sizes]
    tris = sorted(set(tris))
    if args.quick:
        tris = tris[:2]
    ranks = sorted(set(args.ranks))
    cores = available_cores()
    threads = parse_threads(args.threads, ranks, cores)

    print("# hssbem dense benchmark: unit sphere, uniform pressure %g, E %g, nu %g" % (PRESSURE, YOUNG, POISSON))
    print(f"# date {datetime.datetime.now().isoformat(timespec='seconds')}, host {platform.node()}, "
          f"{cpu_model()}, {cores} cores, {os.sysconf('SC_PAGE_SIZE') * os.sysconf('SC_PHYS_PAGES') / 2**30:.1f} GiB")
    print(f"# binary {exe} (built {time.strftime('%Y-%m-%d %H:%M', time.localtime(os.path.getmtime(exe)))}), repo HEAD now {git_revision()}")
    print(f"# launch: {args.mpirun} -n P --bind-to none hssbem -problem ... -o ... {args.petsc}".rstrip())
    print("# threads per rank (OPENBLAS_NUM_THREADS = OMP_NUM_THREADS): "
          + ", ".join(f"P={p}: {threads[p]}" for p in ranks))
    print(f"# sphere triangles: {', '.join(map(str, tris))}; repeats {args.repeat} (each time column = min)")
    print("# assembly = /timings/assembly, LU = /timings/solve (factor-format conversion + LU + solve + "
          "residual), total = mpirun wall clock; rel err = ||u - u_ex - rigid||_2 / ||u_ex||_2")
    print("# RSS/rank = max peak RSS of one process (wait4); RSS sum = sum of the ranks' VmHWM (polled /proc)")
    print("# other = average number of cores busy with other processes during the run (/proc/stat minus "
          f"the run's own CPU time); > {args.max_other:g}: marked (disturbed)")
    if args.retry_busy > 0:
        print(f"# up to {args.retry_busy} extra runs per case while its fastest run has other > {args.max_other:g}")
    if args.wait_idle > 0:
        print(f"# before each run: wait up to {args.wait_idle:g} s for the machine to be idle")
    print(header_line())
    sys.stdout.flush()

    rows, failures, runs = [], [], []
    for tri in tris:
        msh, err = make_mesh(tri, workdir, args.remesh)
        problem = write_problem(msh) if msh else None
        for p in ranks:
            row = {"triangles": tri, "ranks": p, "threads": threads[p], "repeats": args.repeat,
                   "unknowns": 3 * (tri // 2 + 2), "status": "ok"}
            if err:
                row["status"] = "FAILED (mesh)"
                failures.append((tri, p, err))
                rows.append(row)
                print(fmt_row(row))
                print("    " + err.rstrip().replace("\n", "\n    "))
                sys.stdout.flush()
                continue
            results = []
            k, extra = 0, 0
            while True:
                if k >= args.repeat:
                    best = min(results, key=lambda r: r["total_s"])
                    if best["other_cores"] <= args.max_other or extra >= args.retry_busy:
                        break
                    extra += 1
                    print(f"#   note: T={tri} P={p}: other processes used {best['other_cores']:.2f} cores during "
                          f"the fastest run; extra run {extra}/{args.retry_busy}")
                    sys.stdout.flush()
                h5 = os.path.join(workdir, f"sphere_T{tri}_p{p}.h5")
                log = os.path.join(workdir, f"sphere_T{tri}_p{p}_r{k}.log")
                if args.wait_idle > 0:
                    waited, load = wait_until_idle(args.wait_idle)
                    if load >= 0.25:
                        print(f"#   note: machine still busy ({load:.2f} cores) after waiting {waited:.0f} s; "
                              f"running T={tri} P={p} anyway")
                        sys.stdout.flush()
                res, rerr = run_once(args, exe, problem, h5, log, p, threads[p])
                k += 1
                runs.append(dict(res or {}, triangles=tri, ranks=p, threads=threads[p], run=k,
                                 status="ok" if res else "FAILED"))
                if rerr:
                    row["status"] = f"FAILED (run {k})"
                    failures.append((tri, p, rerr))
                    print(fmt_row(row))
                    print("    " + rerr.rstrip().replace("\n", "\n    "))
                    sys.stdout.flush()
                    results = []
                    break
                results.append(res)
            if results:
                last = results[-1]
                row.update({k: last[k] for k in ("unknowns", "vertices", "solver", "residual", "rel_err", "rel_err_max")})
                for k in ("setup_s", "assembly_s", "lu_s", "post_s", "total_s", "cpu_s"):
                    row[k] = min(r[k] for r in results)
                # the load seen by the fastest repeat
                row["other_cores"] = min(results, key=lambda r: r["total_s"])["other_cores"]
                row["rss_rank_mib"] = max(r["rss_rank_mib"] for r in results)
                sums = [r["rss_sum_mib"] for r in results if not math.isnan(r["rss_sum_mib"])]
                row["rss_sum_mib"] = max(sums) if sums else float("nan")
                row["repeats"] = len(results)
                row["disturbed"] = int(row["other_cores"] > args.max_other)
                print(fmt_row(row) + ("  (disturbed)" if row["disturbed"] else ""))
                sys.stdout.flush()
            rows.append(row)

    print()
    print("# log-log slopes of time vs N (least squares):")
    for p in ranks:
        pr = [r for r in rows if r["ranks"] == p]
        parts = []
        for key, name in (("assembly_s", "assembly"), ("lu_s", "LU")):
            s, note, m = slope(pr, key, args.fit_min)
            parts.append(f"{name} {s:.2f}" if s is not None else f"{name} n/a")
        nd = sum(1 for r in pr if r.get("disturbed") and r["unknowns"] >= (args.fit_min if "all" not in note else 0))
        dist = f"; {nd} disturbed point{'s' if nd != 1 else ''} included" if nd else ""
        print(f"#   ranks {p}: " + ", ".join(parts) + f"   ({note}{dist}; expected about 2 and 3)")

    write_csv(csv_path, rows)
    runs_path = os.path.splitext(csv_path)[0] + "_runs.csv"
    write_csv(runs_path, runs, RUN_KEYS)
    print(f"# table written to {csv_path} (every single run: {runs_path})")
    if args.plot and not any(r.get("status") == "ok" for r in rows):
        print("# plot skipped: no successful run")
    elif args.plot:
        try:
            plot(args.plot, rows, ranks, threads)
            print(f"# plot written to {args.plot}")
        except Exception as e:  # plotting must not hide the measurements
            failures.append(("plot", "-", f"{type(e).__name__}: {e}"))
            print(f"# plot FAILED: {type(e).__name__}: {e}")

    if failures:
        print(f"# {len(failures)} FAILURE(S): " + "; ".join(f"T={t} P={p}" for t, p, _ in failures))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
