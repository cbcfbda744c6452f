/// \file surface_intersection.hpp
/// Surfaces that pass through themselves or through each other: a body's boundary must not, and
/// two bodies must not overlap. A bounding-volume hierarchy over the triangles finds the
/// candidate pairs; each pair is decided by a triangle–triangle test with a tolerance relative
/// to the mesh's size.
#pragma once

#include "hssbem/mesh/mesh.hpp"

#include <optional>

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

} // namespace hssbem
