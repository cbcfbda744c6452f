#!/usr/bin/env python3
"""A contact's precomputation saved and loaded (-hssbem_save, -hssbem_load; docs/persistence.md),
side by side with the cold set-up, through the driver: runs in turn a cold run that saves its
precomputation and a run that loads it (cold, load, cold, load, ...), on one contact scene, and
reports per run the set-up (cold) or the load, the first frame, the save, the process's wall
time and CPU time (user + system, every thread: on a shared machine, what the run cost), one
plain read of the file (file_read_s: what the load's checksum pass costs at least),
the precomputation's memory against the file's size, and whether every frame's fields after the
load are the cold run's to the bit.

  OMP_NUM_THREADS=2 OPENBLAS_NUM_THREADS=2 bench_persistence.py --driver build/bin/hssbem \\
      --mesh organ10k.msh --candidates 0.2 --frames 5 --runs 2 --csv out.csv

The scene: the mesh's region "bottom" clamped (scripts/gen_meshes.py --disk-triangles), a
sphere of radius 0.6 pressed 0.03 into the top and moved across it over the frames; the contact
candidates are the `--candidates` share of the vertices highest in z. Needs h5py and numpy.
"""
import argparse
import csv
import json
import os
import re
import subprocess
import sys
import tempfile
import time


def msh_vertices(path):
    """The vertices of a Gmsh 4.1 ASCII file (its $Nodes blocks)."""
    lines = open(path).read().split("\n")
    i = lines.index("$Nodes") + 2
    out = []
    while not lines[i].startswith("$EndNodes"):
        n = int(lines[i].split()[3])
        out += [tuple(map(float, l.split())) for l in lines[i + 1 + n:i + 1 + 2 * n]]
        i += 1 + 2 * n
    return out


def problem(mesh, share, frames, out_dir):
    """The problem file of the scene (see the module's docstring)."""
    v = msh_vertices(mesh)
    z = sorted(p[2] for p in v)
    z_cut, z_top = z[int((1 - share) * len(z))], z[-1]
    depth, r = 0.03, 0.6
    spec = {"mesh": os.path.abspath(mesh), "material": {"E": 3000, "nu": 0.45},
            "boundary": [{"where": {"region": "bottom"}, "displacement": [0, 0, 0]}],
            "contact": {"obstacles": [{"name": "tool", "sphere": {"center": [-0.2, 0, z_top + r - depth], "radius": r}}],
                        "where": {"box": [[-10, -10, z_cut], [10, 10, 10]]}},
            "frames": [{"obstacles": {"tool": {"translate": [0.4 * f / max(1, frames - 1), 0, 0]}}} for f in range(frames)]}
    path = os.path.join(out_dir, "scene.json")
    with open(path, "w") as f:
        json.dump(spec, f, indent=1)
    return path, sum(p[2] >= z_cut for p in v), len(v)


def run(driver, prob, out, extra):
    """(wall s, CPU s (user + system, every thread), stdout) of one run."""
    cmd = ["/usr/bin/time", "-f", "%e %U %S", driver, "-problem", prob, "-o", out] + extra
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True)
    if p.returncode != 0:
        sys.exit("failed: %s\n%s\n%s" % (" ".join(cmd), p.stdout, p.stderr))
    wall, user, system = p.stderr.strip().splitlines()[-1].split()
    return float(wall), float(user) + float(system), p.stdout


def figure(pattern, text):
    m = re.search(pattern, text)
    return float(m.group(1)) if m else float("nan")


def frames_of(path):
    """Every frame's displacement, traction and contact pressure, and frame 0's seconds."""
    import h5py
    with h5py.File(path, "r") as f:
        n = int(f.attrs["num_frames"])
        fields = [[f["/frames/%d/%s" % (i, k)][()] for k in ("displacement", "traction", "contact/pressure")] for i in range(n)]
        return fields, float(f["/frames/0"].attrs["seconds"]), {k: float(v) for k, v in f["/timings"].attrs.items()}


def identical(a, b):
    import numpy as np
    return all(np.array_equal(x, y) and x.tobytes() == y.tobytes() for fa, fb in zip(a, b) for x, y in zip(fa, fb)) and len(a) == len(b)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--driver", required=True)
    ap.add_argument("--mesh", required=True)
    ap.add_argument("--candidates", type=float, default=0.2)
    ap.add_argument("--frames", type=int, default=5)
    ap.add_argument("--runs", type=int, default=2)
    ap.add_argument("--dir", default=None, help="where the files go (default: a new temporary directory)")
    ap.add_argument("--csv", required=True)
    ap.add_argument("--keep", action="store_true", help="keep the last saved file")
    a = ap.parse_args()
    d = a.dir or tempfile.mkdtemp(prefix="bench-persistence-")
    prob, ncand, nv = problem(a.mesh, a.candidates, a.frames, d)
    print("bench_persistence: %s, %d of %d vertices candidates, %d frames; OMP_NUM_THREADS=%s; load %s" %
          (a.mesh, ncand, nv, a.frames, os.environ.get("OMP_NUM_THREADS"), os.getloadavg()), flush=True)
    rows = []
    for i in range(1, a.runs + 1):
        saved = os.path.join(d, "precomputation_%d.h5" % i)
        wall_c, cpu_c, out_c = run(a.driver, prob, os.path.join(d, "cold.h5"), ["-hssbem_save", saved])
        cold, frame0_c, t_c = frames_of(os.path.join(d, "cold.h5"))
        t0 = time.time()
        with open(saved, "rb") as f:  # one read of the file (from the page cache when it is there)
            while f.read(1 << 24):
                pass
        read_s = time.time() - t0
        wall_l, cpu_l, out_l = run(a.driver, prob, os.path.join(d, "load.h5"), ["-hssbem_load", saved])
        load, frame0_l, t_l = frames_of(os.path.join(d, "load.h5"))
        row = {"run": i, "unknowns": int(figure(r"(\d+) unknowns", out_c)), "candidates": ncand,
               "setup_s": figure(r"contact: set up in ([\d.]+) s", out_c), "save_s": figure(r"saved the precomputation to .* in ([\d.]+) s", out_c),
               "cold_frame0_s": frame0_c, "cold_wall_s": wall_c, "cold_cpu_s": cpu_c,
               "load_s": figure(r"loaded the precomputation from .* in ([\d.]+) s", out_l), "load_frame0_s": frame0_l, "load_wall_s": wall_l, "load_cpu_s": cpu_l,
               "file_read_s": read_s, "memory_mb": figure(r"contact: set up in .*; (\d+) MB\)", out_c), "file_mb": os.path.getsize(saved) / 1e6,
               "bitwise": identical(cold, load), "loadavg_1min": os.getloadavg()[0]}
        rows.append(row)
        print(" ".join("%s=%s" % (k, ("%.3f" % v) if isinstance(v, float) else v) for k, v in row.items()), flush=True)
        if not a.keep or i < a.runs:
            os.remove(saved)
    with open(a.csv, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


if __name__ == "__main__":
    main()
