/// \file triangle_bvh.hpp
/// Closest points on a set of triangles: a bounding-volume hierarchy (axis-aligned boxes,
/// median splits) searched best-first with a distance bound. What contact asks of a rigid mesh
/// obstacle and of the other bodies' surfaces (node-to-surface pairing).
#pragma once

#include "hssbem/core/geometry.hpp"

#include <array>
#include <limits>
#include <vector>

namespace hssbem {

/// The closest point of a triangle set to a query point.
struct TriangleHit {
  int triangle = -1;                 ///< index into the triangle list given, -1: nothing within the bound
  Vec3 point{};                      ///< the closest point
  std::array<double, 3> bary{};      ///< its barycentric coordinates in the triangle
  double distance = std::numeric_limits<double>::infinity();
  bool interior = false;             ///< the point lies inside the triangle (not on an edge or corner)
};


class TriangleBvh {
public:
  TriangleBvh() = default;
  /// The triangles `subset` (indices into `triangles`; empty: all) of the mesh (vertices,
  /// triangles); the hierarchy keeps copies of the coordinates it needs.
  TriangleBvh(const std::vector<Vec3> &vertices, const std::vector<std::array<int, 3>> &triangles, const std::vector<int> &subset = {});

  /// The closest point to x within `max_distance` (hit.triangle = -1 when there is none); the
  /// triangle index is the one of the list given to the constructor.
  TriangleHit closest(const Vec3 &x, double max_distance = std::numeric_limits<double>::infinity()) const;
  bool empty() const { return m_tri.empty(); }

private:
  struct Node {
    Vec3 lo, hi;
    int first = 0, count = 0; ///< a leaf's triangles first .. first + count - 1 (count > 0)
    int second = 0;           ///< an inner node's children: first and second
  };
  int build(int begin, int end);
  static double box_distance2(const Node &n, const Vec3 &x);

  std::vector<std::array<Vec3, 3>> m_corners; ///< per triangle of the subset, in tree order
  std::vector<int> m_tri;                     ///< their indices in the constructor's list
  std::vector<Node> m_nodes;
};

} // namespace hssbem
