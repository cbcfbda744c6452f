#!/usr/bin/python3
"""Scaling benchmark of the HSS direct solver, or of H² + GMRES, against dense assembly + LU
(drives bench_hss or bench_h2).

For every mesh family (unit sphere, disk organ) and every target number of unknowns N this script

  1. generates the surface mesh with scripts/gen_meshes.py (--sphere-triangles T or
     --disk-triangles T, T = 2 (N/3 - 2) triangles) into the mesh cache directory, or reuses the
     cached file when it is already there;
  2. runs the C++ benchmark program of the chosen --solver: bench_hss (benchmarks/bench_hss.cpp:
     HSS compression, ULV factorization and solve) or bench_h2 (benchmarks/bench_h2.cpp: H²
     compression, GMRES(100) + Jacobi with the H² product; its "factor" time is 0)

         bench_hss|bench_h2 --mesh FILE --tol TOL [--leaf L] --dense 0|1 [EXTRA ARGS]

     as a subprocess (with --dense 1 only up to --dense-max unknowns), with a per-run timeout;
  3. appends the single CSV line it prints on stdout, preceded by a `family` column, to the CSV
     file, and saves its stderr (ranks per HSS level, compression time breakdown) in
     <csv stem>_logs/<mesh stem>_<tol>.log.

A run that fails or times out is reported (with the tail of its log) and the sweep goes on. At the
end one markdown table per family is printed (dense and HSS times, speed-up, ranks, memory,
difference to the dense solution), followed by the log-log least-squares slopes of HSS setup
time (compress + factor), solve time and max rank against N, and the ranks per HSS level read
back from the logs. --plot draws the times and ranks against N on log-log axes.

--from-csv FILE skips all runs and only prints the tables and slopes (and plots) of an existing
CSV file.

Uses numpy (and matplotlib for --plot); gen_meshes.py needs gmsh: run with Debian's
/usr/bin/python3.

Examples
  benchmarks/bench_hss.py --bench build/bin/bench_hss --quick                # smoke test, minutes
  benchmarks/bench_hss.py --csv out/bench/hss.csv --plot out/bench/hss.png   # full sweep (hours)
  benchmarks/bench_hss.py --from-csv out/bench/hss.csv --plot out/bench/hss.png
  benchmarks/bench_hss.py --solver h2 --tol 1e-5 --extra "--single 1" --csv out/bench/h2.csv \
      --plot out/bench/h2.png                                                 # H², 3k .. 300k
"""

import argparse
import csv
import datetime
import math
import os
import platform
import shlex
import signal
import subprocess
import sys
import time

import numpy as np

from bench_common import available_cores, cpu_model, parse_int_list, tail, triangles_for_unknowns

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
GEN_MESHES = os.path.join(REPO, "scripts", "gen_meshes.py")

DEFAULT_SIZES = (3000, 6000, 10000, 20000, 40000, 80000, 150000, 300000)
QUICK_SIZES = (3000, 6000)

# Mesh families: name -> (gen_meshes.py option that takes a triangle count, mesh file prefix).
FAMILIES = {
    "sphere": ("--sphere-triangles", "sphere"),
    "disk": ("--disk-triangles", "disk"),
}

# Columns printed by `bench_hss --header`; the CSV written here has `family` in front of them.
BENCH_COLUMNS = ["mesh", "N", "tol", "leaf", "dense_assembly_s", "dense_lu_s", "compress_s",
                 "factor_s", "solve_s", "matvec_s", "max_row_rank", "max_col_rank", "top_front",
                 "hss_memory_mb", "factor_memory_mb", "peak_rss_mb", "rel_diff"]
# Columns only bench_h2 prints (nan for bench_hss rows).
H2_COLUMNS = ["iterations", "sample_err"]
CSV_COLUMNS = ["family", "solver"] + BENCH_COLUMNS + H2_COLUMNS

# Solvers: name -> benchmark program (default path).
SOLVERS = {"hss": "bench_hss", "h2": "bench_h2"}

# Default range of N over which the log-log slopes are fitted.
FIT_MIN, FIT_MAX = 10000, 300000


# ------------------------------------------------------------------------------------------------
# small helpers


def log(msg=""):
    """Progress output: stdout, flushed at once so it interleaves correctly with subprocesses."""
    print(msg, flush=True)


def parse_families(text):
    fams = [s for s in text.replace(" ", "").split(",") if s]
    bad = [f for f in fams if f not in FAMILIES]
    if not fams or bad:
        raise argparse.ArgumentTypeError(f"families are {', '.join(FAMILIES)}; got {text!r}")
    return fams


def tol_tag(tol):
    """Tolerance as the C++ program prints it (printf %.0e), e.g. 1e-06; used in log names."""
    return f"{tol:.0e}"


def to_float(text):
    """CSV field -> float; empty or unparsable fields (and the program's 'nan') give nan."""
    try:
        return float(text)
    except (TypeError, ValueError):
        return math.nan


def finite(x):
    return x is not None and not math.isnan(x) and not math.isinf(x)


def fmt_s(t):
    """Seconds with about three significant digits and no exponent; '–' for missing values."""
    if not finite(t):
        return "–"
    if t >= 100:
        return f"{t:.0f}"
    if t >= 10:
        return f"{t:.1f}"
    if t >= 1:
        return f"{t:.2f}"
    return f"{t:.3g}"


def fmt_ratio(x):
    """Speed-up factor: two significant digits below 10 (0.065, 3.4), integer above."""
    if not finite(x):
        return "–"
    return f"{x:.0f}" if x >= 10 else f"{x:.2g}"


def fmt_mb(m):
    return "–" if not finite(m) else (f"{m:.0f}" if m >= 10 else f"{m:.1f}")


def logs_dir_for(csv_path):
    """Run logs live next to the CSV: out/bench/hss.csv -> out/bench/hss_logs/."""
    return os.path.splitext(csv_path)[0] + "_logs"


def log_path_for(logs_dir, mesh_file, tol, leaf):
    """<logs>/<mesh stem>_<tol>.log, with _leaf<L> added when a leaf size was given explicitly."""
    stem = os.path.splitext(os.path.basename(mesh_file))[0]
    extra = f"_leaf{leaf}" if leaf is not None else ""
    return os.path.join(logs_dir, f"{stem}_{tol_tag(tol)}{extra}.log")


# ------------------------------------------------------------------------------------------------
# subprocesses


def run_command(cmd, timeout, stdout_path=None, stderr_path=None):
    """Run cmd in its own process group (so a timeout kills the whole group, and only it).

    stdout is captured and returned unless stdout_path is given; stderr goes to stderr_path, or is
    captured and returned. Returns (returncode or None on timeout, stdout text, stderr text,
    wall seconds). KeyboardInterrupt kills the group and is re-raised."""
    out_f = open(stdout_path, "w") if stdout_path else None
    err_f = open(stderr_path, "w") if stderr_path else None
    t0 = time.monotonic()
    try:
        proc = subprocess.Popen(cmd, stdout=out_f or subprocess.PIPE, stderr=err_f or subprocess.PIPE,
                                text=True, start_new_session=True)
        try:
            out, err = proc.communicate(timeout=timeout if timeout and timeout > 0 else None)
            rc = proc.returncode
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            out, err = proc.communicate()
            rc = None
        except KeyboardInterrupt:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
            raise
    finally:
        for f in (out_f, err_f):
            if f:
                f.close()
    return rc, out or "", err or "", time.monotonic() - t0


def ensure_mesh(family, triangles, mesh_dir, timeout):
    """Path of the cached mesh <mesh_dir>/<prefix>_T<T>.msh, generated first if it is missing.

    The generator writes to a temporary name that is renamed on success, so an interrupted or
    failed generation never leaves a file that would be taken for a cached mesh. Returns
    (path, None) or (None, error message)."""
    option, prefix = FAMILIES[family]
    path = os.path.join(mesh_dir, f"{prefix}_T{triangles}.msh")
    if os.path.isfile(path):
        return path, None
    os.makedirs(mesh_dir, exist_ok=True)
    tmp = os.path.join(mesh_dir, f"{prefix}_T{triangles}.tmp{os.getpid()}.msh")
    cmd = [sys.executable, GEN_MESHES, option, str(triangles), "--out", tmp]
    log(f"    generating {os.path.basename(path)}: {' '.join(shlex.quote(c) for c in cmd)}")
    try:
        rc, out, err, wall = run_command(cmd, timeout)
    except KeyboardInterrupt:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise
    if rc != 0 or not os.path.isfile(tmp):
        if os.path.exists(tmp):
            os.remove(tmp)
        why = "timed out" if rc is None else f"exit status {rc}"
        return None, f"mesh generation {why}:\n{(out + err)[-2000:]}"
    os.replace(tmp, path)
    log(f"    {out.strip().replace(os.path.basename(tmp), os.path.basename(path))}  ({wall:.1f} s)")
    return path, None


def bench_header(bench):
    """Columns that `bench_hss --header` prints; also checks that the binary runs at all."""
    rc, out, err, _ = run_command([bench, "--header"], 60)
    if rc != 0:
        sys.exit(f"bench_hss.py: `{bench} --header` failed (exit status {rc}):\n{err}")
    return out.strip().splitlines()[0].split(",")


def parse_bench_line(stdout, ncols):
    """The last stdout line with the expected number of comma-separated fields, or None."""
    for line in reversed(stdout.strip().splitlines()):
        fields = line.strip().split(",")
        if len(fields) == ncols:
            return fields
    return None


# ------------------------------------------------------------------------------------------------
# CSV


def open_csv(path, append):
    """Start the CSV (header row) unless appending to an existing file with the same columns.

    Without --append an existing file is kept as FILE.bak instead of being overwritten."""
    d = os.path.dirname(os.path.abspath(path))
    os.makedirs(d, exist_ok=True)
    if append and os.path.isfile(path) and os.path.getsize(path) > 0:
        with open(path, newline="") as f:
            head = next(csv.reader(f), [])
        if head != CSV_COLUMNS:
            sys.exit(f"bench_hss.py: --append: {path} has other columns than this script writes")
        return
    if os.path.isfile(path):
        os.replace(path, path + ".bak")
        log(f"# previous {path} kept as {path}.bak")
    with open(path, "w", newline="") as f:
        csv.writer(f).writerow(CSV_COLUMNS)


def append_csv(path, row):
    with open(path, "a", newline="") as f:
        csv.writer(f).writerow(row)


def read_csv(path):
    """Rows of a CSV written by this script as dicts: numbers converted to float (nan when
    missing); 'family', 'mesh' and 'tol' (as printed) stay strings."""
    rows = []
    with open(path, newline="") as f:
        for rec in csv.DictReader(f):
            if not rec.get("family"):
                continue
            row = {k: to_float(v) for k, v in rec.items() if k not in ("family", "solver", "mesh", "tol")}
            row["family"], row["mesh"], row["tol"] = rec["family"], rec["mesh"], rec["tol"]
            row["solver"] = rec.get("solver") or "hss"
            rows.append(row)
    return rows


# ------------------------------------------------------------------------------------------------
# report: tables, slopes, ranks per level


def derived(r):
    """Quantities of the summary table computed from one CSV row."""
    setup = r["compress_s"] + r["factor_s"]
    hss_total = setup + r["solve_s"]
    dense_total = r["dense_assembly_s"] + r["dense_lu_s"]
    return {
        "setup": setup,
        "hss_total": hss_total,
        "dense_total": dense_total,
        "speedup": dense_total / hss_total if finite(dense_total) and hss_total > 0 else math.nan,
        "max_rank": max(r["max_row_rank"], r["max_col_rank"]),
    }


def loglog_slope(points, lo, hi):
    """Least-squares slope of log y against log N over the points with lo <= N <= hi, give or take
    5 % (the meshes hit the target sizes only roughly: 9 969 for 10 000, 300 030 for 300 000).

    Points with a missing or non-positive y are ignored. Returns (slope, Nmin, Nmax, count); with
    fewer than two usable points in [lo, hi] all usable points are taken instead, and with fewer
    than two in total the slope is nan."""
    good = [(n, y) for n, y in points if finite(y) and y > 0]
    sel = [(n, y) for n, y in good if lo / 1.05 <= n <= hi * 1.05]
    if len(sel) < 2:
        sel = good
    if len(sel) < 2:
        return math.nan, math.nan, math.nan, len(sel)
    x = np.log([n for n, _ in sel])
    y = np.log([v for _, v in sel])
    slope = float(np.polyfit(x, y, 1)[0])
    return slope, min(n for n, _ in sel), max(n for n, _ in sel), len(sel)


def read_level_ranks(log_file):
    """[(level, clusters, max row rank, max col rank)] from a bench_hss stderr log."""
    levels = []
    try:
        with open(log_file, errors="replace") as f:
            for line in f:
                # level 3: 8 clusters, row rank max 120 mean 98, column rank max 131 mean 104
                if not line.startswith("level "):
                    continue
                try:
                    head, rest = line.split(":", 1)
                    words = rest.replace(",", " ").split()
                    lev = int(head.split()[1])
                    clusters = int(words[0])
                    row = int(words[words.index("row") + 3])
                    col = int(words[words.index("column") + 3])
                except (ValueError, IndexError):
                    continue
                levels.append((lev, clusters, row, col))
    except OSError:
        return None
    return levels


def group_rows(rows):
    """Rows grouped by (family, solver, tol, leaf), each sorted by N. For a repeated (family,
    solver, mesh, tol, leaf), e.g. from --append sweeps, the last row wins."""
    latest = {}
    for r in rows:
        latest[(r["family"], r["solver"], r["mesh"], r["tol"], r["leaf"])] = r
    groups = {}
    for r in latest.values():
        groups.setdefault((r["family"], r["solver"], r["tol"], r["leaf"]), []).append(r)
    order = list(FAMILIES)
    keys = sorted(groups, key=lambda k: (order.index(k[0]) if k[0] in order else len(order), k[0], k[1],
                                         to_float(k[2]), k[3]))
    return [(k, sorted(groups[k], key=lambda r: r["N"])) for k in keys]


def print_report(rows, logs_dir, fit_min, fit_max):
    """Markdown table, slopes and ranks per level for each (family, solver, tol, leaf) group."""
    if not rows:
        log("\n(no successful runs to report)")
        return
    for (family, solver, tol, leaf), grp in group_rows(rows):
        log(f"\n### {family}, {solver}: tol {tol}, leaf {leaf:.0f}\n")
        hdr = ["N", "dense s (asm + LU)", "compress s", "factor s", "solve s", "total s",
               "speed-up", "max rank r/c", "top front", "matrix + factor MB", "peak RSS MB", "rel_diff", "its",
               "sampled K err"]
        log("| " + " | ".join(hdr) + " |")
        log("|" + "|".join("---:" for _ in hdr) + "|")
        for r in grp:
            d = derived(r)
            dense = (f"{fmt_s(d['dense_total'])} ({fmt_s(r['dense_assembly_s'])} + {fmt_s(r['dense_lu_s'])})"
                     if finite(d["dense_total"]) else "–")
            mem = r["hss_memory_mb"] + r["factor_memory_mb"]
            cells = [f"{r['N']:.0f}", dense, fmt_s(r["compress_s"]), fmt_s(r["factor_s"]),
                     fmt_s(r["solve_s"]), fmt_s(d["hss_total"]),
                     fmt_ratio(d["speedup"]),
                     f"{r['max_row_rank']:.0f}/{r['max_col_rank']:.0f}",
                     f"{r['top_front']:.0f}" if finite(r["top_front"]) else "–",
                     f"{fmt_mb(mem)} ({fmt_mb(r['hss_memory_mb'])} + {fmt_mb(r['factor_memory_mb'])})",
                     fmt_mb(r["peak_rss_mb"]),
                     f"{r['rel_diff']:.2e}" if finite(r["rel_diff"]) else "–",
                     f"{r.get('iterations', math.nan):.0f}" if finite(r.get("iterations", math.nan)) else "–",
                     f"{r['sample_err']:.1e}" if finite(r.get("sample_err", math.nan)) else "–"]
            log("| " + " | ".join(cells) + " |")

        # log-log slopes
        log(f"\nlog-log slopes against N (least squares; fit range {fit_min} <= N <= {fit_max}):")
        series = [
            ("setup (compress + factor)", [(r["N"], derived(r)["setup"]) for r in grp], "1 to 1.5"),
            ("solve", [(r["N"], r["solve_s"]) for r in grp], "about 1"),
            ("max rank (row/col)", [(r["N"], derived(r)["max_rank"]) for r in grp], "about 0.5"),
            ("dense assembly + LU", [(r["N"], derived(r)["dense_total"]) for r in grp], "2 to 3"),
        ]
        for name, pts, expect in series:
            slope, n0, n1, cnt = loglog_slope(pts, fit_min, fit_max)
            if not finite(slope):
                if name.startswith("dense"):
                    continue  # fewer than two dense runs: nothing to say
                log(f"  {name:30s}  –     (fewer than two runs)")
                continue
            in_range = all(fit_min / 1.05 <= n <= fit_max * 1.05 for n in (n0, n1))
            note = "" if in_range else f"; fewer than two runs in [{fit_min}, {fit_max}], all runs used"
            log(f"  {name:30s} {slope:5.2f}   (N = {n0:.0f} .. {n1:.0f}, {cnt} runs{note}; "
                f"expected {expect})")

        # ranks per level from the saved logs (the root, level 0, has no rank and is left out)
        lines = []
        for r in grp:
            lf = log_path_for(logs_dir, r["mesh"], to_float(r["tol"]), int(r["leaf"]))
            if not os.path.isfile(lf):
                lf = log_path_for(logs_dir, r["mesh"], to_float(r["tol"]), None)
            lev = read_level_ranks(lf)
            if lev:
                lines.append(f"  N {r['N']:7.0f}:  " + "  ".join(f"L{lv} {row}/{col}" for lv, nc, row, col in lev
                                                             if nc > 0))
        if lines:
            log(f"\nmax row/column rank per {solver.upper()} level (L1 = the two children of the root), from the logs:")
            for line in lines:
                log(line)


# ------------------------------------------------------------------------------------------------
# plot


def plot(rows, path, fit_min=FIT_MIN, fit_max=FIT_MAX):
    """Log-log scaling plot. Left: wall time to a solution against N (HSS: compression +
    factorization + solve; H²: compression + GMRES), its set-up part, and dense assembly + LU
    where it was run.
    Right: memory against N (the compressed matrix plus its factorization, and the run's peak
    RSS), beside the dense matrix's 8 N² bytes. Each measured series is labelled with its fitted
    slope (fit range as in the report); grey lines are reference slopes."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    groups = group_rows(rows)
    if not groups:
        log("(nothing to plot)")
        return
    fig, (ax, axm) = plt.subplots(1, 2, figsize=(14, 7.5))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    label_tol = len({(k[1], k[2], k[3]) for k, _ in groups}) > len({k[1] for k, _ in groups})
    markers = {"sphere": "o", "disk": "s"}
    names = {"hss": "HSS direct", "h2": "H² + GMRES"}

    def slope_text(ns, ys):
        sl, _, _, cnt = loglog_slope(list(zip(ns, ys)), fit_min, fit_max)
        return f"slope {sl:.2f}" if finite(sl) and cnt >= 2 else "one point"

    def guide(axis, n_ref, y_ref, n_max, power, text):
        """Grey line y = y_ref (N / n_ref)^power from n_ref to n_max, labelled at its end."""
        ns = np.array([n_ref, n_max], float)
        axis.plot(ns, y_ref * (ns / n_ref) ** power, color="0.7", lw=1, ls="-", zorder=0)
        axis.annotate(text, (ns[-1], y_ref * (ns[-1] / n_ref) ** power), color="0.45",
                      fontsize=9, xytext=(3, 0), textcoords="offset points", va="center")

    all_n = [r["N"] for _, g in groups for r in g]
    n_lo, n_hi = min(all_n), max(all_n)
    dense_pts = {}
    ci = 0
    for (family, solver, tol, leaf), grp in groups:
        c = colors[ci % len(colors)]
        ci += 1
        mk = markers.get(family, "^")
        name = f"{family}, {names.get(solver, solver)}" + (f" (tol {tol}, leaf {leaf:.0f})" if label_tol else "")
        N = np.array([r["N"] for r in grp])
        total = np.array([derived(r)["hss_total"] for r in grp])
        mem = np.array([r["hss_memory_mb"] + (r["factor_memory_mb"] if finite(r["factor_memory_mb"]) else 0.0) for r in grp]) / 1024
        rss = np.array([r["peak_rss_mb"] for r in grp]) / 1024
        setup = np.array([derived(r)["setup"] for r in grp])
        ax.plot(N, total, mk + "-", color=c, label=f"{name}, total: {slope_text(N, total)}")
        ax.plot(N, setup, mk + ":", color=c, alpha=0.6, mfc="none",
                label=f"{name}, set-up ({'compression + factorization' if solver == 'hss' else 'compression'}): {slope_text(N, setup)}")
        what = "matrix + factorization" if solver == "hss" else "matrix"
        axm.plot(N, mem, mk + "-", color=c, label=f"{name}, {what}: {slope_text(N, mem)}")
        alone = ~np.isfinite(np.array([derived(r)["dense_total"] for r in grp]))  # a dense run in the same process sets its peak
        if alone.any():
            axm.plot(N[alone], rss[alone], mk + ":", color=c, alpha=0.6,
                     label=f"{name}, peak RSS (runs without dense): {slope_text(N[alone], rss[alone])}")
        for r in grp:
            d = derived(r)["dense_total"]
            if finite(d):
                dense_pts.setdefault(family, {})[r["N"]] = d
    for family, pts in dense_pts.items():
        ns = sorted(pts)
        ys = [pts[n] for n in ns]
        ax.plot(ns, ys, markers.get(family, "^") + "--", color="k", mfc="none",
                label=f"{family}, dense assembly + LU: {slope_text(ns, ys)}")
    nd = np.geomspace(n_lo, n_hi, 20)
    axm.plot(nd, 8.0 * nd ** 2 / 2 ** 30, "k--", label="dense matrix, 8 N² bytes: slope 2")
    axm.axhline(24, color="tab:red", lw=1, ls="-.")
    axm.annotate("24 GiB (this machine)", (n_lo, 24), color="tab:red", fontsize=9, xytext=(2, 3), textcoords="offset points")
    first_total = min(((g[0]["N"], derived(g[0])["hss_total"]) for _, g in groups), key=lambda p: p[0])
    guide(ax, *first_total, n_hi, 1.0, r"$N$")
    if dense_pts:
        fam, pts = next(iter(dense_pts.items()))
        n0 = min(pts)
        guide(ax, n0, pts[n0], n_hi, 3.0, r"$N^3$")
    for a, title, ylabel in ((ax, "time to a solution", "wall time [s]"), (axm, "memory", "memory [GiB]")):
        a.set_xscale("log")
        a.set_yscale("log")
        a.set_xlabel("N (unknowns)")
        a.set_ylabel(ylabel)
        a.set_title(title)
        a.set_xlim(n_lo / 1.3, n_hi * 1.6)
        a.grid(True, which="both", alpha=0.3)
        a.legend(fontsize=7.5, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=1)
    ax.set_ylim(top=max(ax.get_ylim()[1], 1e4) if dense_pts else None)
    axm.set_ylim(1e-2, 1e3)
    fig.suptitle("hssbem: time and memory against N (2 cores; slopes fitted for "
                 f"{fit_min:,} ≤ N ≤ {fit_max:,}; grey lines: reference slopes)", fontsize=10)
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    log(f"\nplot written to {path}")


# ------------------------------------------------------------------------------------------------
# sweep


def print_preamble(args, sizes, families):
    env = {k: os.environ[k] for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "OMP_PROC_BIND")
           if k in os.environ}
    try:
        built = datetime.datetime.fromtimestamp(os.path.getmtime(args.bench)).isoformat(" ", "seconds")
    except OSError:
        built = "?"
    log(f"# bench_hss.py  {datetime.datetime.now().isoformat(' ', 'seconds')}  host {platform.node()}")
    log(f"# CPU {cpu_model()}, {available_cores()} cores available; "
        f"threads: {', '.join(f'{k}={v}' for k, v in env.items()) or 'environment defaults'}")
    log(f"# binary {args.bench} (modified {built})")
    log(f"# families {','.join(families)}; target N {','.join(map(str, sizes))}; tol {args.tol:g}; "
        f"leaf {args.leaf if args.leaf is not None else 'program default'}; dense up to N = {args.dense_max}; "
        f"timeout {args.timeout:g} s" + (f"; extra args {args.extra!r}" if args.extra else ""))
    log(f"# meshes {args.mesh_dir}; CSV {args.csv}; logs {logs_dir_for(args.csv)}")


def sweep(args, sizes, families):
    """Run every (family, size); returns the list of failures (description, log file)."""
    header = bench_header(args.bench)
    if header[:len(BENCH_COLUMNS)] != BENCH_COLUMNS:
        log(f"# note: {os.path.basename(args.bench)} prints the columns {','.join(header)}; expected {','.join(BENCH_COLUMNS)} first")
    logs_dir = logs_dir_for(args.csv)
    os.makedirs(logs_dir, exist_ok=True)
    open_csv(args.csv, args.append)
    extra = shlex.split(args.extra) if args.extra else []
    cases = [(f, n) for f in families for n in sizes]
    failures = []
    for k, (family, n_target) in enumerate(cases, 1):
        tri = triangles_for_unknowns(n_target)
        dense = n_target <= args.dense_max
        what = args.solver.upper()
        log(f"[{k}/{len(cases)}] {family} N~{n_target} (T={tri}, {what + ' + dense' if dense else what + ' only'})")
        mesh, err = ensure_mesh(family, tri, args.mesh_dir, args.timeout)
        if mesh is None:
            log(f"    FAILED: {err}")
            failures.append((f"{family} N~{n_target}: {err.splitlines()[0]}", None))
            continue
        cmd = [args.bench, "--mesh", mesh, "--tol", repr(args.tol), "--dense", "1" if dense else "0"]
        if args.leaf is not None:
            cmd += ["--leaf", str(args.leaf)]
        cmd += extra
        log_file = log_path_for(logs_dir, mesh, args.tol, args.leaf)
        log(f"    {' '.join(shlex.quote(c) for c in cmd)}")
        rc, out, _, wall = run_command(cmd, args.timeout, stderr_path=log_file)
        fields = parse_bench_line(out, len(header)) if rc == 0 else None
        if fields is None:
            why = (f"timed out after {args.timeout:g} s" if rc is None else
                   f"exit status {rc}" if rc != 0 else "no CSV line on stdout")
            log(f"    FAILED ({why}, {wall:.1f} s); log {log_file}; its tail:")
            for line in (tail(log_file, 15) + out[-1000:]).rstrip().splitlines():
                log(f"      | {line}")
            failures.append((f"{family} N~{n_target}: {why}", log_file))
            continue
        # put the fields in this script's column order (by name, in case the program's differs)
        rec = dict(zip(header, fields))
        append_csv(args.csv, [family, args.solver] + [rec.get(c, "nan") for c in BENCH_COLUMNS + H2_COLUMNS])
        r = {c: to_float(rec.get(c)) for c in BENCH_COLUMNS}
        d = derived(r)
        dense_txt = f", dense {fmt_s(d['dense_total'])} s, speed-up {fmt_ratio(d['speedup'])}" if finite(d["dense_total"]) else ""
        log(f"    done in {wall:.1f} s: N={r['N']:.0f}, compress {fmt_s(r['compress_s'])} s, factor "
            f"{fmt_s(r['factor_s'])} s, solve {fmt_s(r['solve_s'])} s, max rank "
            f"{r['max_row_rank']:.0f}/{r['max_col_rank']:.0f}, peak RSS {fmt_mb(r['peak_rss_mb'])} MB"
            f"{dense_txt}" + (f", rel_diff {r['rel_diff']:.2e}" if finite(r["rel_diff"]) else ""))
    return failures


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 epilog=__doc__[__doc__.index("Examples"):],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--solver", choices=sorted(SOLVERS), default="hss",
                    help="hss: HSS direct (bench_hss); h2: H² + GMRES/Jacobi (bench_h2) (default: hss)")
    ap.add_argument("--bench", default=None,
                    help="benchmark binary (default: $BENCH_HSS or $BENCH_H2, else build/bin/bench_hss or bench_h2)")
    ap.add_argument("--family", type=parse_families, default=",".join(FAMILIES),
                    help="comma-separated mesh families: sphere, disk (default: both)")
    ap.add_argument("--sizes", type=parse_int_list, default=",".join(map(str, DEFAULT_SIZES)),
                    help="target unknown counts N (default: %(default)s)")
    ap.add_argument("--quick", action="store_true",
                    help=f"smoke test: sizes {','.join(map(str, QUICK_SIZES))} only (overrides --sizes)")
    ap.add_argument("--tol", type=float, default=1e-6, help="compression tolerance (default: 1e-6)")
    ap.add_argument("--leaf", type=int, default=None, help="leaf size (default: the program's default)")
    ap.add_argument("--dense-max", type=int, default=21000, metavar="N",
                    help="also run dense assembly + LU for target N <= this (default: 21000)")
    ap.add_argument("--csv", default=os.path.join(REPO, "out", "bench", "hss.csv"),
                    help="CSV output (default: out/bench/hss.csv); logs go to <stem>_logs/")
    ap.add_argument("--append", action="store_true",
                    help="append to an existing CSV (without it a new CSV is started and an existing one is "
                         "renamed to FILE.bak)")
    ap.add_argument("--plot", metavar="FILE.png", help="write a log-log plot of time and memory against N, with slopes")
    ap.add_argument("--mesh-dir", default=os.path.join(REPO, "build", "bench-meshes"),
                    help="mesh cache directory (default: build/bench-meshes)")
    ap.add_argument("--timeout", type=float, default=7200,
                    help="seconds per run (and per mesh generation); 0 = none (default: 7200)")
    ap.add_argument("--extra", default="", metavar="ARGS",
                    help='further bench_hss arguments, e.g. --extra "--proxy-ratio 2.5" '
                         '(a single word: --extra=--dense)')
    ap.add_argument("--fit-min", type=int, default=FIT_MIN, help=f"slope fit: smallest N (default: {FIT_MIN})")
    ap.add_argument("--fit-max", type=int, default=FIT_MAX, help=f"slope fit: largest N (default: {FIT_MAX})")
    ap.add_argument("--from-csv", metavar="FILE[,FILE...]",
                    help="run nothing: only print the tables and slopes (and --plot) of these CSVs, "
                         "e.g. an HSS and an H² sweep in one plot")
    args = ap.parse_args()
    if args.bench is None:
        prog = SOLVERS[args.solver]
        args.bench = os.environ.get(prog.upper(), os.path.join(REPO, "build", "bin", prog))

    if args.from_csv:
        files = [f for f in args.from_csv.split(",") if f]
        rows = [r for f in files for r in read_csv(f)]
        log(f"# {len(rows)} rows from {', '.join(files)}")
        print_report(rows, logs_dir_for(files[0]), args.fit_min, args.fit_max)
        if args.plot:
            plot(rows, args.plot, args.fit_min, args.fit_max)
        return 0

    if not (os.path.isfile(args.bench) and os.access(args.bench, os.X_OK)):
        ap.error(f"benchmark binary {args.bench!r} not found or not executable "
                 f"(build it: cmake --build build --target {SOLVERS[args.solver]}, or pass --bench)")
    sizes = list(QUICK_SIZES) if args.quick else args.sizes
    args.csv = os.path.abspath(args.csv)
    args.mesh_dir = os.path.abspath(args.mesh_dir)
    print_preamble(args, sizes, args.family)
    t0 = time.monotonic()
    try:
        failures = sweep(args, sizes, args.family)
    except KeyboardInterrupt:
        log("\ninterrupted; the report below covers the runs finished so far")
        failures = [("interrupted", None)]
    log(f"\n# sweep took {time.monotonic() - t0:.0f} s")

    rows = read_csv(args.csv)
    print_report(rows, logs_dir_for(args.csv), args.fit_min, args.fit_max)
    if args.plot:
        plot(rows, args.plot, args.fit_min, args.fit_max)
    if failures:
        log(f"\n{len(failures)} failed run(s):")
        for what, lf in failures:
            log(f"  {what}" + (f"  (log {lf})" if lf else ""))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
