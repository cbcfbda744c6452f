#!/usr/bin/python3
"""Draw the deformed surface of an hssbem result file, one picture per frame, off-screen.

Usage:
    /usr/bin/python3 scripts/render.py result.h5 [-o outdir] [--frames 0,5,10|all] [--gif anim.gif]
                                       [--scale s] [--view elev,azim] [--fps n] [--size WxH]
                                       [--field NAME] [--no-obstacles]

The surface is /mesh/vertices + scale * displacement over /mesh/triangles, each triangle coloured
by the mean of its corners' values: |u| by default, the contact pressure where the body touches in
a contact result (the rest of the body a light neutral colour), or the per-vertex dataset given by --field
NAME (e.g. von_mises, or pressure in a contact result). NAME is looked up as /fields/NAME, then
/contact/NAME; in a result with frames as /frames/<i>/NAME, then /frames/<i>/contact/NAME; a NAME
with a slash is a path as given. A dataset with several columns per vertex (a vector, the Voigt
stress) is coloured by the norm of its rows, or by one column with NAME:COLUMN: a column number
from 0, or for six columns a Voigt label xx, yy, zz, yz, xz, xy (stress:xx, stress:yz), for three
columns x, y, z, and for principal_stress 1, 2, 3 (largest first: principal_stress:1);
e.g. displacement:z; NaN values (vertices without one) count as 0. The
colour scale and the axes are the same for every frame (taken over all frames of the file), so
pictures of one file can be compared and put in sequence.

The rigid obstacles of a contact result (/obstacles/<name>: a plane's patch, a sphere, a mesh)
are drawn translucent grey where the frame places them (/frames/<i>/obstacles/<name>/vertices),
clipped to the picture's box (the bodies' box, widened to take the instruments in but never
beyond half the body's size on each side); --no-obstacles leaves them out. The body and the
obstacles are one set of polygons, sorted back to front together.

A result with frames (/frames/<i>/displacement, i = 0, 1, ...) gives outdir/frame_0000.png, ...
(the number is the frame index), titled with the frame index and the frame's `strategy` and
`seconds` attributes when present; --gif also writes them as an animated GIF. A result without
/frames gives one picture of /fields/displacement, outdir/displacement.png.

Needs numpy, h5py and matplotlib (Debian: python3-numpy, python3-h5py, python3-matplotlib, whose
dependency python3-pil writes the GIFs); hence /usr/bin/python3 where a pyenv python3 lacks them.
Errors (missing file, no displacement, a frame that does not exist) print one line
`render.py: error: ...` and exit with status 1; bad arguments exit with status 2.
"""

import argparse
import os
import sys
import textwrap

import numpy as np

try:
    import h5py
    import matplotlib
    matplotlib.use("Agg")  # off-screen: no display needed
    import matplotlib.pyplot as plt
    from matplotlib.animation import PillowWriter
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection
except ImportError as exc:  # report it like any other error, naming the package to install
    sys.exit("render.py: error: %s (install python3-h5py and python3-matplotlib, "
             "and run with /usr/bin/python3)" % exc)

PROG = "render.py"
# The default scale makes the largest displacement this fraction of the body's size.
DEFAULT_SCALE_FRACTION = 0.10
DPI = 100
TITLE_CHAR_PIXELS = 10  # a wide character of the title's font (12 points at DPI): where lines wrap
DEFAULT_SIZE = (960, 720)  # pixels: the title, the colour bar and the axes' labels all fit
COLORMAP = "viridis"


class RenderError(Exception):
    """A fault in the input (file, dataset, frame index) reported as one line."""


class Frame:
    """One picture: a displacement field (nv x 3), the colour values (nv) and what its title
    shows."""

    def __init__(self, index, displacement, strategy=None, seconds=None):
        self.index = index  # frame number, or None for /fields/displacement
        self.displacement = displacement
        self.strategy = strategy
        self.seconds = seconds
        self.colour = np.nan_to_num(np.linalg.norm(displacement, axis=1))
        self.field = None  # the dataset that colours it; None: |u|
        self.touching = None  # contact pressure: per vertex, where the colour applies (else neutral)
        self.obstacles = []  # (vertices, triangles) of each rigid obstacle, placed for this frame

    def file_name(self):
        """The PNG name of this frame in the output directory."""
        if self.index is None:
            return "displacement.png" if self.field is None else \
                "%s.png" % self.field.strip("/").replace("/", "_").replace(":", "_")
        return "frame_%04d.png" % self.index

    def title(self):
        """Frame index, strategy and solve time, as far as the file tells them."""
        if self.index is None:
            if self.field is not None:
                return "%s on the deformed surface" % self.field
            return "displacement (/fields/displacement)"
        parts = ["frame %d" % self.index]
        if self.strategy:
            parts.append(self.strategy)
        if self.seconds is not None:
            parts.append("%.3g s" % self.seconds)
        return ", ".join(parts)


# ---------------------------------------------------------------------------------------------
# Reading the result file


def read_attribute(group, name):
    """An attribute as a Python value (strings decoded), or None when absent."""
    if name not in group.attrs:
        return None
    value = group.attrs[name]
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray) and value.size == 1:
        value = value.reshape(()).item()
    if isinstance(value, np.generic):
        value = value.item()
    return value


def read_vectors(h5, path, nv):
    """Dataset `path` as an nv x 3 float array, or a RenderError saying what is wrong."""
    if path not in h5:
        raise RenderError("%s: no dataset %s" % (h5.filename, path))
    data = np.asarray(h5[path], dtype=float)
    if data.shape != (nv, 3):
        raise RenderError("%s: %s has shape %s, expected (%d, 3)"
                          % (h5.filename, path, data.shape, nv))
    return data


def read_mesh(h5):
    """(vertices nv x 3, triangles nt x 3) from /mesh."""
    for path in ("/mesh/vertices", "/mesh/triangles"):
        if path not in h5:
            raise RenderError("%s: no dataset %s (not an hssbem result?)" % (h5.filename, path))
    vertices = np.asarray(h5["/mesh/vertices"], dtype=float)
    triangles = np.asarray(h5["/mesh/triangles"], dtype=np.int64)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or triangles.ndim != 2 \
            or triangles.shape[1] != 3:
        raise RenderError("%s: /mesh/vertices and /mesh/triangles must be n x 3" % h5.filename)
    if triangles.size and (triangles.min() < 0 or triangles.max() >= len(vertices)):
        raise RenderError("%s: /mesh/triangles has a vertex index out of range" % h5.filename)
    return vertices, triangles


def frame_indices(h5):
    """The frame numbers under /frames, ascending (group names in decimal)."""
    return sorted(int(name) for name in h5["/frames"] if name.isdigit())


def read_frames(h5, nv, wanted):
    """The frames to draw: those listed in `wanted` (None: all), or /fields/displacement."""
    if "/frames" not in h5:
        if wanted is not None:
            raise RenderError("%s: no /frames group, so --frames does not apply "
                              "(the file holds one displacement field)" % h5.filename)
        return [Frame(None, read_vectors(h5, "/fields/displacement", nv))]
    available = frame_indices(h5)
    if not available:
        raise RenderError("%s: /frames holds no frame" % h5.filename)
    for index in wanted or []:
        if index not in available:
            raise RenderError("%s: frame %d does not exist (the file has frames %d..%d)"
                              % (h5.filename, index, available[0], available[-1]))
    return [read_frame(h5, index, nv) for index in (wanted or available)]


def read_frame(h5, index, nv):
    """Frame `index`: /frames/<index>/displacement and the group's attributes."""
    group = h5["/frames/%d" % index]
    displacement = read_vectors(h5, "/frames/%d/displacement" % index, nv)
    seconds = read_attribute(group, "seconds")
    return Frame(index, displacement, read_attribute(group, "strategy"),
                 float(seconds) if seconds is not None else None)


VOIGT = ("xx", "yy", "zz", "yz", "xz", "xy")


def split_column(spec):
    """(NAME, COLUMN label or None) of --field NAME[:COLUMN]."""
    name, _, column = spec.partition(":")
    return name, (column or None)


def column_index(label, columns, where):
    """The 0-based column that `label` names in the dataset `where` of `columns` columns: 1, 2, 3
    for principal_stress (sigma_1 >= sigma_2 >= sigma_3), otherwise a number from 0, a Voigt
    label (six columns) or x, y, z (three)."""
    if columns == 3 and where.endswith("principal_stress"):
        if label in ("1", "2", "3"):
            return int(label) - 1
        raise RenderError("%s: no column '%s' (1, 2 or 3: the principal stresses, largest first)"
                          % (where, label))
    if label.isdigit() and int(label) < columns:
        return int(label)
    if columns == 6 and label in VOIGT:
        return VOIGT.index(label)
    if columns == 3 and label in ("x", "y", "z"):
        return "xyz".index(label)
    raise RenderError("%s has %d columns: no column '%s' (a number from 0%s)"
                      % (where, columns, label, {6: ", or xx, yy, zz, yz, xz, xy",
                                                  3: ", or x, y, z"}.get(columns, "")))


def field_candidates(name, index):
    """Where --field NAME is looked for, in order, for frame `index` (None: no frames)."""
    if "/" in name:
        return [name]
    if index is None:
        return ["/fields/%s" % name, "/contact/%s" % name]
    return ["/frames/%d/%s" % (index, name), "/frames/%d/contact/%s" % (index, name)]


def read_field(h5, name, index, nv):
    """(path, values per vertex) of --field NAME[:COLUMN]: the dataset's rows, their norms when it
    has several columns, or the column asked for; NaN counts as 0."""
    name, column = split_column(name)
    candidates = field_candidates(name, index)
    found = [p for p in candidates if p in h5 and isinstance(h5[p], h5py.Dataset)]
    if not found:
        raise RenderError("%s: no dataset %s" % (h5.filename, " or ".join(candidates)))
    data = np.asarray(h5[found[0]], dtype=float)
    if data.ndim == 0 or data.shape[0] != nv or data.ndim > 2:
        raise RenderError("%s: %s has shape %s, expected (%d,) or (%d, k): one value or row per "
                          "vertex" % (h5.filename, found[0], data.shape, nv, nv))
    if column is not None:
        if data.ndim != 2:
            raise RenderError("%s: %s has one value per vertex: no column '%s'"
                              % (h5.filename, found[0], column))
        data = data[:, column_index(column, data.shape[1], "%s: %s" % (h5.filename, found[0]))]
        return "%s:%s" % (found[0], column), np.nan_to_num(data)
    if data.ndim == 2:
        data = np.linalg.norm(np.nan_to_num(data), axis=1)
    return found[0], np.nan_to_num(data)


def obstacle_names(h5):
    """The obstacles' names under /obstacles, with their shapes ("plane", "sphere", "mesh")."""
    if "/obstacles" not in h5:
        return []
    return [(name, read_attribute(h5["/obstacles/%s" % name], "shape") or "mesh")
            for name in sorted(h5["/obstacles"])]


def read_obstacles(h5, index):
    """Each obstacle's (vertices, triangles, shape) as frame `index` (None: no frames) places
    it: /frames/<index>/obstacles/<name>/vertices, else /obstacles/<name>/vertices."""
    out = []
    for name, shape in obstacle_names(h5):
        base = "/obstacles/%s" % name
        triangles = np.asarray(h5[base + "/triangles"], dtype=np.int64)
        placed = "/frames/%d/obstacles/%s/vertices" % (index, name) if index is not None else None
        vertices = np.asarray(h5[placed if placed and placed in h5 else base + "/vertices"],
                              dtype=float)
        if triangles.size and (triangles.min() < 0 or triangles.max() >= len(vertices)):
            raise RenderError("%s: %s/triangles has a vertex index out of range"
                              % (h5.filename, base))
        out.append((vertices, triangles, shape))
    return out


def colour_by_pressure(h5, frame, nv):
    """A contact result drawn without --field: the contact pressure where the body touches."""
    path = "/contact/pressure" if frame.index is None else \
        "/frames/%d/contact/pressure" % frame.index
    if path not in h5:
        return
    pressure = np.nan_to_num(np.asarray(h5[path], dtype=float))
    if pressure.shape != (nv,):
        raise RenderError("%s: %s has shape %s, expected (%d,)"
                          % (h5.filename, path, pressure.shape, nv))
    frame.colour, frame.touching = pressure, pressure > 0


def load_result(path, wanted, field=None, obstacles=True):
    """(vertices, triangles, frames) of result file `path`, coloured by `field` if given (else by
    the contact pressure where the body touches, in a contact result), with the obstacles."""
    if not os.path.isfile(path):
        raise RenderError("%s: no such file" % path)
    try:
        h5 = h5py.File(path, "r")
    except OSError as exc:
        raise RenderError("%s: not a readable HDF5 file (%s)" % (path, exc))
    with h5:
        vertices, triangles = read_mesh(h5)
        frames = read_frames(h5, len(vertices), wanted)
        for frame in frames:
            if field is not None:
                frame.field, frame.colour = read_field(h5, field, frame.index, len(vertices))
            else:
                colour_by_pressure(h5, frame, len(vertices))
            if obstacles:
                frame.obstacles = read_obstacles(h5, frame.index)
        return vertices, triangles, frames


# ---------------------------------------------------------------------------------------------
# Drawing


def body_size(vertices):
    """The largest extent of the undeformed body's bounding box."""
    finite = vertices[np.all(np.isfinite(vertices), axis=1)]
    return float(np.max(finite.max(axis=0) - finite.min(axis=0)))


def magnitudes(frame):
    """|u| per vertex; vertices without a value (NaN) count as 0."""
    return np.nan_to_num(np.linalg.norm(frame.displacement, axis=1))


def default_scale(vertices, frames):
    """The scale that makes the largest |u| of all frames 10 % of the body's size."""
    largest = max(float(magnitudes(f).max()) for f in frames)
    if largest == 0.0:
        return 1.0, largest
    return DEFAULT_SCALE_FRACTION * body_size(vertices) / largest, largest


def deformed(vertices, frame, scale):
    """Vertices moved by scale times the frame's displacement (NaN displacement: not moved)."""
    return vertices + scale * np.nan_to_num(frame.displacement)


def axis_limits(vertices, frames, scale):
    """(lo, hi) over the deformed surfaces of all frames, so the camera never moves; widened to
    take in the obstacles but planes (a sphere, an instrument's mesh), by half the body's size
    on each side at most."""
    points = np.vstack([deformed(vertices, f, scale) for f in frames])
    lo, hi = points.min(axis=0), points.max(axis=0)
    size = float(np.max(hi - lo))
    solids = [v for f in frames for v, _, shape in f.obstacles if shape != "plane" and len(v)]
    if solids:
        around = np.vstack(solids)
        lo = np.maximum(np.minimum(lo, around.min(axis=0)), lo - 0.5 * size)
        hi = np.minimum(np.maximum(hi, around.max(axis=0)), hi + 0.5 * size)
    pad = 0.02 * float(np.max(hi - lo))
    return lo - pad, hi + pad


def clip_polygon(polygon, lo, hi):
    """The part of a planar polygon (k x 3) inside the box [lo, hi] (Sutherland-Hodgman, one
    face of the box at a time); None when nothing is left."""
    points = list(polygon)
    for axis in range(3):
        for bound, inside in ((lo[axis], lambda p, a=axis, b=lo[axis]: p[a] >= b),
                              (hi[axis], lambda p, a=axis, b=hi[axis]: p[a] <= b)):
            out = []
            for k, p in enumerate(points):
                q = points[k - 1]
                if inside(p) != inside(q):
                    t = (bound - q[axis]) / (p[axis] - q[axis])
                    out.append(q + t * (p - q))
                if inside(p):
                    out.append(p)
            points = out
            if len(points) < 3:
                return None
    return np.array(points)


OBSTACLE_FACE = (0.55, 0.55, 0.55, 0.28)  # translucent grey
OBSTACLE_EDGE = (0.3, 0.3, 0.3, 0.12)
NEUTRAL = (0.86, 0.84, 0.80, 1.0)  # the body where it does not touch (coloured by pressure)


class Renderer:
    """One figure reused for every frame: the surface is replaced, axes and colour bar stay."""

    def __init__(self, vertices, triangles, limits, vrange, view, size, label="|u|"):
        self.vertices = vertices
        self.triangles = triangles
        self.limits = limits
        vmin, vmax = vrange
        self.norm = matplotlib.colors.Normalize(vmin=vmin, vmax=vmax if vmax > vmin else vmin + 1.0)
        self.cmap = plt.get_cmap(COLORMAP)
        self.figure = plt.figure(figsize=(size[0] / DPI, size[1] / DPI), dpi=DPI)
        self.axes = self.figure.add_subplot(projection="3d")
        self.surface = None
        self.set_up_axes(limits, view)
        mappable = matplotlib.cm.ScalarMappable(norm=self.norm, cmap=self.cmap)
        self.figure.subplots_adjust(left=0.0, right=0.97, bottom=0.03, top=0.95)
        self.figure.colorbar(mappable, ax=self.axes, shrink=0.6, pad=0.1, label=label)

    def set_up_axes(self, limits, view):
        """Fixed limits, equal scale along x, y, z, and the camera direction."""
        lo, hi = limits
        self.axes.set_xlim(lo[0], hi[0])
        self.axes.set_ylim(lo[1], hi[1])
        self.axes.set_zlim(lo[2], hi[2])
        self.axes.set_box_aspect(tuple(np.maximum(hi - lo, 1e-12 * np.max(hi - lo))))
        self.axes.set_xlabel("x")
        self.axes.set_ylabel("y")
        self.axes.set_zlabel("z")
        self.axes.view_init(elev=view[0], azim=view[1])

    def body_faces(self, frame):
        """The body's face colours: the colour map of the mean of each triangle's corners; in a
        picture of the contact pressure, the neutral colour where no corner touches."""
        faces = self.cmap(self.norm(frame.colour[self.triangles].mean(axis=1)))
        if frame.touching is not None:
            faces[~frame.touching[self.triangles].any(axis=1)] = NEUTRAL
        return faces

    def obstacle_polygons(self, frame):
        """The obstacles' triangles clipped to the picture's box."""
        lo, hi = self.limits
        polygons = []
        for vertices, triangles, _ in frame.obstacles:
            for triangle in vertices[triangles]:
                clipped = clip_polygon(triangle, lo, hi)
                if clipped is not None:
                    polygons.append(clipped)
        return polygons

    def draw(self, frame, scale):
        """Put this frame's deformed surface and its obstacles in the figure: one collection, so
        that their polygons are sorted back to front together."""
        points = deformed(self.vertices, frame, scale)
        obstacles = self.obstacle_polygons(frame)
        faces = list(self.body_faces(frame)) + [OBSTACLE_FACE] * len(obstacles)
        edges = [(0, 0, 0, 0.25)] * len(self.triangles) + [OBSTACLE_EDGE] * len(obstacles)
        if self.surface is not None:
            self.surface.remove()
        self.surface = Poly3DCollection(list(points[self.triangles]) + obstacles,
                                        facecolors=faces, edgecolors=edges, linewidths=0.2)
        self.axes.add_collection3d(self.surface)
        title = "%s (displacement x %.3g)" % (frame.title(), scale)
        self.figure.suptitle(textwrap.fill(title, max(20, int(self.figure.bbox.width / TITLE_CHAR_PIXELS))))

    def close(self):
        plt.close(self.figure)


def render(vertices, triangles, frames, args):
    """Write the PNGs (and the GIF) of `frames`; returns the list of PNG paths."""
    scale = args.scale
    if scale is None:
        scale, largest = default_scale(vertices, frames)
        print("%s: scale %.4g (largest |u| %.4g drawn as %d %% of the body's size %.4g)"
              % (PROG, scale, largest, round(100 * DEFAULT_SCALE_FRACTION), body_size(vertices)))
    vmin = min(0.0, min(float(f.colour.min()) for f in frames))
    vmax = max(float(f.colour.max()) for f in frames)
    label = args.field if args.field is not None else \
        "contact pressure" if frames[0].touching is not None else "|u|"
    renderer = Renderer(vertices, triangles, axis_limits(vertices, frames, scale), (vmin, vmax),
                        args.view, args.size, label)
    try:
        return write_pictures(renderer, frames, scale, args)
    finally:
        renderer.close()


def write_pictures(renderer, frames, scale, args):
    """One PNG per frame into args.outdir, each also a GIF frame when args.gif is set."""
    os.makedirs(args.outdir, exist_ok=True)
    writer = None
    if args.gif:
        writer = PillowWriter(fps=args.fps)
        writer.setup(renderer.figure, args.gif, dpi=DPI)
    paths = []
    for frame in frames:
        renderer.draw(frame, scale)
        path = os.path.join(args.outdir, frame.file_name())
        renderer.figure.savefig(path, dpi=DPI)
        paths.append(path)
        if writer is not None:
            writer.grab_frame()
    if writer is not None:
        writer.finish()
    return paths


# ---------------------------------------------------------------------------------------------
# Command line


def parse_frames(text):
    """'all' -> None; '0,5,10' -> [0, 5, 10] (ascending, without repeats)."""
    if text.strip() == "all":
        return None
    try:
        indices = sorted({int(item) for item in text.split(",")})
    except ValueError:
        raise argparse.ArgumentTypeError("expected 'all' or comma-separated frame numbers, "
                                         "got '%s'" % text)
    if indices[0] < 0:
        raise argparse.ArgumentTypeError("frame numbers are >= 0, got '%s'" % text)
    return indices


def parse_pair(text, kind, convert):
    """'a,b' -> (a, b) converted; `kind` names the expected form in the message."""
    separator = "x" if kind == "WxH" else ","
    parts = text.lower().split(separator)
    try:
        if len(parts) != 2:
            raise ValueError
        return convert(parts[0]), convert(parts[1])
    except ValueError:
        raise argparse.ArgumentTypeError("expected %s, got '%s'" % (kind, text))


def parse_size(text):
    """'WxH' in pixels, each at least 100."""
    size = parse_pair(text, "WxH", int)
    if min(size) < 100:
        raise argparse.ArgumentTypeError("width and height must be at least 100 pixels")
    return size


def positive(convert):
    """An argparse type: a number > 0."""
    def parse(text):
        try:
            value = convert(text)
        except ValueError:
            raise argparse.ArgumentTypeError("expected a number, got '%s'" % text)
        if not value > 0:
            raise argparse.ArgumentTypeError("must be > 0, got '%s'" % text)
        return value
    return parse


def make_parser():
    parser = argparse.ArgumentParser(
        prog=PROG, description=__doc__.split("\n")[0],
        epilog="Example: render.py scene.h5 -o scene_png --gif scene.gif --fps 10")
    parser.add_argument("result", help="hssbem result file (.h5)")
    parser.add_argument("-o", "--outdir", help="directory for the PNGs "
                        "(default: <result name>_render beside the result file)")
    parser.add_argument("--frames", type=parse_frames, default=None,
                        help="frames to draw: 'all' (default) or a list such as 0,5,10")
    parser.add_argument("--gif", help="also write the frames drawn as this animated GIF")
    parser.add_argument("--scale", type=positive(float), help="displacement magnification "
                        "(default: largest |u| drawn as 10%% of the body's size)")
    parser.add_argument("--view", type=lambda t: parse_pair(t, "elev,azim", float),
                        default=(25.0, -60.0), help="camera elevation and azimuth in degrees "
                        "(default 25,-60)")
    parser.add_argument("--fps", type=positive(float), default=8.0,
                        help="GIF frames per second (default 8)")
    parser.add_argument("--size", type=parse_size, default=DEFAULT_SIZE,
                        help="picture size in pixels, WxH (default %dx%d)" % DEFAULT_SIZE)
    parser.add_argument("--no-obstacles", action="store_true",
                        help="leave out the rigid obstacles of a contact result")
    parser.add_argument("--field", metavar="NAME",
                        help="colour by this per-vertex dataset instead of |u|: /fields/NAME, "
                        "else /contact/NAME (with frames /frames/<i>/NAME, else "
                        "/frames/<i>/contact/NAME); a NAME with a slash is a path as given; "
                        "rows of several values (vectors, stress) colour by their norm, or by "
                        "one column with NAME:COLUMN (a number from 0; xx, yy, zz, yz, xz, xy "
                        "of the Voigt stress; x, y, z; 1, 2, 3 of principal_stress); "
                        "e.g. --field von_mises, stress:zz, principal_stress:1, pressure")
    return parser


def main(argv=None):
    args = make_parser().parse_args(argv)
    if args.outdir is None:
        args.outdir = os.path.splitext(args.result)[0] + "_render"
    try:
        vertices, triangles, frames = load_result(args.result, args.frames, args.field,
                                                  not args.no_obstacles)
        paths = render(vertices, triangles, frames, args)
    except (RenderError, OSError) as exc:
        print("%s: error: %s" % (PROG, exc), file=sys.stderr)
        return 1
    print("%s: wrote %d picture(s) to %s" % (PROG, len(paths), args.outdir))
    if args.gif:
        print("%s: wrote %s (%d frames, %g per second)" % (PROG, args.gif, len(paths), args.fps))
    return 0


if __name__ == "__main__":
    sys.exit(main())
