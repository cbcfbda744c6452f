#!/usr/bin/python3
"""Seed corpora for the fuzzers, from the shipped meshes and examples.

    make_seeds.py OUT_DIR

writes OUT_DIR/{msh,stl,off,obj,problem,saved}/: the small shipped .msh files (Gmsh 2.2 and 4.1), the
box with a spherical cavity (tests/data) converted to ASCII STL, binary STL, OFF and OBJ (polygons and the OBJ
corner forms included), a unit cube alone, with a cavity and overlapping another in every format
(small: under the harnesses' 4 kB input limit), the shipped example problems (.json) and saved
precomputations' headers."""
import os
import shutil
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))


def read_msh22(path):
    """Nodes and 3-node triangles of a Gmsh 2.2 ASCII file (enough for seeding)."""
    lines = open(path).read().split("\n")
    i = lines.index("$Nodes")
    n = int(lines[i + 1])
    tags, verts = {}, []
    for k in range(n):
        f = lines[i + 2 + k].split()
        tags[int(f[0])] = len(verts)
        verts.append(tuple(float(v) for v in f[1:4]))
    i = lines.index("$Elements")
    tris = []
    for k in range(int(lines[i + 1])):
        f = [int(v) for v in lines[i + 2 + k].split()]
        if f[1] == 2:
            tris.append(tuple(tags[t] for t in f[3 + f[2]:]))
    return verts, tris


def write(path, data):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb" if isinstance(data, bytes) else "w") as f:
        f.write(data)


# A unit cube (8 vertices, 12 outward triangles) and a second one inside it (a cavity) or
# overlapping it: small valid inputs (under the harnesses' 4 kB limit) that reach validation,
# orientation and the intersection check.
CUBE_V = [(float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1)) for i in range(8)]
CUBE_T = [(0, 2, 3), (0, 3, 1), (4, 5, 7), (4, 7, 6), (0, 1, 5), (0, 5, 4), (2, 6, 7), (2, 7, 3), (0, 4, 6), (0, 6, 2), (1, 3, 7), (1, 7, 5)]


def two_cubes(scale, shift):
    v = CUBE_V + [tuple(scale * c + shift for c in p) for p in CUBE_V]
    return v, CUBE_T + [tuple(8 + i for i in t) for t in CUBE_T]


def small_seeds(out):
    shapes = {"cube": (CUBE_V, CUBE_T), "cavity": two_cubes(0.5, 0.25), "overlap": two_cubes(1.0, 0.5)}
    for name, (v, t) in shapes.items():
        write(os.path.join(out, "off", name + ".off"), "OFF\n%d %d 0\n" % (len(v), len(t)) + "".join("%g %g %g\n" % p for p in v) + "".join("3 %d %d %d\n" % f for f in t))
        write(os.path.join(out, "obj", name + ".obj"), "".join("v %g %g %g\n" % p for p in v) + "".join("f %d %d %d\n" % (a + 1, b + 1, c + 1) for a, b, c in t))
        write(os.path.join(out, "stl", name + ".stl"), "solid s\n" + "".join("facet normal 0 0 0\nouter loop\n" + "".join("vertex %g %g %g\n" % v[c] for c in f) + "endloop\nendfacet\n" for f in t) + "endsolid s\n")
        nodes22 = "".join("%d %g %g %g\n" % ((i + 1,) + p) for i, p in enumerate(v))
        elems22 = "".join("%d 2 2 1 1 %d %d %d\n" % (k + 1, a + 1, b + 1, c + 1) for k, (a, b, c) in enumerate(t))
        write(os.path.join(out, "msh", name + "_v22.msh"), "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n2 1 \"body\"\n$EndPhysicalNames\n"
              "$Nodes\n%d\n%s$EndNodes\n$Elements\n%d\n%s$EndElements\n" % (len(v), nodes22, len(t), elems22))
        nodes41 = "1 %d 1 %d\n2 1 0 %d\n" % (len(v), len(v), len(v)) + "".join("%d\n" % (i + 1) for i in range(len(v))) + "".join("%g %g %g\n" % p for p in v)
        elems41 = "1 %d 1 %d\n2 1 2 %d\n" % (len(t), len(t), len(t)) + "".join("%d %d %d %d\n" % (k + 1, a + 1, b + 1, c + 1) for k, (a, b, c) in enumerate(t))
        write(os.path.join(out, "msh", name + "_v41.msh"), "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n%s$EndNodes\n$Elements\n%s$EndElements\n" % (nodes41, elems41))


def main():
    out = sys.argv[1]
    os.makedirs(os.path.join(out, "msh"), exist_ok=True)
    for name in ("cube_l0.msh", "sphere_l0.msh"):
        shutil.copy(os.path.join(ROOT, "meshes", name), os.path.join(out, "msh", name))
    for name in ("box_sphere_cavity_v22.msh", "box_sphere_cavity_v41.msh"):
        shutil.copy(os.path.join(ROOT, "tests", "data", "meshes", name), os.path.join(out, "msh", name))
    v, t = read_msh22(os.path.join(ROOT, "tests", "data", "meshes", "box_sphere_cavity_v22.msh"))
    normal = "0 0 1"
    ascii_stl = ["solid cube"] + [
        "facet normal %s\n outer loop\n%s\n endloop\nendfacet" % (normal, "\n".join("  vertex %.9g %.9g %.9g" % v[c] for c in tri))
        for tri in t] + ["endsolid cube"]
    write(os.path.join(out, "stl", "cube_ascii.stl"), "\n".join(ascii_stl) + "\n")
    binary = bytearray(b"binary cube".ljust(80, b" ")) + struct.pack("<I", len(t))
    for tri in t:
        binary += struct.pack("<3f", 0, 0, 1) + b"".join(struct.pack("<3f", *v[c]) for c in tri) + b"\0\0"
    write(os.path.join(out, "stl", "cube_binary.stl"), bytes(binary))
    off = ["OFF", "# box_sphere_cavity", "%d %d 0" % (len(v), len(t))] + ["%.9g %.9g %.9g" % p for p in v]
    off += ["3 %d %d %d" % tri for tri in t[:-2]]
    off += ["4 %d %d %d %d" % (t[-2][0], t[-2][1], t[-2][2], t[-1][2])]  # a quad, fan-triangulated
    write(os.path.join(out, "off", "cube.off"), "\n".join(off) + "\n")
    obj = ["# box_sphere_cavity"] + ["v %.9g %.9g %.9g" % p for p in v] + ["vn 0 0 1", "vt 0 0"]
    forms = ["%d", "%d/1", "%d//1", "%d/1/1"]
    for k, tri in enumerate(t):
        obj.append("f " + " ".join(forms[(k + j) % 4] % (c + 1) for j, c in enumerate(tri)))
    obj.append("f -1 -2 -3")
    write(os.path.join(out, "obj", "cube.obj"), "\n".join(obj) + "\n")
    small_seeds(out)
    os.makedirs(os.path.join(out, "problem"), exist_ok=True)
    examples = os.path.join(ROOT, "meshes", "examples")
    for name in sorted(os.listdir(examples)):
        if name.endswith(".json"):
            shutil.copy(os.path.join(examples, name), os.path.join(out, "problem", name))
    saved_seeds(out)


def saved_seeds(out):
    """Saved precomputations' headers (io/saved_file.hpp): the right kind and format with a
    length and checksum that do not hold, another kind, another format, a damaged field."""
    def header(kind="contact precomputation", fmt="2", size="4096", checksum="0123456789abcdef", tail=b"", unhashed="unhashed:"):
        text = "hssbem saved file\nkind: %s\nformat: %s\nbytes: %s\nchecksum: %s\n%s\n" % (kind, fmt, size, checksum, unhashed)
        return text.encode().ljust(4096, b"\0") + tail
    seeds = {"empty_body": header(), "with_body": header(size="4184", tail=b"\x89HDF\r\n\x1a\n" + bytes(80)),
             "unhashed_range": header(size="4184", tail=bytes(88), unhashed="unhashed: 1010+10"),
             "bad_range": header(size="4184", tail=bytes(88), unhashed="unhashed: 1060+ffff"),
             "other_kind": header(kind="scene precomputation"), "other_format": header(fmt="7"),
             "bad_size": header(size="5x2"), "bad_checksum": header(checksum="zz")}
    for name, data in seeds.items():
        write(os.path.join(out, "saved", name + ".pre"), data)


if __name__ == "__main__":
    main()
