/// \file surface_intersection.hpp
/// Surfaces that pass through themselves or through each other: a body's boundary must not, and
/// two bodies must not overlap. A bounding-volume hierarchy over the triangles finds the
/// candidate pairs; each pair is decided by a triangle–triangle test with a tolerance relative
/// to the mesh's size.
#pragma once

#include "hssbem/mesh/mesh.hpp"

#include <optional>
#include <vector>

namespace hssbem {

/// Two triangles that intersect: indices into the mesh (for two meshes: `first` in the first,
/// `second` in the second).
struct TrianglePair {
  int first  = -1;
  int second = -1;
};

/// What counts as an intersection. Two triangles intersect when they share a point interior to
/// both (their interiors cross), or when they lie in one plane, overlap with positive area and
/// face the same way (two bodies sharing volume there). Not intersections: triangles of one
/// mesh that share a vertex or an edge (neighbours in the surface); triangles that only touch
/// (at a point, along an edge, or face to face with opposite normals: bodies in contact).
/// `tolerance` is relative to the diagonal of the meshes' bounding box: distances below
/// tolerance × diagonal count as zero.
struct IntersectionOptions {
  double tolerance = 1e-10;
};

/// The first pair of triangles of `mesh` that intersect (the lowest `first`, then the lowest
/// `second` > first), or none. The triangles' vertex indices must lie in range (validate the
/// mesh's indices first). Cost: O(n log n) for n triangles (a bounding-volume hierarchy),
/// threaded with OpenMP; the answer does not depend on the number of threads.
std::optional<TrianglePair> find_intersection(const SurfaceMesh &mesh, const IntersectionOptions &o = {});

/// The first pair (the lowest triangle of `a`, then of `b`) of a triangle of `a` and one of `b`
/// that intersect, or none: two bodies that overlap. No pair is taken for neighbours here,
/// even where the meshes share coordinates.
std::optional<TrianglePair> find_intersection(const SurfaceMesh &a, const SurfaceMesh &b, const IntersectionOptions &o = {});

/// A point of a surface used to place it with respect to another: a vertex, or the centroid of
/// a triangle (indices into the mesh).
struct SurfaceSample {
  int vertex   = -1;
  int triangle = -1;
};

/// Two closed surfaces that pass through each other where no two triangles' interiors cross
/// (along triangle edges or through vertices: meshes whose grids line up), or that coincide.
struct SurfaceCrossing {
  int first  = -1;              ///< surfaces (the numbers of `surface_of`)
  int second = -1;
  SurfaceSample inside, outside; ///< samples of `first` strictly inside and strictly outside `second`
  bool coincide = false;         ///< every sample of `first` lies on `second` (inside, outside unset)
};

/// How the closed surfaces of a mesh lie in one another.
struct SurfaceNesting {
  std::vector<std::vector<char>> inside; ///< inside[s][r]: surface s lies inside surface r (never for s = r)
  std::optional<SurfaceCrossing> crossing; ///< the first pair (lowest s, then r) that crosses or coincides
};

/// Places every closed surface of `mesh` (`surface_of`: per triangle, its surface 0 .. count − 1;
/// each surface closed and consistently oriented) with respect to every other, from samples of
/// it: its vertices and its triangles' centroids. A sample within `o.tolerance` × the mesh's
/// bounding-box diagonal of the other surface lies on it and decides nothing; the others lie
/// inside it (|winding number| > 1/2) or outside. A surface lies inside another when some of its
/// samples do and none lies outside; when both occur the two surfaces cross (`crossing`), and
/// when all its samples lie on the other they coincide. So a surface taken for a cavity lies
/// wholly inside its parent (every sample checked), and two surfaces that pass through each
/// other are caught however they do so: through triangle interiors (find_intersection() names
/// those triangles first), along edges or at vertices. Cost: O(n log n) for n triangles (a
/// SurfaceLocator per surface; pairs whose boxes do not meet are outside each other unqueried).
SurfaceNesting nest_surfaces(const SurfaceMesh &mesh, const std::vector<int> &surface_of, int count, const IntersectionOptions &o = {});

} // namespace hssbem
