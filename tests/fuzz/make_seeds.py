#!/usr/bin/python3
"""Seed corpora for the fuzzers, from the shipped meshes and examples.

    make_seeds.py OUT_DIR

writes OUT_DIR/{msh,stl,off,obj,problem}/: the small shipped .msh files (Gmsh 2.2 and 4.1), the
box with a spherical cavity (tests/data) converted to ASCII STL, binary STL, OFF and OBJ (polygons and the OBJ
corner forms included), and the shipped example problems."""
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
    os.makedirs(os.path.join(out, "problem"), exist_ok=True)
    examples = os.path.join(ROOT, "meshes", "examples")
    for name in sorted(os.listdir(examples)):
        shutil.copy(os.path.join(examples, name), os.path.join(out, "problem", name))


if __name__ == "__main__":
    main()
