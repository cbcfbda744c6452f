#!/usr/bin/python3
"""Generate the surface meshes shipped with hssbem (meshes/*.msh).

Every mesh is a closed, manifold, consistently and outward oriented triangulation (normals from the
node order point out of the solid; for the hollow sphere the inner surface's normals point into the
cavity).  Files are Gmsh ASCII .msh 4.1 with 3-node triangles only, one discrete surface entity and
one named physical group per region, node tags 1..N (vertex i of the mesh is node tag i+1, all nodes
are stored in one block in tag order), element tags 1..T in file order.  Every written file is read
back, parsed and checked; any failed check aborts with a non-zero exit status.

Uses the Debian gmsh Python module: run with /usr/bin/python3.

Usage
  scripts/gen_meshes.py                       # all families into <repo>/meshes
  scripts/gen_meshes.py --out DIR --only cube # one family (sphere, cube, cardioid, disk_organ,
                                              # hollow_sphere)
  scripts/gen_meshes.py --sphere-triangles 20000 --out s.msh   # sphere with ~N triangles
  scripts/gen_meshes.py --sphere-size 0.05 --out s.msh          # sphere with gmsh size h
        [--radius R] [--refine K]   (K nested 1:4 refinements with projection onto the sphere)
  scripts/gen_meshes.py --disk-triangles 20000 --out d.msh     # disk organ with ~N triangles
  scripts/gen_meshes.py --disk-size 0.02 --out d.msh            # disk organ with gmsh size h
  scripts/gen_meshes.py --disk-triangles 10000 --disk-pair 0.01 --out p.msh  # two organs face to face
        [--refine K]   (K nested 1:4 refinements with projection onto the ellipsoid)
  scripts/gen_meshes.py --cardioid-triangles 20000 --out c.msh  # cardioid with exactly N triangles
  scripts/gen_meshes.py --check-examples [--out DIR]   # check meshes/examples/*.json selectors
  scripts/gen_meshes.py --hertz-size HC --out h.msh     # Hertz contact: a hemisphere of radius R
        [--radius R] [--hertz-far HF] [--hertz-fine-radius RF] [--hertz-pair GAP]
        (pole at the origin, flat face up at z = R; size HC within RF of the pole, growing to HF;
        --hertz-pair adds its mirror image below, pole at z = -GAP: two bodies in one mesh)
  scripts/gen_meshes.py --block-size HC --out b.msh      # a contact block (friction: sliding, Mindlin)
        [--block-width W] [--block-depth D] [--block-far HF] [--block-fine-radius RF]
        (the box [-W/2, W/2]^2 x [-D, 0], top face at z = 0; size HC within RF of the top's centre,
        growing to HF; regions top, bottom, sides)

Nested refinement (sphere, cube, hollow sphere, disk organ; not the cardioid): every triangle
(a, b, c) is split into (a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca) with the new mid-edge vertices
projected onto the exact surface.  The vertices of the coarse level keep their indices: they are
the first vertices of the fine level.
"""

import argparse
import json
import math
import os
import sys

import numpy as np

try:
    import gmsh
except ImportError:  # pragma: no cover
    sys.exit("gen_meshes.py: cannot import gmsh; run it with /usr/bin/python3 (Debian python3-gmsh)")


class MeshCheckError(RuntimeError):
    pass


REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_OUT = os.path.join(REPO, "meshes")
FAMILIES = ("sphere", "cube", "cardioid", "disk_organ", "hollow_sphere")


# ------------------------------------------------------------------------------------------------
# gmsh helpers


def gmsh_start():
    gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("General.Verbosity", 1)
    gmsh.option.setNumber("General.NumThreads", 1)


def gmsh_triangles():
    """All 3-node triangles of the current gmsh model as (V, T), nodes compacted to used ones."""
    ntags, coords, _ = gmsh.model.mesh.getNodes()
    X = np.asarray(coords, float).reshape(-1, 3)
    _, enodes = gmsh.model.mesh.getElementsByType(2)
    enodes = np.asarray(enodes, np.int64).reshape(-1, 3)
    pos = {int(t): i for i, t in enumerate(ntags)}
    T = np.vectorize(pos.__getitem__)(enodes) if len(enodes) else enodes
    used = np.unique(T)
    remap = -np.ones(len(X), np.int64)
    remap[used] = np.arange(len(used))
    return X[used].copy(), remap[T]


def mesh_occ_surface(build, h, curvature=0, hmin=0.0):
    """Mesh the surface of the OCC solid made by build() with target size h; returns (V, T)."""
    gmsh_start()
    try:
        gmsh.model.add("m")
        build()
        gmsh.model.occ.synchronize()
        gmsh.option.setNumber("Mesh.MeshSizeMin", hmin)
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", curvature)
        gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
        gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
        gmsh.option.setNumber("Mesh.Algorithm", 6)  # Frontal-Delaunay
        gmsh.model.mesh.generate(2)
        V, T = gmsh_triangles()
    finally:
        gmsh.finalize()
    return V, T


def mesh_by_count(mesher, target, h0):
    """Search the gmsh size h so that mesher(h) has about `target` triangles (deterministic)."""
    best = None
    h = h0
    for _ in range(8):
        V, T = mesher(h)
        n = len(T)
        if best is None or abs(n - target) < abs(len(best[1]) - target):
            best = (V, T, h)
        if abs(n - target) <= 0.01 * target:
            break
        h = h * math.sqrt(n / target)
    return best


# ------------------------------------------------------------------------------------------------
# geometry helpers


def signed_volume(V, T):
    a, b, c = V[T[:, 0]], V[T[:, 1]], V[T[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def components(nv, T):
    """Connected components of the triangles (through shared vertices); label per triangle."""
    parent = np.arange(nv)

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for a, b, c in T:
        ra, rb, rc = find(a), find(b), find(c)
        parent[rb] = ra
        parent[find(rc)] = ra
    roots = np.array([find(i) for i in range(nv)])
    _, lab = np.unique(roots[T[:, 0]], return_inverse=True)
    return lab


def subdivide(V, T, project):
    """1:4 split; old vertices keep indices, new mid-edge vertex of edge k gets index nv+k (edges in
    lexicographic order of (min, max)); children of triangle t are 4t..4t+3."""
    nv = len(V)
    E = np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]])
    Es = np.sort(E, axis=1)
    uniq, inv = np.unique(Es, axis=0, return_inverse=True)
    inv = inv.reshape(3, len(T)).T  # inv[t, k]: edge id of edge k of triangle t
    mids = project(uniq[:, 0], uniq[:, 1])
    a, b, c = T[:, 0], T[:, 1], T[:, 2]
    ab, bc, ca = nv + inv[:, 0], nv + inv[:, 1], nv + inv[:, 2]
    child = np.stack([np.stack([a, ab, ca], 1), np.stack([ab, b, bc], 1),
                      np.stack([ca, bc, c], 1), np.stack([ab, bc, ca], 1)], 1).reshape(-1, 3)
    return np.vstack([V, mids]), child


def sphere_projector(V, center, radius):
    def project(i, j):
        m = 0.5 * (V[i] + V[j]) - center
        return center + radius[i][:, None] * m / np.linalg.norm(m, axis=1)[:, None]
    return project


def orient_outward(V, T):
    """Flip the whole (single component) triangulation if its signed volume is negative."""
    if signed_volume(V, T) < 0:
        T = T[:, [0, 2, 1]]
    return T


# ------------------------------------------------------------------------------------------------
# checks


def check_mesh(name, V, T, expect_volume_signs, min_angle_deg=1.0):
    """Closed, manifold, consistently oriented; per component volume sign as expected (sorted by
    |volume| descending); no orphan vertices, no degenerate or duplicate triangles."""
    def fail(msg):
        raise MeshCheckError(f"{name}: {msg}")

    T = np.asarray(T)
    nv, nt = len(V), len(T)
    if nt == 0:
        fail("no triangles")
    if T.min() < 0 or T.max() >= nv:
        fail("triangle index out of range")
    if np.any(T[:, 0] == T[:, 1]) or np.any(T[:, 1] == T[:, 2]) or np.any(T[:, 0] == T[:, 2]):
        fail("triangle with a repeated vertex")
    used = np.zeros(nv, bool)
    used[T.ravel()] = True
    if not used.all():
        fail(f"{(~used).sum()} orphan vertices (first {np.flatnonzero(~used)[0]})")
    if len(np.unique(np.sort(T, axis=1), axis=0)) != nt:
        fail("duplicate triangles")
    # directed edges: each exactly once, and its reverse exactly once
    D = np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]]).astype(np.int64)
    key = D[:, 0] * nv + D[:, 1]
    ukey, cnt = np.unique(key, return_counts=True)
    if np.any(cnt != 1):
        k = ukey[cnt != 1][0]
        fail(f"directed edge {k // nv}->{k % nv} used {cnt[cnt != 1][0]} times "
             "(inconsistent orientation or non-manifold edge)")
    rkey = D[:, 1] * nv + D[:, 0]
    found = np.isin(rkey, ukey)
    if not found.all():
        i = np.flatnonzero(~found)[0]
        fail(f"edge {D[i, 0]}-{D[i, 1]} has only one triangle (open surface)")
    # vertex manifoldness: the link of every vertex is a single cycle
    nxt = {}
    for t in T:
        for k in range(3):
            v, p, q = t[k], t[(k + 1) % 3], t[(k + 2) % 3]
            nxt.setdefault(v, {})[p] = q
    for v, m in nxt.items():
        start = next(iter(m))
        p, steps = start, 0
        while True:
            p = m[p]
            steps += 1
            if p == start or steps > len(m):
                break
        if steps != len(m):
            fail(f"vertex {v} is non-manifold (its triangle fan is not a single disc)")
    a, b, c = V[T[:, 0]], V[T[:, 1]], V[T[:, 2]]
    area2 = np.linalg.norm(np.cross(b - a, c - a), axis=1)
    if area2.min() <= 1e-14 * max(1.0, float(np.abs(V).max())) ** 2:
        fail(f"degenerate triangle {int(np.argmin(area2))}")
    ang = min_angles(V, T)
    if ang.min() < min_angle_deg:
        fail(f"triangle {int(np.argmin(ang))} has a {ang.min():.3g} degree angle")
    # components: Euler characteristic 2 (sphere topology) and volume sign
    lab = components(nv, T)
    ncomp = lab.max() + 1
    if ncomp != len(expect_volume_signs):
        fail(f"{ncomp} connected components, expected {len(expect_volume_signs)}")
    vols = []
    for k in range(ncomp):
        Tk = T[lab == k]
        nvk = len(np.unique(Tk))
        nek = 3 * len(Tk) // 2
        if nvk - nek + len(Tk) != 2:
            fail(f"component {k}: Euler characteristic {nvk - nek + len(Tk)} != 2")
        vols.append(signed_volume(V, Tk))
    vols = sorted(vols, key=lambda x: -abs(x))
    for vol, s in zip(vols, expect_volume_signs):
        if vol * s <= 0:
            fail(f"component signed volume {vol:.6g} has the wrong sign (expected {'+' if s > 0 else '-'}); "
                 "normals do not point out of the solid")
    return {"triangles": nt, "vertices": nv, "volumes": vols, "min_angle": float(ang.min())}


def min_angles(V, T):
    a, b, c = V[T[:, 0]], V[T[:, 1]], V[T[:, 2]]

    def ang(p, q, r):
        u, v = q - p, r - p
        cs = np.einsum("ij,ij->i", u, v) / (np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1))
        return np.degrees(np.arccos(np.clip(cs, -1, 1)))

    return np.minimum(np.minimum(ang(a, b, c), ang(b, c, a)), ang(c, a, b))


def check_normals_star(name, V, T, center, sign=+1):
    """For star-shaped (convex) closed parts: every facet normal points away from (sign=+1) or
    toward (sign=-1) the given centre."""
    a, b, c = V[T[:, 0]], V[T[:, 1]], V[T[:, 2]]
    n = np.cross(b - a, c - a)
    d = np.einsum("ij,ij->i", n, (a + b + c) / 3 - center) * sign
    if d.min() <= 0:
        raise MeshCheckError(f"{name}: triangle {int(np.argmin(d))} normal points the wrong way")


# ------------------------------------------------------------------------------------------------
# .msh 4.1 writing and reading


def write_msh(path, V, T, region_of_tri, region_names):
    """Write V, T with physical groups 1..len(region_names) (region_of_tri: 0-based index into
    region_names).  Triangles must be sorted by region (so file order == element tag order)."""
    if np.any(np.diff(region_of_tri) < 0):
        raise MeshCheckError(f"{path}: triangles not sorted by region")
    for r, nm in enumerate(region_names):
        if not np.any(region_of_tri == r):
            raise MeshCheckError(f"{path}: region '{nm}' is empty")
    gmsh_start()
    try:
        gmsh.model.add(os.path.splitext(os.path.basename(path))[0])
        ents = [gmsh.model.addDiscreteEntity(2, r + 1) for r in range(len(region_names))]
        # all nodes in the first entity: one block, tags 1..N in file order
        gmsh.model.mesh.addNodes(2, ents[0], list(range(1, len(V) + 1)), V.ravel().tolist())
        for r, e in enumerate(ents):
            idx = np.flatnonzero(region_of_tri == r)
            gmsh.model.mesh.addElementsByType(e, 2, (idx + 1).tolist(), (T[idx] + 1).ravel().tolist())
        for r, (e, nm) in enumerate(zip(ents, region_names)):
            gmsh.model.addPhysicalGroup(2, [e], r + 1)
            gmsh.model.setPhysicalName(2, r + 1, nm)
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.option.setNumber("Mesh.Binary", 0)
        gmsh.option.setNumber("Mesh.SaveAll", 0)
        gmsh.option.setNumber("Mesh.SaveParametric", 0)
        gmsh.write(path)
    finally:
        gmsh.finalize()


def read_msh41(path):
    """Minimal independent reader of ASCII .msh 4.1 surface meshes -> (V, T, region_tag, names).
    Vertices in ascending node tag order; triangles in file order."""
    with open(path) as f:
        lines = [ln.strip() for ln in f]
    sec = {}
    i = 0
    while i < len(lines):
        if lines[i].startswith("$") and not lines[i].startswith("$End"):
            name = lines[i][1:]
            j = lines.index("$End" + name, i)
            sec[name] = lines[i + 1:j]
            i = j + 1
        else:
            i += 1
    if sec["MeshFormat"][0].split()[:2] != ["4.1", "0"]:
        raise MeshCheckError(f"{path}: not ASCII msh 4.1")
    names = {}
    for ln in sec.get("PhysicalNames", [])[1:]:
        d, t, nm = ln.split(maxsplit=2)
        if int(d) != 2:
            raise MeshCheckError(f"{path}: physical group of dimension {d}")
        names[nm.strip('"')] = int(t)
    ent = sec["Entities"]
    npnt, ncur, nsur, nvol = map(int, ent[0].split())
    if (npnt, ncur, nvol) != (0, 0, 0):
        raise MeshCheckError(f"{path}: entities other than surfaces")
    ent_phys = {}
    for ln in ent[1:1 + nsur]:
        w = ln.split()
        nphys = int(w[7])
        ent_phys[int(w[0])] = [int(x) for x in w[8:8 + nphys]]
        if nphys != 1:
            raise MeshCheckError(f"{path}: surface {w[0]} has {nphys} physical tags")
    nod = sec["Nodes"]
    nblocks, nnodes = map(int, nod[0].split()[:2])
    k = 1
    tags, xyz = [], []
    for _ in range(nblocks):
        d, et, par, n = map(int, nod[k].split())
        if d != 2 or par != 0:
            raise MeshCheckError(f"{path}: node block of dimension {d}")
        tags += [int(x) for x in nod[k + 1:k + 1 + n]]
        xyz += [[float(x) for x in ln.split()] for ln in nod[k + 1 + n:k + 1 + 2 * n]]
        k += 1 + 2 * n
    if len(tags) != nnodes:
        raise MeshCheckError(f"{path}: node count mismatch")
    tags = np.array(tags)
    order = np.argsort(tags, kind="stable")
    V = np.array(xyz)[order]
    pos = {int(t): i for i, t in enumerate(tags[order])}
    el = sec["Elements"]
    nblocks, nel = map(int, el[0].split()[:2])
    k = 1
    T, reg, etags = [], [], []
    for _ in range(nblocks):
        d, et, typ, n = map(int, el[k].split())
        if d != 2 or typ != 2:
            raise MeshCheckError(f"{path}: element block of dim {d} type {typ} (want triangles)")
        for ln in el[k + 1:k + 1 + n]:
            w = [int(x) for x in ln.split()]
            etags.append(w[0])
            T.append([pos[x] for x in w[1:4]])
            reg.append(ent_phys[et][0])
        k += 1 + n
    if len(T) != nel:
        raise MeshCheckError(f"{path}: element count mismatch")
    if etags != list(range(1, nel + 1)):
        raise MeshCheckError(f"{path}: element tags are not 1..T in file order")
    if list(tags) != list(range(1, nnodes + 1)):
        raise MeshCheckError(f"{path}: node tags are not 1..N in file order")
    return V, np.array(T, np.int64), np.array(reg), names


def save(outdir, fname, V, T, region_of_tri, region_names, expect_volume_signs, log):
    """Sort by region, write, read back (own parser and gmsh), compare and check."""
    order = np.argsort(region_of_tri, kind="stable")
    T, region_of_tri = T[order], region_of_tri[order]
    stats = check_mesh(fname, V, T, expect_volume_signs)
    path = os.path.join(outdir, fname)
    write_msh(path, V, T, region_of_tri, region_names)
    V2, T2, reg2, names2 = read_msh41(path)
    if not (np.array_equal(T2, T) and np.allclose(V2, V, rtol=0, atol=1e-15)
            and np.array_equal(reg2, region_of_tri + 1)
            and names2 == {nm: r + 1 for r, nm in enumerate(region_names)}):
        raise MeshCheckError(f"{path}: file read back differs from what was written")
    check_mesh(path, V2, T2, expect_volume_signs)
    # gmsh itself must accept it and see exactly these triangles and nodes
    gmsh_start()
    try:
        gmsh.open(path)
        et, _ = gmsh.model.mesh.getElementsByType(2)
        nt_all = sum(len(t) for t in gmsh.model.mesh.getElements()[1])
        nn = len(gmsh.model.mesh.getNodes()[0])
    finally:
        gmsh.finalize()
    if len(et) != len(T) or nt_all != len(T) or nn != len(V):
        raise MeshCheckError(f"{path}: gmsh reads {len(et)}/{nt_all} elements, {nn} nodes")
    counts = {nm: int((region_of_tri == r).sum()) for r, nm in enumerate(region_names)}
    log.append((fname, stats["triangles"], stats["vertices"], counts, stats["min_angle"],
                stats["volumes"]))
    print(f"  {fname}: {stats['triangles']} triangles, {stats['vertices']} vertices, regions "
          + ", ".join(f"{k}={v}" for k, v in counts.items())
          + f", min angle {stats['min_angle']:.1f} deg, volume(s) "
          + ", ".join(f"{v:.5f}" for v in stats["volumes"]), flush=True)
    return T, region_of_tri


# ------------------------------------------------------------------------------------------------
# families


def sphere_mesh_h(radius, h):
    def build():
        gmsh.model.occ.addSphere(0, 0, 0, radius)
    V, T = mesh_occ_surface(build, h)
    V = radius * V / np.linalg.norm(V, axis=1)[:, None]  # exactly on the sphere
    return V, orient_outward(V, T)


def sphere_mesh_count(radius, target):
    h0 = radius * math.sqrt(4 * math.pi * 4 / (math.sqrt(3) * target)) * 1.05
    V, T, h = mesh_by_count(lambda h: sphere_mesh_h(radius, h), target, h0)
    return V, T


def sphere_regions(V, T):
    zc = V[T].mean(axis=1)[:, 2]
    reg = np.full(len(T), 2)  # band
    reg[zc > 0.5] = 0         # north
    reg[zc < -0.5] = 1        # south
    return reg


SPHERE_REGIONS = ["north", "south", "band"]


def refine_sphere(V, T, radius_per_vertex, center=np.zeros(3)):
    rad = np.asarray(radius_per_vertex, float)
    V2, T2 = subdivide(V, T, sphere_projector(V, center, rad))
    # radius of new vertices = radius of the edge end points (both on the same sphere)
    E = np.unique(np.sort(np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]]), axis=1), axis=0)
    rad2 = np.concatenate([rad, rad[E[:, 0]]])
    return V2, T2, rad2


def gen_sphere(outdir, log):
    V, T = sphere_mesh_count(1.0, 500)
    rad = np.ones(len(V))
    for lev in range(3):
        if lev > 0:
            V, T, rad = refine_sphere(V, T, rad)
        check_normals_star(f"sphere_l{lev}", V, T, np.zeros(3))
        save(outdir, f"sphere_l{lev}.msh", V, T, sphere_regions(V, T), SPHERE_REGIONS, [+1], log)


def gen_hollow_sphere(outdir, log):
    Vo, To = sphere_mesh_count(1.0, 500)     # identical to sphere_l0
    Vi, Ti = sphere_mesh_count(0.5, 300)
    Ti = Ti[:, [0, 2, 1]]                     # cavity: normals toward the centre
    V = np.vstack([Vo, Vi])
    T = np.vstack([To, Ti + len(Vo)])
    reg = np.concatenate([np.zeros(len(To), int), np.ones(len(Ti), int)])
    rad = np.concatenate([np.ones(len(Vo)), 0.5 * np.ones(len(Vi))])
    for lev in range(2):
        if lev > 0:
            V, T, rad = refine_sphere(V, T, rad)
            reg = np.repeat(reg, 4)
        outer = reg == 0
        check_normals_star(f"hollow_sphere_l{lev} outer", V, T[outer], np.zeros(3), +1)
        check_normals_star(f"hollow_sphere_l{lev} inner", V, T[~outer], np.zeros(3), -1)
        T, reg = save(outdir, f"hollow_sphere_l{lev}.msh", V, T, reg, ["outer", "inner"], [+1, -1], log)
    # The Lame check is limited by the flat facets of the small inner sphere: a companion mesh with
    # its cavity as finely resolved (relative to its radius) as the outer surface, and then some.
    Vo, To = sphere_mesh_count(1.0, 2000)
    Vi, Ti = sphere_mesh_count(0.5, 2400)
    Ti = Ti[:, [0, 2, 1]]
    V = np.vstack([Vo, Vi])
    T = np.vstack([To, Ti + len(Vo)])
    reg = np.concatenate([np.zeros(len(To), int), np.ones(len(Ti), int)])
    check_normals_star("hollow_sphere_fine outer", V, T[reg == 0], np.zeros(3), +1)
    check_normals_star("hollow_sphere_fine inner", V, T[reg == 1], np.zeros(3), -1)
    save(outdir, "hollow_sphere_fine.msh", V, T, reg, ["outer", "inner"], [+1, -1], log)


def cube_mesh(n):
    """Unit cube, each face an n x n grid of squares split along the same diagonal; regions per face.
    Vertices sorted lexicographically by (x, y, z); face order x0, x1, y0, y1, z0, z1."""
    ex, ey, ez = np.eye(3, dtype=int)
    # (origin, u, v) with u x v = outward normal
    faces = [
        (np.zeros(3, int), ez, ey),   # x0: z x y = -x
        (ex, ey, ez),                 # x1
        (np.zeros(3, int), ex, ez),   # y0: x x z = -y
        (ey, ez, ex),                 # y1
        (np.zeros(3, int), ey, ex),   # z0: y x x = -z
        (ez, ex, ey),                 # z1
    ]
    tris, reg = [], []
    for f, (o, u, v) in enumerate(faces):
        for i in range(n):
            for j in range(n):
                p00 = o * n + i * u + j * v
                p10, p11, p01 = p00 + u, p00 + u + v, p00 + v
                tris += [(p00, p10, p11), (p00, p11, p01)]
                reg += [f, f]
    P = np.array(tris).reshape(-1, 3)
    keys = (P[:, 0] * (n + 1) + P[:, 1]) * (n + 1) + P[:, 2]
    ukeys, inv = np.unique(keys, return_inverse=True)
    V = np.stack([ukeys // (n + 1) ** 2, (ukeys // (n + 1)) % (n + 1), ukeys % (n + 1)], 1) / n
    return V.astype(float), inv.reshape(-1, 3), np.array(reg)


CUBE_REGIONS = ["x0", "x1", "y0", "y1", "z0", "z1"]


def gen_cube(outdir, log):
    V, T, reg = cube_mesh(4)
    T, reg = save(outdir, "cube_l0.msh", V, T, reg, CUBE_REGIONS, [+1], log)
    V1, T1 = subdivide(V, T, lambda i, j: 0.5 * (V[i] + V[j]))
    reg1 = np.repeat(reg, 4)
    # nested refinement must equal the structured 8 x 8 triangulation
    Vg, Tg, rg = cube_mesh(8)
    key = lambda VV, TT: sorted(tuple(sorted(tuple(np.round(VV[k] * 8).astype(int)) for k in t)) for t in TT)
    if key(V1, T1) != key(Vg, Tg):
        raise MeshCheckError("cube_l1: nested refinement differs from the 8x8 structured grid")
    save(outdir, "cube_l1.msh", V1, T1, reg1, CUBE_REGIONS, [+1], log)


# cardioid body of revolution ----------------------------------------------------------------------
CARD_A = 0.5
CARD_L = 4 * CARD_A  # arc length of the meridian from cusp to tip


def cardioid_point(s, phi):
    """Meridian r(theta) = a(1 - cos theta) parametrised by arc length s in [0, 4a] from the cusp,
    revolved about the z axis; the cusp is at the origin, the tip at z = 2a."""
    s = np.asarray(s, float)
    th = 2 * np.arccos(np.clip(1 - s / (4 * CARD_A), -1, 1))
    r = CARD_A * (1 - np.cos(th))
    z = -r * np.cos(th)
    rho = np.where((s <= 0) | (s >= CARD_L), 0.0, r * np.sin(th))  # poles exactly on the axis
    z = z + 0.0  # no negative zero at the cusp
    return np.stack([rho * np.cos(phi), rho * np.sin(phi), z], -1)


def cardioid_rings(target):
    """Ring-stitched triangulation with about isotropic triangles and exactly `target` triangles
    (target even): rings at uniform arc length, ring k has n_k points (>= 3) with
    2 * sum(n_k) = target.  Returns (V, T, s, phi) with s, phi the parameters of each vertex."""
    assert target % 2 == 0
    want = target // 2
    best = None
    for m in range(4, max(200, int(2.2 * math.sqrt(target)))):
        ds = CARD_L / m
        h = ds * 2 / math.sqrt(3)
        sk = ds * np.arange(1, m)
        rho = np.hypot(*cardioid_point(sk, 0.0)[:, :2].T)
        n = np.maximum(3, np.round(2 * math.pi * rho / h)).astype(int)
        if best is None or abs(n.sum() - want) < abs(best[2].sum() - want):
            best = (m, sk, n, rho)
    m, sk, n, rho = best
    # adjust ring counts deterministically to hit the target exactly
    while n.sum() != want:
        d = 1 if n.sum() < want else -1
        ratio = n / (2 * math.pi * rho)  # points per unit length
        k = int(np.argmin(ratio)) if d > 0 else int(np.argmax(np.where(n > 3, ratio, -1)))
        n[k] += d
    svals = [0.0]
    phis = [0.0]
    rings = []
    idx = 1
    for k in range(m - 1):
        off = 0.5 * (k % 2)
        ph = 2 * math.pi * (np.arange(n[k]) + off) / n[k]
        rings.append((np.arange(idx, idx + n[k]), ph))
        svals += [sk[k]] * n[k]
        phis += list(ph)
        idx += n[k]
    svals.append(CARD_L)
    phis.append(0.0)
    tip = idx
    T = []
    ids, _ = rings[0]
    for j in range(len(ids)):
        T.append((0, ids[(j + 1) % len(ids)], ids[j]))
    for (A, pa), (B, pb) in zip(rings[:-1], rings[1:]):
        T += stitch(A, pa, B, pb)
    ids, _ = rings[-1]
    for j in range(len(ids)):
        T.append((ids[j], ids[(j + 1) % len(ids)], tip))
    s = np.array(svals)
    phi = np.array(phis)
    V = cardioid_point(s, phi)
    T = np.array(T)
    if len(T) != target:
        raise MeshCheckError(f"cardioid: {len(T)} triangles, wanted {target}")
    return V, orient_outward(V, T), s, phi


def stitch(A, pa, B, pb):
    """Triangulate the band between two rings (angles increasing, evenly spaced)."""
    nA, nB = len(A), len(B)
    twopi = 2 * math.pi
    j0 = int(np.argmin(np.abs((pb - pa[0] + math.pi) % twopi - math.pi)))
    b0 = pa[0] + ((pb[j0] - pa[0] + math.pi) % twopi - math.pi)
    aang = lambda i: pa[0] + twopi * i / nA
    bang = lambda j: b0 + twopi * j / nB
    i = j = 0
    T = []
    while i < nA or j < nB:
        if j == nB or (i < nA and aang(i + 1) <= bang(j + 1)):
            T.append((A[i % nA], A[(i + 1) % nA], B[(j0 + j) % nB]))
            i += 1
        else:
            T.append((A[i % nA], B[(j0 + j + 1) % nB], B[(j0 + j) % nB]))
            j += 1
    return T


CARD_ZMIN = -CARD_A / 4          # lowest point of the body (the rim around the cusp)
CARD_ZMAX = 2 * CARD_A            # the tip
CARD_BASE_Z = CARD_ZMIN + 0.15 * (CARD_ZMAX - CARD_ZMIN)


def cardioid_regions(V, T):
    zc = V[T].mean(axis=1)[:, 2]
    return np.where(zc < CARD_BASE_Z, 0, 1)  # base, body


def gen_cardioid(outdir, log):
    V, T, s, phi = cardioid_rings(832)
    T, _ = save(outdir, "cardioid_832.msh", V, T, cardioid_regions(V, T), ["base", "body"], [+1], log)
    # not nested: a fresh ring mesh has better triangles near the cusp than a 1:4 split
    V2, T2, _, _ = cardioid_rings(4 * 832)
    save(outdir, "cardioid_fine.msh", V2, T2, cardioid_regions(V2, T2), ["base", "body"], [+1], log)


# disk-shaped organ ---------------------------------------------------------------------------------
DISK_AXES = np.array([1.0, 0.8, 0.3])


def disk_mesh_h(h):
    def build():
        tag = gmsh.model.occ.addSphere(0, 0, 0, 1.0)
        gmsh.model.occ.dilate([(3, tag)], 0, 0, 0, *DISK_AXES)
    V, T = mesh_occ_surface(build, h, curvature=10)
    V = project_ellipsoid(V)
    return V, orient_outward(V, T)


def project_ellipsoid(X):
    q = np.sqrt(((X / DISK_AXES) ** 2).sum(axis=1))
    return X / q[:, None]


def disk_regions(V, T):
    a, b, c = V[T[:, 0]], V[T[:, 1]], V[T[:, 2]]
    n = np.cross(b - a, c - a)
    nz = n[:, 2] / np.linalg.norm(n, axis=1)
    return np.where(nz < -0.7, 0, 1)  # bottom, top


# Surface area of the (1, 0.8, 0.3) ellipsoid (about 6.1; Knud Thomsen's formula, within ~1 %).
# Only used for the initial gmsh size of the triangle-count search.
DISK_AREA = 4 * math.pi * ((np.prod(DISK_AXES[[0, 1]]) ** 1.6075 + np.prod(DISK_AXES[[0, 2]]) ** 1.6075
                            + np.prod(DISK_AXES[[1, 2]]) ** 1.6075) / 3) ** (1 / 1.6075)


def disk_mesh_count(target):
    """Disk organ with about `target` triangles (gmsh size searched, like sphere_mesh_count)."""
    h0 = math.sqrt(4 * DISK_AREA / (math.sqrt(3) * target)) * 1.05
    V, T, h = mesh_by_count(disk_mesh_h, target, h0)
    return V, T


def disk_pair(V, T, gap):
    """Two disk organs pressed together: the organ and its mirror image below, the lower flat
    face's pole `gap` below the upper one's (the surfaces apart for gap > 0).  Regions: the faces
    toward each other (the organ's bottom, nz < -0.7, and its image) and the rest."""
    if not gap > 0:
        raise MeshCheckError("--disk-pair: the gap must be positive (the undeformed surfaces may not touch)")
    reg = disk_regions(V, T)  # 0: bottom (faces the other organ), 1: the rest
    Vb = V * np.array([1, 1, -1]) - np.array([0, 0, 2 * DISK_AXES[2] + gap])
    Tb = T[:, [0, 2, 1]] + len(V)  # mirrored: flip to stay outward
    return (np.vstack([V, Vb]), np.vstack([T, Tb]), np.concatenate([reg, reg + 2]),
            ["a_face", "a_rest", "b_face", "b_rest"])


def gen_disk_organ(outdir, log):
    V, T, h = mesh_by_count(disk_mesh_h, 1000, 0.15)
    check_normals_star("disk_organ_1k", V, T, np.zeros(3))
    T, _ = save(outdir, "disk_organ_1k.msh", V, T, disk_regions(V, T), ["bottom", "top"], [+1], log)
    V2, T2 = subdivide(V, T, lambda i, j: project_ellipsoid(0.5 * (V[i] + V[j])))
    check_normals_star("disk_organ_4k", V2, T2, np.zeros(3))
    save(outdir, "disk_organ_4k.msh", V2, T2, disk_regions(V2, T2), ["bottom", "top"], [+1], log)


# Hertz contact hemispheres --------------------------------------------------------------------------


def hertz_hemisphere(R, hc, hf, rf):
    """The hemisphere z in [0, R] of the sphere of radius R centred at (0, 0, R): pole at the
    origin, flat face at z = R; gmsh size hc within rf of the origin, growing linearly to hf.
    Vertices projected exactly onto the sphere and the plane.  Returns (V, T, region) with
    regions 0 flat, 1 curved."""
    def build():
        ball = gmsh.model.occ.addSphere(0, 0, R, R)
        box = gmsh.model.occ.addBox(-2 * R, -2 * R, 0, 4 * R, 4 * R, R)
        gmsh.model.occ.intersect([(3, ball)], [(3, box)])
        gmsh.model.occ.synchronize()
        f = gmsh.model.mesh.field.add("MathEval")
        gmsh.model.mesh.field.setString(f, "F", f"min({hf}, {hc} + 0.35 * max(0, sqrt(x*x + y*y + z*z) - {rf}))")
        gmsh.model.mesh.field.setAsBackgroundMesh(f)
    V, T = mesh_occ_surface(build, hf)
    on_flat = np.abs(V[:, 2] - R) < 1e-6 * R
    c = np.array([0, 0, R])
    d = V - c
    V = np.where(on_flat[:, None], np.column_stack([V[:, 0], V[:, 1], np.full(len(V), R)]),
                 c + R * d / np.linalg.norm(d, axis=1)[:, None])
    T = orient_outward(V, T)
    flat_tri = on_flat[T].all(axis=1)
    return V, T, np.where(flat_tri, 0, 1)


def hertz_mesh(R, hc, hf, rf, pair_gap):
    V, T, reg = hertz_hemisphere(R, hc, hf, rf)
    if pair_gap is None:
        return V, T, reg, ["flat", "curved"], [+1]
    Vb = V * np.array([1, 1, -1]) - np.array([0, 0, pair_gap])  # the mirror image, pole at z = -gap
    Tb = T[:, [0, 2, 1]] + len(V)                                 # mirrored: flip to stay outward
    return (np.vstack([V, Vb]), np.vstack([T, Tb]), np.concatenate([reg, reg + 2]),
            ["flat_a", "curved_a", "flat_b", "curved_b"], [+1, +1])


# A contact block (an elastic half-space under a sliding instrument) -----------------------------


def contact_block(W, D, hc, hf, rf):
    """The box [-W/2, W/2]^2 x [-D, 0] (top face at z = 0): gmsh size hc within rf of the top face's
    centre (the origin), growing linearly to hf.  Vertices snapped onto the box's planes.  Returns
    (V, T, region) with regions 0 top, 1 bottom, 2 sides."""
    def build():
        gmsh.model.occ.addBox(-W / 2, -W / 2, -D, W, W, D)
        gmsh.model.occ.synchronize()
        f = gmsh.model.mesh.field.add("MathEval")
        gmsh.model.mesh.field.setString(f, "F", f"min({hf}, {hc} + 0.35 * max(0, sqrt(x*x + y*y + z*z) - {rf}))")
        gmsh.model.mesh.field.setAsBackgroundMesh(f)
    V, T = mesh_occ_surface(build, hf)
    for d, planes in ((0, (-W / 2, W / 2)), (1, (-W / 2, W / 2)), (2, (-D, 0.0))):
        for p in planes:
            V[np.abs(V[:, d] - p) < 1e-9 * max(W, D), d] = p
    T = orient_outward(V, T)
    on_top, on_bottom = V[:, 2] == 0.0, V[:, 2] == -D
    return V, T, np.where(on_top[T].all(axis=1), 0, np.where(on_bottom[T].all(axis=1), 1, 2))


# ------------------------------------------------------------------------------------------------
# example problem checks


def load_json_with_comments(path):
    out = []
    with open(path) as f:
        txt = f.read()
    # strip // comments outside strings
    i, n, in_str = 0, len(txt), False
    while i < n:
        ch = txt[i]
        if in_str:
            out.append(ch)
            if ch == "\\":
                out.append(txt[i + 1])
                i += 1
            elif ch == '"':
                in_str = False
        elif ch == '"':
            in_str = True
            out.append(ch)
        elif txt.startswith("//", i):
            while i < n and txt[i] != "\n":
                i += 1
            continue
        else:
            out.append(ch)
        i += 1
    return json.loads("".join(out))


def winding_number(V, T, x):
    a, b, c = V[T[:, 0]] - x, V[T[:, 1]] - x, V[T[:, 2]] - x
    la, lb, lc = (np.linalg.norm(v, axis=1) for v in (a, b, c))
    num = np.einsum("ij,ij->i", a, np.cross(b, c))
    den = la * lb * lc + lc * np.einsum("ij,ij->i", a, b) + la * np.einsum("ij,ij->i", b, c) \
        + lb * np.einsum("ij,ij->i", c, a)
    return 2 * np.arctan2(num, den).sum() / (4 * math.pi)


def select(where, V, T, reg, names):
    if where == "all":
        return np.arange(len(V))
    if "region" in where:
        r = where["region"]
        tag = names[r] if isinstance(r, str) else int(r)
        return np.unique(T[reg == tag])
    if "box" in where:
        lo, hi = np.array(where["box"][0]), np.array(where["box"][1])
        return np.flatnonzero(np.all((V >= lo) & (V <= hi), axis=1))
    if "sphere" in where:
        c, r = np.array(where["sphere"]["center"]), where["sphere"]["radius"]
        return np.flatnonzero(np.linalg.norm(V - c, axis=1) <= r)
    if "vertices" in where:
        return np.array(where["vertices"])
    raise MeshCheckError(f"unknown selector {where}")


def check_examples(meshdir):
    exdir = os.path.join(meshdir, "examples")
    ok = True
    for fn in sorted(os.listdir(exdir)):
        if not fn.endswith(".json"):
            continue
        path = os.path.join(exdir, fn)
        P = load_json_with_comments(path)
        mpath = os.path.normpath(os.path.join(exdir, P["mesh"]))
        V, T, reg, names = read_msh41(mpath)
        print(f"{fn}: mesh {os.path.relpath(mpath, meshdir)} ({len(T)} triangles, {len(V)} vertices)")
        for k, rule in enumerate(P["boundary"]):
            sel = select(rule["where"], V, T, reg, names)
            kind = [x for x in ("displacement", "traction", "pressure") if x in rule]
            extra = ""
            if "vertices" in rule["where"]:
                extra = " at " + "; ".join(f"{i}:({V[i][0]:.3g},{V[i][1]:.3g},{V[i][2]:.3g})"
                                           for i in sel)
            print(f"  rule {k}: {json.dumps(rule['where'])} {kind} -> {len(sel)} vertices{extra}")
            if len(sel) == 0 or len(kind) != 1:
                ok = False
                print("    ERROR: selects no vertex or has not exactly one condition")
        for x in P.get("interior_points", []):
            w = winding_number(V, T, np.array(x, float))
            dmin = np.linalg.norm(V - np.array(x), axis=1).min()
            print(f"  interior point {x}: winding {w:.4f}, nearest vertex {dmin:.3f}")
            if abs(w - 1) > 1e-6:
                ok = False
                print("    ERROR: point is not inside the solid")
    return ok


# ------------------------------------------------------------------------------------------------


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", help="output directory (default: <repo>/meshes), or the output .msh "
                    "file with --sphere-triangles/--sphere-size/--disk-triangles/--disk-size/--cardioid-triangles")
    ap.add_argument("--only", choices=FAMILIES, action="append",
                    help="generate only this family (repeatable)")
    ap.add_argument("--sphere-triangles", type=int, metavar="N",
                    help="write one sphere with about N triangles (gmsh size searched) to --out FILE")
    ap.add_argument("--sphere-size", type=float, metavar="H",
                    help="write one sphere meshed by gmsh with size H to --out FILE")
    ap.add_argument("--radius", type=float, default=1.0, help="sphere radius (single-sphere mode)")
    ap.add_argument("--disk-triangles", type=int, metavar="N",
                    help="write one disk organ with about N triangles (gmsh size searched) to --out FILE")
    ap.add_argument("--disk-size", type=float, metavar="H",
                    help="write one disk organ meshed by gmsh with size H to --out FILE")
    ap.add_argument("--cardioid-triangles", type=int, metavar="N",
                    help="write one cardioid body of revolution (the source paper's heart-like organ) with "
                    "N triangles (N even) to --out FILE")
    ap.add_argument("--hertz-size", type=float, metavar="HC",
                    help="write a Hertz contact hemisphere (pole at the origin, flat face up) with size HC "
                    "near the pole to --out FILE")
    ap.add_argument("--hertz-far", type=float, metavar="HF", help="Hertz: size far from the pole (default 0.25 R)")
    ap.add_argument("--hertz-fine-radius", type=float, metavar="RF",
                    help="Hertz: size HC within this distance of the pole (default 0.3 R)")
    ap.add_argument("--hertz-pair", type=float, metavar="GAP",
                    help="Hertz: add the mirror image below, its pole at z = -GAP (two bodies)")
    ap.add_argument("--block-size", type=float, metavar="HC",
                    help="write a contact block (top face at z = 0) with size HC near the top's centre to --out FILE")
    ap.add_argument("--block-width", type=float, default=1.2, help="contact block: width W (default 1.2)")
    ap.add_argument("--block-depth", type=float, default=0.6, help="contact block: depth D (default 0.6)")
    ap.add_argument("--block-far", type=float, default=0.15, help="contact block: size far from the centre (default 0.15)")
    ap.add_argument("--block-fine-radius", type=float, default=0.28,
                    help="contact block: size HC within this distance of the top's centre (default 0.28)")
    ap.add_argument("--disk-pair", type=float, metavar="GAP",
                    help="disk organ: add its mirror image below, the two flat faces' poles GAP apart "
                    "(two bodies; regions a_face, a_rest, b_face, b_rest, the faces toward each other)")
    ap.add_argument("--refine", type=int, default=0, metavar="K",
                    help="apply K nested 1:4 refinements (single-sphere and single-disk modes)")
    ap.add_argument("--check-examples", action="store_true",
                    help="only check the selectors and interior points of <out>/examples/*.json")
    args = ap.parse_args()

    if args.check_examples:
        sys.exit(0 if check_examples(args.out or DEFAULT_OUT) else 1)

    single_sphere = args.sphere_triangles is not None or args.sphere_size is not None
    single_disk = args.disk_triangles is not None or args.disk_size is not None
    single_cardioid = args.cardioid_triangles is not None
    if single_sphere + single_disk + single_cardioid + (args.sphere_triangles is not None and args.sphere_size is not None) \
            + (args.disk_triangles is not None and args.disk_size is not None) > 1:
        ap.error("give only one of --sphere-triangles, --sphere-size, --disk-triangles, --disk-size, --cardioid-triangles")

    if args.hertz_size is not None:
        if not args.out or not args.out.endswith(".msh"):
            ap.error("Hertz mode needs --out FILE.msh")
        R = args.radius
        hf = args.hertz_far if args.hertz_far else 0.25 * R
        rf = args.hertz_fine_radius if args.hertz_fine_radius else 0.3 * R
        V, T, reg, names, signs = hertz_mesh(R, args.hertz_size, hf, rf, args.hertz_pair)
        d = os.path.dirname(os.path.abspath(args.out))
        os.makedirs(d, exist_ok=True)
        save(d, os.path.basename(args.out), V, T, reg, names, signs, [])
        return

    if args.block_size is not None:
        if not args.out or not args.out.endswith(".msh"):
            ap.error("contact block mode needs --out FILE.msh")
        V, T, reg = contact_block(args.block_width, args.block_depth, args.block_size, args.block_far,
                                  args.block_fine_radius)
        d = os.path.dirname(os.path.abspath(args.out))
        os.makedirs(d, exist_ok=True)
        save(d, os.path.basename(args.out), V, T, reg, ["top", "bottom", "sides"], [+1], [])
        return

    if single_cardioid:
        if not args.out or not args.out.endswith(".msh"):
            ap.error("single-cardioid mode needs --out FILE.msh")
        if args.cardioid_triangles < 8 or args.cardioid_triangles % 2:
            ap.error("--cardioid-triangles must be even and at least 8")
        V, T, _, _ = cardioid_rings(args.cardioid_triangles)  # oriented outward
        d = os.path.dirname(os.path.abspath(args.out))
        os.makedirs(d, exist_ok=True)
        save(d, os.path.basename(args.out), V, T, cardioid_regions(V, T), ["base", "body"], [+1], [])
        return

    if single_sphere:
        if not args.out or not args.out.endswith(".msh"):
            ap.error("single-sphere mode needs --out FILE.msh")
        R = args.radius
        if args.sphere_triangles is not None:
            V, T = sphere_mesh_count(R, args.sphere_triangles)
        else:
            V, T = sphere_mesh_h(R, args.sphere_size)
        rad = np.full(len(V), R)
        for _ in range(args.refine):
            V, T, rad = refine_sphere(V, T, rad)
        check_normals_star(args.out, V, T, np.zeros(3))
        d = os.path.dirname(os.path.abspath(args.out))
        os.makedirs(d, exist_ok=True)
        reg = sphere_regions(V / R, T)
        save(d, os.path.basename(args.out), V, T, reg, SPHERE_REGIONS, [+1], [])
        return

    if single_disk:
        if not args.out or not args.out.endswith(".msh"):
            ap.error("single-disk mode needs --out FILE.msh")
        if args.disk_triangles is not None:
            V, T = disk_mesh_count(args.disk_triangles)
        else:
            V, T = disk_mesh_h(args.disk_size)
        for _ in range(args.refine):
            Vc = V
            V, T = subdivide(Vc, T, lambda i, j: project_ellipsoid(0.5 * (Vc[i] + Vc[j])))
        check_normals_star(args.out, V, T, np.zeros(3))
        d = os.path.dirname(os.path.abspath(args.out))
        os.makedirs(d, exist_ok=True)
        if args.disk_pair is not None:
            V, T, reg, names = disk_pair(V, T, args.disk_pair)
            save(d, os.path.basename(args.out), V, T, reg, names, [+1, +1], [])
            return
        save(d, os.path.basename(args.out), V, T, disk_regions(V, T), ["bottom", "top"], [+1], [])
        return

    outdir = args.out or DEFAULT_OUT
    os.makedirs(outdir, exist_ok=True)
    fams = args.only or FAMILIES
    log = []
    gens = {"sphere": gen_sphere, "cube": gen_cube, "cardioid": gen_cardioid,
            "disk_organ": gen_disk_organ, "hollow_sphere": gen_hollow_sphere}
    for fam in FAMILIES:
        if fam in fams:
            print(f"{fam}:", flush=True)
            gens[fam](outdir, log)
    if os.path.isdir(os.path.join(outdir, "examples")) and not args.only:
        print("examples:")
        if not check_examples(outdir):
            raise MeshCheckError("example problem check failed")


if __name__ == "__main__":
    try:
        main()
    except MeshCheckError as e:
        sys.exit(f"gen_meshes.py: MESH CHECK FAILED: {e}")
