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

With `--base-driver OLD` (another build's driver, e.g. the commit a change started from), each
run also makes OLD's own file (its cold run, whose frames must be the new driver's to the bit),
and `--load-rounds K` then loads each driver's file K more times, OLD and new alternating: the
load compared side by side on the same machine at the same time (rows with `driver` old / new;
`file_read_s` is one plain read of that file just before).

The scene: the mesh's region "bottom" clamped (scripts/gen_meshes.py --disk-triangles), a
sphere of radius 0.6 pressed 0.03 into the top and moved across it over the frames; the contact
candidates are the `--candidates` share of the vertices highest in z. Needs h5py and numpy.
"""
import argparse
import csv
import json
import os
import tempfile
import time

from bench_common import figure, timed_run


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


def pair_problem(mesh, share, frames, out_dir):
    """Two organs face to face (scripts/gen_meshes.py --disk-pair): contact between the bodies,
    the lower one's bottom 20 % (in z) clamped, the upper one's top 20 % pushed down 0.03 over
    the frames; the candidates: the `share` of each body's vertices nearest the other."""
    v = msh_vertices(mesh)
    z = sorted(p[2] for p in v)
    mid = 0.5 * (z[0] + z[-1])  # between the two (mirrored) bodies
    near = sorted(abs(p[2] - mid) for p in v)[int(share * len(v))]
    low, high = z[int(0.1 * len(z))], z[int(0.9 * len(z))]  # each body's 20 % farthest from the other
    box = lambda z0, z1: {"box": [[-10, -10, z0], [10, 10, z1]]}
    push = lambda f: 0.03 * (f + 1) / frames
    spec = {"mesh": os.path.abspath(mesh), "material": {"E": 3000, "nu": 0.45},
            "boundary": [{"where": box(-10, low), "displacement": [0, 0, 0]}, {"where": box(high, 10), "displacement": [0, 0, 0]}],
            "contact": {"obstacles": [], "bodies": True, "where": box(mid - near, mid + near)},
            "frames": [{"boundary": [{"where": box(high, 10), "displacement": [0, 0, -push(f)]}]} for f in range(frames)]}
    path = os.path.join(out_dir, "pair.json")
    with open(path, "w") as f:
        json.dump(spec, f, indent=1)
    return path, sum(abs(p[2] - mid) <= near for p in v), len(v)


def frames_of(path):
    """Every frame's displacement, traction and contact pressure, and frame 0's seconds."""
    import h5py
    with h5py.File(path, "r") as f:
        n = int(f.attrs["num_frames"])
        fields = [[f["/frames/%d/%s" % (i, k)][()] for k in ("displacement", "traction", "contact/pressure")] for i in range(n)]
        return fields, float(f["/frames/0"].attrs["seconds"]), {k: float(v) for k, v in f["/timings"].attrs.items()}


def touching(frames):
    """The most vertices with a positive contact pressure in any frame."""
    return max(int((fr[2] > 0).sum()) for fr in frames)


def identical(a, b):
    import numpy as np
    return all(np.array_equal(x, y) and x.tobytes() == y.tobytes() for fa, fb in zip(a, b) for x, y in zip(fa, fb)) and len(a) == len(b)


def cold_run(driver, prob, d, tag, saved):
    """A cold run of `driver` that saves to `saved`: its figures and its frames."""
    wall, cpu, out = timed_run(driver, prob, os.path.join(d, "cold_%s.h5" % tag), ["-hssbem_save", saved])
    frames, frame0, _ = frames_of(os.path.join(d, "cold_%s.h5" % tag))
    return {"unknowns": int(figure(r"(\d+) unknowns", out)), "setup_s": figure(r"contact: set up in ([\d.]+) s", out),
            "save_s": figure(r"saved the precomputation to .* in ([\d.]+) s", out), "cold_frame0_s": frame0, "cold_wall_s": wall,
            "cold_cpu_s": cpu, "touching_max": touching(frames), "memory_mb": figure(r"contact: set up in .*; (\d+) MB\)", out), "file_mb": os.path.getsize(saved) / 1e6}, frames


def read_once(path):
    """Seconds of one plain read of the file (from the page cache when it is there)."""
    t0 = time.time()
    with open(path, "rb") as f:
        while f.read(1 << 24):
            pass
    return time.time() - t0


def load_run(driver, prob, d, saved, cold):
    """A run of `driver` that loads `saved`: its figures, its frames compared with `cold`'s."""
    read_s = read_once(saved)
    wall, cpu, out = timed_run(driver, prob, os.path.join(d, "load.h5"), ["-hssbem_load", saved])
    frames, frame0, _ = frames_of(os.path.join(d, "load.h5"))
    return {"load_s": figure(r"loaded the precomputation from .* in ([\d.]+) s", out), "load_frame0_s": frame0, "load_wall_s": wall,
            "load_cpu_s": cpu, "file_read_s": read_s, "bitwise": identical(cold, frames), "loadavg_1min": os.getloadavg()[0]}


def show(row):
    print(" ".join("%s=%s" % (k, ("%.3f" % v) if isinstance(v, float) else v) for k, v in row.items()), flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--driver", required=True)
    ap.add_argument("--base-driver", default=None, help="another build's driver, loaded side by side (its own file)")
    ap.add_argument("--load-rounds", type=int, default=0, help="after the runs, loads of each driver's file, alternating")
    ap.add_argument("--mesh", required=True)
    ap.add_argument("--candidates", type=float, default=0.2)
    ap.add_argument("--pair", action="store_true", help="the mesh holds two organs (--disk-pair): press them together")
    ap.add_argument("--frames", type=int, default=5)
    ap.add_argument("--runs", type=int, default=2)
    ap.add_argument("--dir", default=None, help="where the files go (default: a new temporary directory)")
    ap.add_argument("--csv", required=True)
    ap.add_argument("--keep", action="store_true", help="keep the last saved file")
    a = ap.parse_args()
    d = a.dir or tempfile.mkdtemp(prefix="bench-persistence-")
    os.makedirs(d, exist_ok=True)
    prob, ncand, nv = (pair_problem if a.pair else problem)(a.mesh, a.candidates, a.frames, d)
    print("bench_persistence: %s, %d of %d vertices candidates, %d frames; OMP_NUM_THREADS=%s; load %s" %
          (a.mesh, ncand, nv, a.frames, os.environ.get("OMP_NUM_THREADS"), os.getloadavg()), flush=True)
    drivers = [("new", a.driver)] + ([("old", a.base_driver)] if a.base_driver else [])
    rows, files = [], {}
    for i in range(1, a.runs + 1):
        colds = {}
        for tag, driver in drivers:
            files[tag] = os.path.join(d, "precomputation_%s_%d.h5" % (tag, i))
            figures, colds[tag] = cold_run(driver, prob, d, tag, files[tag])
            row = {"run": i, "driver": tag, "candidates": ncand, **figures, **load_run(driver, prob, d, files[tag], colds["new"])}
            rows.append(row)
            show(row)
        if i < a.runs or not (a.keep or a.load_rounds):
            for f in files.values():
                os.remove(f)
    for k in range(1, a.load_rounds + 1):
        for tag, driver in (drivers[::-1] if k % 2 else drivers):
            row = {"run": "load%d" % k, "driver": tag, **load_run(driver, prob, d, files[tag], colds["new"])}
            rows.append(row)
            show(row)
    if a.load_rounds and not a.keep:
        for f in files.values():
            os.remove(f)
    fields = list(dict.fromkeys(k for r in rows for k in r))
    with open(a.csv, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        w.writerows(rows)


if __name__ == "__main__":
    main()
