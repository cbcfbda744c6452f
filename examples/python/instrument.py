#!/usr/bin/env python3
"""An instrument dragged across an organ, driven frame by frame from Python.

    PYTHONPATH=build/python python3 examples/python/instrument.py [--frames N] [--out DIR] [--no-gif]

The shipped contact example (meshes/examples/organ_table_instrument.json): a disk-shaped organ
(disk_organ_1k, E = 3000, nu = 0.45) attached at one end and lying on a frictionless table, and a
spherical instrument of radius 0.3 above it. The contact is set up once (hssbem.Scene); then each
frame is one scene.step() with the instrument's new translation: first pressed 0.1 into the
organ, then dragged 1.1 along x (N frames in all, a quarter of them pressing; 32 by default).
Between two frames of the drag the haptic call (scene.haptic_forces) gives the force at three
positions in between, as a haptic loop running faster than the frames would.

Writes DIR/instrument.gif (the deformed surface, coloured by the contact pressure, with the
instrument; skipped with --no-gif) and DIR/instrument_force.png (the instrument's force on the
organ against the instrument's position, frames and haptic calls), and prints one line per frame.
Needs matplotlib (Debian: python3-matplotlib, whose python3-pil writes the GIF).
"""
import argparse
import json
import os
import sys
import time

import numpy as np

import hssbem

HERE = os.path.dirname(os.path.abspath(__file__))
PROBLEM = os.path.join(HERE, "..", "..", "meshes", "examples", "organ_table_instrument.json")
DEPTH, TRAVEL = 0.1, 1.1  # the press and the drag of the shipped example's frames


def load_problem():
    """The shipped problem as a dict, without its own frames (this script makes them)."""
    with open(PROBLEM) as f:
        problem = json.loads("\n".join(line for line in f if not line.lstrip().startswith("//")))
    problem["mesh"] = os.path.normpath(os.path.join(os.path.dirname(PROBLEM), problem["mesh"]))
    for key in ("frames", "output"):
        problem.pop(key, None)
    return problem


def path(frames):
    """The instrument's translations: pressed to DEPTH, then dragged TRAVEL along x."""
    press = max(2, frames // 4)
    down = [[0.0, 0.0, -DEPTH * (i + 1) / press] for i in range(press)]
    along = [[TRAVEL * (i + 1) / (frames - press), 0.0, -DEPTH] for i in range(frames - press)]
    return down + along


def run(scene, offsets, on_frame):
    """Step the scene along the path; between drag frames, the haptic call at 3 points between.
    Returns the instrument's x, the force of each frame, and the haptic samples (x, force)."""
    xs, forces, haptic, haptic_seconds = [], [], [], []
    for k, offset in enumerate(offsets):
        report = scene.step({"obstacles": {"tool": {"translate": offset}}})
        force = np.array(scene.contact["forces"]["tool"])
        xs.append(offset[0]), forces.append(force)
        print("frame %2d: instrument at x %+.3f z %+.3f, force (%+.3f, %+.3f, %+.3f), %d vertices in contact, %.3f s"
              % (k, offset[0], offset[2], *force, report["active_vertices"], report["seconds"]))
        on_frame(k, offset)
        if k + 1 < len(offsets) and offsets[k + 1][2] == offset[2]:  # dragging: the haptic loop
            for t in (0.25, 0.5, 0.75):
                between = [offset[0] + t * (offsets[k + 1][0] - offset[0]), 0.0, offset[2]]
                start = time.perf_counter()
                f = scene.haptic_forces({"tool": between})["tool"]
                haptic_seconds.append(time.perf_counter() - start)
                haptic.append((between[0], f))
    if haptic_seconds:
        print("haptic call: %d calls, %.2f ms each on average" % (len(haptic_seconds), 1e3 * np.mean(haptic_seconds)))
    return np.array(xs), np.array(forces), haptic


class Movie:
    """The deformed surface per frame, coloured by the contact pressure, and the instrument."""

    def __init__(self, scene, sphere, size=(6.0, 3.0)):
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection
        self.plt, self.poly = plt, Poly3DCollection
        self.vertices, self.triangles = np.array(scene.mesh["vertices"]), np.array(scene.mesh["triangles"])
        self.scene, self.sphere, self.size, self.images = scene, sphere, size, []
        self.pmax = None

    def frame(self, k, offset):
        plt = self.plt
        u = self.scene.fields["displacement"]
        p = np.nan_to_num(self.scene.contact["pressure"])
        if self.pmax is None or p.max() > self.pmax:
            self.pmax = max(p.max(), 1e-12)
        fig = plt.figure(figsize=self.size, dpi=80)
        ax = fig.add_subplot(projection="3d")
        x = self.vertices + u
        colours = plt.cm.YlOrRd(0.1 + 0.9 * p[self.triangles].mean(axis=1) / self.pmax)
        ax.add_collection3d(self.poly(x[self.triangles], facecolors=colours, edgecolor=(0, 0, 0, 0.15), linewidth=0.2))
        c, r = np.array(self.sphere["center"]) + offset, self.sphere["radius"]
        a, b = np.meshgrid(np.linspace(0, 2 * np.pi, 16), np.linspace(0, np.pi, 9))
        ax.plot_wireframe(c[0] + r * np.cos(a) * np.sin(b), c[1] + r * np.sin(a) * np.sin(b), c[2] + r * np.cos(b), color="0.5", linewidth=0.4)
        lo, hi = self.vertices.min(axis=0), self.vertices.max(axis=0)
        hi[2] += 2 * r  # room for the instrument above
        ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]), box_aspect=tuple(hi - lo))
        ax.view_init(elev=20, azim=-70)
        ax.set_axis_off()
        ax.set_title("frame %d: instrument at x = %+.2f" % (k, c[0]), fontsize=9)
        fig.canvas.draw()
        self.images.append(np.asarray(fig.canvas.buffer_rgba())[..., :3].copy())
        plt.close(fig)

    def write(self, out):
        from PIL import Image
        frames = [Image.fromarray(a).quantize(colors=64) for a in self.images]
        frames[0].save(out, save_all=True, append_images=frames[1:], duration=120, loop=0, optimize=True)


def plot_force(xs, forces, haptic, pressing, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(5.5, 3.2), dpi=100)
    drag = slice(pressing - 1, None)  # from the last pressing frame (x = 0) on
    x0 = -0.5  # the instrument's centre at translation 0 (the problem file's sphere)
    for i, (name, colour) in enumerate([("$F_x$", "C0"), ("$F_z$", "C3")]):
        j = (0, 2)[i]
        ax.plot(x0 + xs[drag], forces[drag, j], "o-", color=colour, markersize=3, label=name + " (frames)")
        if haptic:
            hx = np.array([h[0] for h in haptic])
            ax.plot(x0 + hx, [h[1][j] for h in haptic], ".", color=colour, markersize=3, alpha=0.6, label=name + " (haptic calls)")
    ax.axhline(0, color="0.7", linewidth=0.5)
    ax.set(xlabel="instrument centre x (pressed %.2f deep)" % DEPTH, ylabel="force on the organ")
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(out)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=32, help="frames in all (at least 4)")
    ap.add_argument("--out", default=".", help="directory of instrument.gif and instrument_force.png")
    ap.add_argument("--no-gif", action="store_true", help="leave the GIF out")
    a = ap.parse_args()
    if a.frames < 4:
        ap.error("--frames: at least 4")
    os.makedirs(a.out, exist_ok=True)
    problem = load_problem()
    sphere = next(o["sphere"] for o in problem["contact"]["obstacles"] if o["name"] == "tool")
    start = time.perf_counter()
    try:
        scene = hssbem.Scene(problem)
    except hssbem.Error as e:
        print("instrument.py: error: %s" % e, file=sys.stderr)
        return 1
    print("set up in %.2f s: %d vertices, obstacles %s" % (time.perf_counter() - start, len(scene.mesh["vertices"]), ", ".join(scene.obstacles)))
    movie = None if a.no_gif else Movie(scene, sphere)
    offsets = path(a.frames)
    xs, forces, haptic = run(scene, offsets, movie.frame if movie else (lambda k, offset: None))
    plot_force(xs, forces, haptic, max(2, a.frames // 4), os.path.join(a.out, "instrument_force.png"))
    if movie:
        movie.write(os.path.join(a.out, "instrument.gif"))
    print("wrote %s" % ", ".join(os.path.join(a.out, n) for n in (["instrument.gif"] if movie else []) + ["instrument_force.png"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
