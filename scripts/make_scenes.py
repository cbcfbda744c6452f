#!/usr/bin/python3
"""Write real-time scenes as hssbem problem files: a broad contact patch moving over an organ.

Usage:
    /usr/bin/python3 scripts/make_scenes.py
        writes the two scenes of the paper into meshes/examples/:
        cardioid_moving_contact.json (meshes/cardioid_832.msh) and
        disk_organ_equator_wave.json (meshes/disk_organ_4k.msh)
    /usr/bin/python3 scripts/make_scenes.py --mesh M.msh --frames n --fraction f --out F.json
        [--depth d] [--clamp REGION] [--height z] [--turn t] [--E x --nu x]
        the same kind of scene on another mesh

A scene is the organ clamped on one region (base rules: that region's displacement 0, the rest
traction-free) and, in every frame, a contact patch pushed into it (frame rules, applied on top of
the base rules). The patch centre c travels westward (decreasing azimuth about the vertical axis
through the bounding box's centre) on the surface at a constant height, by `turn` revolutions
over the frames; in frame i its azimuth is -2 pi turn i / n. The patch is the `fraction` of the
mesh's vertices nearest to c (clamped vertices excluded), and each patch vertex v moves by

    u_v = -depth * w(|x_v - c| / R) * n_c,   w(s) = (1 - s^2)^2,

with R the distance of the farthest patch vertex and n_c the outward normal at c: a smooth
indentation, deepest at the centre and vanishing at the rim, along the inward normal, all three
components prescribed (the tissue sticks to the indenter). These are per-vertex bulk rows, the
form a contact detector hands over: {"where": {"vertices": [...]}, "displacement": [[...], ...]}.

Meshes are read with the small Gmsh ASCII reader below (formats 2.2 and 4.1; vertex i = i-th
node in ascending tag order, as the solver numbers them). Needs numpy only.
"""

import argparse
import json
import math
import os
import sys

import numpy as np

PROG = "make_scenes.py"
REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CLAMP_NAMES = ("base", "bottom")  # the clamped region of the shipped organs

# The two scenes of the paper, written when no --mesh is given.
PRESETS = [
    {"name": "cardioid_moving_contact", "mesh": "cardioid_832.msh", "frames": 40,
     "fraction": 0.20, "depth": 0.04, "material": {"lambda": 1000.0, "mu": 500.0},
     "what": "Cardioid body of revolution (cardioid_832; cusp at the origin, tip at z = 1) clamped "
             "on its \"base\", pressed on its side by a broad contact patch that travels once "
             "westward around the body at mid-height"},
    {"name": "disk_organ_equator_wave", "mesh": "disk_organ_4k.msh", "frames": 40,
     "fraction": 0.20, "depth": 0.04, "material": {"E": 3000.0, "nu": 0.49},
     "what": "Disk-shaped soft organ (ellipsoid with semi-axes 1, 0.8, 0.3 m; disk_organ_4k) "
             "resting on its clamped \"bottom\", with a broad displacement bump travelling once "
             "westward along its equator (the rim, z = 0); soft tissue, E = 3000 Pa, nu = 0.49"},
]


class SceneError(Exception):
    """A fault in the input (mesh file, region, option) reported as one line."""


# ---------------------------------------------------------------------------------------------
# Gmsh ASCII reader


class Mesh:
    """Vertices (nv x 3), triangles (nt x 3, 0-based), each triangle's physical tag, and names."""

    def __init__(self, vertices, triangles, tags, names):
        self.vertices = vertices
        self.triangles = triangles
        self.tags = tags
        self.names = names  # physical name -> tag (dimension 2)

    def region_vertices(self, name):
        """The vertices of the triangles of physical group `name`."""
        if name not in self.names:
            raise SceneError("no region '%s' in the mesh (known: %s)"
                             % (name, ", ".join(sorted(self.names)) or "none"))
        return np.unique(self.triangles[self.tags == self.names[name]])


def sections(lines):
    """{section name: list of its lines} of a Gmsh file ($Name ... $EndName)."""
    found, name, body = {}, None, []
    for line in lines:
        if line.startswith("$End"):
            found[name] = body
            name = None
        elif line.startswith("$"):
            name, body = line[1:], []
        elif name is not None:
            body.append(line)
    if name is not None:
        raise SceneError("section $%s has no $End%s (truncated file?)" % (name, name))
    return found


def physical_names(body):
    """Names of the dimension-2 physical groups from $PhysicalNames."""
    names = {}
    for line in body[1:]:
        dim, tag, name = line.split(maxsplit=2)
        if int(dim) == 2:
            names[name.strip().strip('"')] = int(tag)
    return names


def nodes_41(body):
    """{node tag: (x, y, z)} from a format 4.1 $Nodes section."""
    coords, pos = {}, 1
    blocks = int(body[0].split()[0])
    for _ in range(blocks):
        count = int(body[pos].split()[3])
        tags = [int(t) for t in body[pos + 1:pos + 1 + count]]
        xyz = body[pos + 1 + count:pos + 1 + 2 * count]
        coords.update((t, [float(c) for c in line.split()[:3]]) for t, line in zip(tags, xyz))
        pos += 1 + 2 * count
    return coords


def surface_physicals_41(body):
    """{surface entity tag: its first physical tag (or -1)} from a 4.1 $Entities section."""
    npoints, ncurves, nsurfaces = (int(n) for n in body[0].split()[:3])
    physical = {}
    for line in body[1 + npoints + ncurves:1 + npoints + ncurves + nsurfaces]:
        fields = line.split()
        count = int(fields[7])
        physical[int(fields[0])] = int(fields[8]) if count > 0 else -1
    return physical


def triangles_41(body, physical):
    """[(node tags), physical tag] of the 3-node triangles of a 4.1 $Elements section."""
    triangles, pos = [], 1
    blocks = int(body[0].split()[0])
    for _ in range(blocks):
        dim, entity, kind, count = (int(n) for n in body[pos].split())
        if dim == 2 and kind == 2:
            tag = physical.get(entity, -1)
            triangles += [([int(n) for n in line.split()[1:4]], tag)
                          for line in body[pos + 1:pos + 1 + count]]
        pos += 1 + count
    return triangles


def nodes_22(body):
    """{node tag: (x, y, z)} from a format 2.2 $Nodes section."""
    return {int(f[0]): [float(c) for c in f[1:4]] for f in (line.split() for line in body[1:])}


def triangles_22(body):
    """[(node tags), physical tag] of the 3-node triangles of a 2.2 $Elements section."""
    triangles = []
    for line in body[1:]:
        fields = [int(n) for n in line.split()]
        if fields[1] == 2:
            ntags = fields[2]
            tag = fields[3] if ntags > 0 else -1
            triangles.append((fields[3 + ntags:6 + ntags], tag))
    return triangles


def read_msh(path):
    """A Mesh from a Gmsh ASCII file (2.2 or 4.1); vertex i is the i-th node by tag."""
    if not os.path.isfile(path):
        raise SceneError("%s: no such file" % path)
    try:
        with open(path) as f:
            parts = sections(line.strip() for line in f)
        version = parts["MeshFormat"][0].split()
        if version[1] != "0":
            raise SceneError("binary .msh is not supported (save as ASCII)")
        if version[0].startswith("4"):
            nodes = nodes_41(parts["Nodes"])
            triangles = triangles_41(parts["Elements"],
                                     surface_physicals_41(parts.get("Entities", ["0 0 0 0"])))
        else:
            nodes, triangles = nodes_22(parts["Nodes"]), triangles_22(parts["Elements"])
        names = physical_names(parts.get("PhysicalNames", ["0"]))
    except (OSError, KeyError, ValueError, IndexError) as exc:
        raise SceneError("%s: cannot read as a Gmsh ASCII mesh (%s: %s)"
                         % (path, type(exc).__name__, exc))
    return build_mesh(path, nodes, triangles, names)


def build_mesh(path, nodes, triangles, names):
    """Number the nodes by ascending tag and turn the triangles' node tags into indices."""
    order = sorted(nodes)
    index = {tag: i for i, tag in enumerate(order)}
    try:
        tris = np.array([[index[t] for t in tri] for tri, _ in triangles], dtype=np.int64)
    except KeyError as exc:
        raise SceneError("%s: a triangle refers to unknown node %s" % (path, exc))
    if len(tris) == 0:
        raise SceneError("%s: no triangles" % path)
    tags = np.array([tag for _, tag in triangles], dtype=np.int64)
    return Mesh(np.array([nodes[t] for t in order], dtype=float), tris, tags, names)


# ---------------------------------------------------------------------------------------------
# Geometry


def triangle_normals(mesh):
    """Area-weighted normals of the triangles (length = twice the area)."""
    a, b, c = (mesh.vertices[mesh.triangles[:, k]] for k in range(3))
    return np.cross(b - a, c - a)


def vertex_normals(mesh):
    """Unit outward normals at the vertices: the area-weighted mean of their triangles'."""
    normals = np.zeros_like(mesh.vertices)
    for k in range(3):
        np.add.at(normals, mesh.triangles[:, k], triangle_normals(mesh))
    length = np.linalg.norm(normals, axis=1)
    return normals / np.where(length > 0, length, 1.0)[:, None]


def vertex_areas(mesh):
    """A third of the area of each vertex's triangles (they add up to the surface area)."""
    areas = np.zeros(len(mesh.vertices))
    third = np.linalg.norm(triangle_normals(mesh), axis=1) / 6.0
    for k in range(3):
        np.add.at(areas, mesh.triangles[:, k], third)
    return areas


def surface_point(mesh, origin, direction):
    """The farthest crossing of the ray origin + t direction (t > 0) with the surface."""
    a, b, c = (mesh.vertices[mesh.triangles[:, k]] for k in range(3))
    e1, e2 = b - a, c - a
    p = np.cross(direction, e2)
    det = np.einsum("ij,ij->i", e1, p)
    ok = np.abs(det) > 1e-14
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = origin - a
    u = np.einsum("ij,ij->i", s, p) * inv
    q = np.cross(s, e1)
    v = (q @ direction) * inv
    t = np.einsum("ij,ij->i", e2, q) * inv
    hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    if not hit.any():
        raise SceneError("the ray from %s along %s misses the surface (is the height inside "
                         "the body?)" % (np.round(origin, 4).tolist(), np.round(direction, 4).tolist()))
    return origin + t[hit].max() * direction


# ---------------------------------------------------------------------------------------------
# The scene


class Scene:
    """What a scene is made of: the mesh, the clamped region and the contact's parameters."""

    def __init__(self, mesh, clamp, frames, fraction, depth, height, turn):
        self.mesh = mesh
        self.clamp = clamp
        self.clamped = mesh.region_vertices(clamp)
        self.frames = frames
        self.fraction = fraction
        lo, hi = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
        self.size = float(np.max(hi - lo))
        self.depth = depth * self.size  # absolute indentation at the patch centre
        self.axis = 0.5 * (lo + hi)  # a point of the vertical axis, at mid-height
        if height is not None:
            self.axis[2] = height
        self.turn = turn
        self.normals = vertex_normals(mesh)
        self.free = np.setdiff1d(np.arange(len(mesh.vertices)), self.clamped)
        self.patch_size = int(round(fraction * len(mesh.vertices)))
        if not 1 <= self.patch_size <= len(self.free):
            raise SceneError("a contact fraction of %g gives %d vertices, but %d are free"
                             % (fraction, self.patch_size, len(self.free)))

    def centre(self, frame):
        """The patch centre of `frame`: on the surface, at the axis's height, moving westward."""
        azimuth = -2.0 * math.pi * self.turn * frame / self.frames
        direction = np.array([math.cos(azimuth), math.sin(azimuth), 0.0])
        return surface_point(self.mesh, self.axis, direction)

    def patch(self, centre):
        """(vertices ascending, their weights w in [0, 1]) of the patch around `centre`."""
        distance = np.linalg.norm(self.mesh.vertices[self.free] - centre, axis=1)
        nearest = np.argsort(distance, kind="stable")[:self.patch_size]
        radius = distance[nearest].max()
        chosen = self.free[nearest]
        weight = (1.0 - (distance[nearest] / radius) ** 2) ** 2 if radius > 0 else np.ones(1)
        order = np.argsort(chosen)
        return chosen[order], weight[order]

    def push_direction(self, vertices, weight):
        """Outward unit normal at the patch centre: the weighted mean of the patch's normals."""
        normal = (weight[:, None] * self.normals[vertices]).sum(axis=0)
        return normal / np.linalg.norm(normal)

    def frame(self, frame):
        """(centre, vertices, displacement rows) of one frame."""
        centre = self.centre(frame)
        vertices, weight = self.patch(centre)
        normal = self.push_direction(vertices, weight)
        return centre, vertices, -self.depth * weight[:, None] * normal[None, :]


def number(x, decimals):
    """A displacement component in JSON with `decimals` digits after the point."""
    text = ("%.*f" % (decimals, x)).rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def decimals_for(depth):
    """Digits after the point that keep 3 significant digits of the indentation `depth`."""
    return max(0, math.ceil(-math.log10(depth))) + 3


def frame_json(vertices, rows, decimals):
    """One frame as a JSON object on one line: a single per-vertex bulk displacement rule."""
    where = '{"vertices": [%s]}' % ",".join(str(v) for v in vertices)
    values = ",".join("[%s]" % ",".join(number(x, decimals) for x in row) for row in rows)
    return '{"boundary": [{"where": %s, "displacement": [%s]}]}' % (where, values)


def header(what, command, scene, stats):
    """The // comment opening the problem file."""
    lines = [what + ".",
             "Base rules: region \"%s\" clamped, the rest traction-free. Each of the %d frames "
             "pushes a contact patch of %d of the %d vertices (%.1f %% of the vertices, %.1f %% "
             "of the area)" % (scene.clamp, scene.frames, scene.patch_size,
                               len(scene.mesh.vertices), 100 * stats["fraction"],
                               100 * stats["area"]),
             "into the body along the inward normal at its centre, by %.4g at the centre (%g of "
             "the size %.4g) with the smooth profile (1 - (r/R)^2)^2 (per-vertex bulk rows);"
             % (scene.depth, scene.depth / scene.size, scene.size),
             "the centre travels westward at z = %.4g, %g turn(s) about the vertical axis "
             "through (%.4g, %.4g), %.1f degrees per frame."
             % (scene.axis[2], scene.turn, scene.axis[0], scene.axis[1],
                360.0 * scene.turn / scene.frames),
             "Generated by: %s" % command]
    return "".join("// %s\n" % line for line in wrap_lines(lines))


def wrap_lines(lines, width=96):
    """Break the comment's lines at spaces so none is much wider than `width`."""
    out = []
    for line in lines:
        words, current = line.split(" "), ""
        for word in words:
            if current and len(current) + 1 + len(word) > width:
                out.append(current)
                current = word
            else:
                current = (current + " " + word) if current else word
        out.append(current)
    return out


def write_scene(scene, path, mesh_path, material, what, command):
    """Build every frame, write the problem file, and return the scene's statistics."""
    frames = [scene.frame(i) for i in range(scene.frames)]
    areas = vertex_areas(scene.mesh)
    stats = {"fraction": scene.patch_size / len(scene.mesh.vertices),
             "area": float(np.mean([areas[v].sum() for _, v, _ in frames]) / areas.sum()),
             "step": float(np.mean([np.linalg.norm(frames[i][0] - frames[i - 1][0])
                                    for i in range(1, len(frames))])) if len(frames) > 1 else 0.0}
    mesh_ref = os.path.relpath(mesh_path, os.path.dirname(os.path.abspath(path)))
    output = os.path.splitext(os.path.basename(path))[0] + ".h5"
    body = ['{',
            '  "mesh": %s,' % json.dumps(mesh_ref),
            '  "material": %s,' % json.dumps(material),
            '  "boundary": [{"where": {"region": %s}, "displacement": [0, 0, 0]}],'
            % json.dumps(scene.clamp),
            '  "frames": [',
            ",\n".join("    " + frame_json(v, rows, decimals_for(scene.depth))
                       for _, v, rows in frames),
            '  ],',
            '  "output": %s' % json.dumps(output),
            '}']
    with open(path, "w") as f:
        f.write(header(what, command, scene, stats) + "\n".join(body) + "\n")
    return stats


def report(path, scene, stats):
    """One line per scene: what was written and the measured contact fraction."""
    print("%s: %s: %d frames, patch %d of %d vertices = %.1f %% of the vertices "
          "(%.1f %% of the area), depth %.4g, centre moves %.4g per frame, %d kB"
          % (PROG, path, scene.frames, scene.patch_size, len(scene.mesh.vertices),
             100 * stats["fraction"], 100 * stats["area"], scene.depth, stats["step"],
             round(os.path.getsize(path) / 1024)))


# ---------------------------------------------------------------------------------------------
# Command line


def default_clamp(mesh, path):
    """The shipped organs' clamped region ("base" or "bottom")."""
    for name in CLAMP_NAMES:
        if name in mesh.names:
            return name
    raise SceneError("%s: no region named %s; say which to clamp with --clamp"
                     % (path, " or ".join(CLAMP_NAMES)))


def make_one(mesh_path, out, frames, fraction, depth, clamp, height, turn, material, what,
             command):
    """Read the mesh, build the scene, write it to `out`, print the report line."""
    mesh = read_msh(mesh_path)
    scene = Scene(mesh, clamp or default_clamp(mesh, mesh_path), frames, fraction, depth,
                  height, turn)
    report(out, scene, write_scene(scene, out, mesh_path, material, what, command))


def make_presets(outdir):
    """The paper's two scenes on the shipped meshes."""
    os.makedirs(outdir, exist_ok=True)
    for preset in PRESETS:
        out = os.path.join(outdir, preset["name"] + ".json")
        make_one(os.path.join(REPO, "meshes", preset["mesh"]), out, preset["frames"],
                 preset["fraction"], preset["depth"], None, None, 1.0, preset["material"],
                 preset["what"], "scripts/make_scenes.py (no arguments)")


# Options of a scene on another mesh (--mesh), with their defaults.
SCENE_DEFAULTS = {"frames": 40, "fraction": 0.20, "depth": 0.04, "clamp": None, "height": None,
                  "turn": 1.0, "E": 3000.0, "nu": 0.49}


def in_range(low, high, convert=float, open_high=False):
    """An argparse type: a number in (low, high], or (low, high) when open_high."""
    def parse(text):
        try:
            value = convert(text)
        except ValueError:
            raise argparse.ArgumentTypeError("expected a number, got '%s'" % text)
        if not (low < value < high if open_high else low < value <= high):
            raise argparse.ArgumentTypeError("must be in (%g, %g%s, got '%s'"
                                             % (low, high, ")" if open_high else "]", text))
        return value
    return parse


def make_parser():
    parser = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n")[0])
    parser.add_argument("--mesh", help="Gmsh ASCII mesh (2.2 or 4.1) of another organ; without "
                        "it the two scenes of the paper are written into meshes/examples/")
    parser.add_argument("--out", help="problem file to write (with --mesh)")
    parser.add_argument("--outdir", default=os.path.join(REPO, "meshes", "examples"),
                        help="directory of the two preset scenes (default meshes/examples)")
    parser.add_argument("--frames", type=in_range(0, 100000, int),
                        help="number of frames (default 40)")
    parser.add_argument("--fraction", type=in_range(0, 1),
                        help="fraction of the vertices in contact (default 0.20)")
    parser.add_argument("--depth", type=in_range(0, 1),
                        help="indentation at the patch centre, as a fraction of the body's "
                        "largest extent (default 0.04)")
    parser.add_argument("--clamp", help="clamped region (default: 'base' or 'bottom')")
    parser.add_argument("--height", type=float, help="z of the centre's path (default: the "
                        "middle of the bounding box)")
    parser.add_argument("--turn", type=in_range(0, 100),
                        help="revolutions of the patch centre over the frames (default 1)")
    parser.add_argument("--E", type=in_range(0, math.inf),
                        help="Young's modulus (default 3000 Pa, soft tissue)")
    parser.add_argument("--nu", type=in_range(-1, 0.5, open_high=True),
                        help="Poisson's ratio (default 0.49)")
    return parser


def main(argv=None):
    parser = make_parser()
    args = parser.parse_args(argv)
    if (args.mesh is None) != (args.out is None):
        parser.error("--mesh and --out go together")
    given = [key for key in SCENE_DEFAULTS if getattr(args, key) is not None]
    if args.mesh is None and given:
        parser.error("--%s: only with --mesh (the preset scenes have their own)" % given[0])
    for key, value in SCENE_DEFAULTS.items():
        if getattr(args, key) is None:
            setattr(args, key, value)
    try:
        if args.mesh is None:
            make_presets(args.outdir)
        else:
            command = "scripts/make_scenes.py " + " ".join(sys.argv[1:] if argv is None else argv)
            make_one(args.mesh, args.out, args.frames, args.fraction, args.depth, args.clamp,
                     args.height, args.turn, {"E": args.E, "nu": args.nu},
                     "Moving contact scene on %s" % os.path.basename(args.mesh), command)
    except (SceneError, OSError) as exc:
        print("%s: error: %s" % (PROG, exc), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
