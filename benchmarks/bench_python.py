#!/usr/bin/python3
"""A Python step against the C++ API, side by side: the frames of a sliding instrument on an
organ, stepped by hssbem.Scene (Python) and by ContactSession (bench_session_step, C++), each
frame and haptic call timed, the two sides alternating in fresh processes.

    /usr/bin/python3 scripts/gen_meshes.py --disk-triangles 10000 --out organ10k.msh
    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 PYTHONPATH=build/python /usr/bin/python3 \\
        benchmarks/bench_python.py --cxx build/bin/bench_session_step --mesh organ10k.msh \\
        --frames 10 --rounds 2 --dir /tmp/bench_python [--csv out.csv]

The scene (as bench_persistence.py's): the mesh's region "bottom" clamped, a sphere of radius 0.6
pressed 0.03 into the top and moved 0.4 across it over the frames; contact candidates the 20 %
of the vertices highest in z; dense reference. Its precomputation is made once (the C++ side
with -hssbem_save, first run) and loaded by every run (-hssbem_load / the option hssbem_load),
so a run costs the load and the frames, not the set-up. Each run steps the frames twice: the
first pass fills the cache of W's columns, the second is measured (per frame: wall and process
CPU time of the step, and the engine's own seconds, the frame report's "seconds"), then 20 haptic
calls between each two frames (the instrument 1 %, 2 %, ... of the way to the next frame).

The Python step is scene.step({"obstacles": {"tool": {"translate": [...]}}}) with stress=False:
the frame as a dict (JSON, parsed), the step, the fields refreshed in the views (displacement,
traction, the prescribed mask, the contact arrays), the report as a dict. The C++ step is
ContactSession::step + frame_data of the same fields. The overhead is the difference of the
medians; the figure robust to the load is each side's step less its engine's seconds (paired in
one frame).
"""
import argparse
import csv
import json
import os
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def problem(mesh, frames, out_dir):
    """bench_persistence.py's scene (the same problem file): its path."""
    sys.path.insert(0, HERE)
    from bench_persistence import problem as persistence_problem
    return persistence_problem(mesh, 0.2, frames, out_dir)[0]


def python_side(prob, load, haptic):
    """The Python run (in its own process): the lines bench_session_step prints."""
    import hssbem
    with open(prob) as f:
        frames = json.load(f)["frames"]
    start = time.perf_counter()
    scene = hssbem.Scene(prob, {"hssbem_load": load}, stress=False)
    print("set-up %.3f s, %d frames" % (time.perf_counter() - start, len(frames)))
    for p in range(2):
        for i, frame in enumerate(frames):
            w, c = time.perf_counter(), time.process_time()
            report = scene.step(frame)
            w, c = time.perf_counter() - w, time.process_time() - c
            if p == 0:
                continue
            print("frame %d wall %.6e cpu %.6e engine %.6e active %d" % (i, w, c, report["seconds"], report["active_vertices"]))
            if i + 1 == len(frames):
                break
            a, b = frame["obstacles"]["tool"]["translate"], frames[i + 1]["obstacles"]["tool"]["translate"]
            for h in range(haptic):
                s = 0.01 * (h + 1)
                at = {"tool": {"translate": [(1 - s) * a[d] + s * b[d] for d in range(3)]}}
                w = time.perf_counter()
                scene.haptic_forces(at)
                print("haptic %.6e" % (time.perf_counter() - w))
    return 0


def run(command, env=None):
    p = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True, env=env)
    if p.returncode != 0:
        sys.exit("failed: %s\n%s\n%s" % (" ".join(command), p.stdout, p.stderr))
    frames, haptic = [], []
    for line in p.stdout.splitlines():
        t = line.split()
        if t and t[0] == "frame":
            frames.append({"wall": float(t[3]), "cpu": float(t[5]), "engine": float(t[7]), "active": int(t[9])})
        elif t and t[0] == "haptic":
            haptic.append(float(t[1]))
    return frames, haptic


def summary(side, frames, haptic):
    med = lambda k: statistics.median(f[k] for f in frames)
    return {"side": side, "frames": len(frames), "wall_ms": 1e3 * med("wall"), "cpu_ms": 1e3 * med("cpu"), "engine_ms": 1e3 * med("engine"),
            "beyond_engine_ms": 1e3 * statistics.median(f["wall"] - f["engine"] for f in frames),
            "active": max(f["active"] for f in frames), "haptic_us": 1e6 * statistics.median(haptic), "haptic_khz": 1e-3 / statistics.median(haptic)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cxx", help="bench_session_step")
    ap.add_argument("--mesh")
    ap.add_argument("--frames", type=int, default=10)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--haptic", type=int, default=20)
    ap.add_argument("--dir", default="bench_python")
    ap.add_argument("--csv")
    ap.add_argument("--python-side", nargs=2, metavar=("PROBLEM", "LOAD"), help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.python_side:
        return python_side(a.python_side[0], a.python_side[1], a.haptic)
    os.makedirs(a.dir, exist_ok=True)
    prob = problem(a.mesh, a.frames, a.dir)
    pre = os.path.join(a.dir, "scene.pre.h5")
    print("bench_python: %s, %d frames; OMP_NUM_THREADS=%s OPENBLAS_NUM_THREADS=%s; load %s" %
          (a.mesh, a.frames, os.environ.get("OMP_NUM_THREADS"), os.environ.get("OPENBLAS_NUM_THREADS"), os.getloadavg()), flush=True)
    if not os.path.exists(pre):
        start = time.perf_counter()
        run([a.cxx, "-problem", prob, "-hssbem_save", pre, "-passes", "0", "-haptic", "0"])
        print("precomputation saved in %.1f s" % (time.perf_counter() - start), flush=True)
    rows = []
    for r in range(a.rounds):
        for side in ("c++", "python"):
            command = [a.cxx, "-problem", prob, "-hssbem_load", pre, "-haptic", str(a.haptic)] if side == "c++" else \
                      [sys.executable, os.path.abspath(__file__), "--haptic", str(a.haptic), "--python-side", prob, pre]
            row = dict(summary(side, *run(command)), round=r, loadavg_1min=os.getloadavg()[0])
            rows.append(row)
            print("round %d %-6s: step %.2f ms wall (median), %.2f ms CPU; engine %.2f ms; step beyond the engine %.3f ms; "
                  "up to %d vertices touching; haptic %.1f us (%.1f kHz); load %.2f" %
                  (r, side, row["wall_ms"], row["cpu_ms"], row["engine_ms"], row["beyond_engine_ms"], row["active"], row["haptic_us"], row["haptic_khz"], row["loadavg_1min"]), flush=True)
    for what in ("wall_ms", "cpu_ms", "beyond_engine_ms"):
        cxx = statistics.median(r[what] for r in rows if r["side"] == "c++")
        py = statistics.median(r[what] for r in rows if r["side"] == "python")
        print("%s: python %.3f, c++ %.3f (median of the rounds); difference %.3f = %.2f %% of the C++ step's wall %.3f" %
              (what, py, cxx, py - cxx, 100 * (py - cxx) / statistics.median(r["wall_ms"] for r in rows if r["side"] == "c++"),
               statistics.median(r["wall_ms"] for r in rows if r["side"] == "c++")))
    if a.csv:
        with open(a.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
