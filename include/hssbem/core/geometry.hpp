/// \file geometry.hpp
/// Small fixed-size vectors (points, normals) and 3×3 matrices: the geometry shared by every layer,
/// from the cluster tree up to the mesh, the kernels, the quadrature and the result files.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace hssbem {

using Vec3 = std::array<double, 3>;
using Mat3 = std::array<double, 9>; ///< row-major 3x3
/// A symmetric 3x3 tensor (stress) in Voigt order: xx, yy, zz, yz, xz, xy.
using Voigt = std::array<double, 6>;

inline Vec3 operator+(const Vec3 &a, const Vec3 &b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline Vec3 operator-(const Vec3 &a, const Vec3 &b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline Vec3 operator*(double s, const Vec3 &a) { return {s * a[0], s * a[1], s * a[2]}; }
inline double dot(const Vec3 &a, const Vec3 &b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec3 cross(const Vec3 &a, const Vec3 &b)
{
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double norm(const Vec3 &a) { return std::sqrt(dot(a, a)); }
inline Vec3 normalized(const Vec3 &a)
{
  const double n = norm(a);
  return n > 0 ? (1.0 / n) * a : a;
}

/// An axis-aligned box, empty until a point is added: the one bounding box of every layer (the
/// surface checks, the locator, the contact's sizes and hierarchies, the geometric tolerance).
struct Box {
  Vec3 lo{HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};

  /// The box of `points`.
  static Box of(const std::vector<Vec3> &points)
  {
    Box b;
    for (const Vec3 &x : points) b.add(x);
    return b;
  }
  void add(const Vec3 &x)
  {
    for (int i = 0; i < 3; ++i) lo[i] = std::min(lo[i], x[i]), hi[i] = std::max(hi[i], x[i]);
  }
  void add(const Box &b) { add(b.lo), add(b.hi); }
  bool empty() const { return lo[0] > hi[0]; }
  /// The boxes share a point, each grown by `pad` (≥ 0).
  bool overlaps(const Box &b, double pad = 0) const
  {
    for (int i = 0; i < 3; ++i)
      if (b.lo[i] > hi[i] + pad || b.hi[i] < lo[i] - pad) return false;
    return true;
  }
  /// x lies in the box grown by `pad` (≥ 0).
  bool contains(const Vec3 &x, double pad = 0) const
  {
    for (int i = 0; i < 3; ++i)
      if (x[i] < lo[i] - pad || x[i] > hi[i] + pad) return false;
    return true;
  }
  /// The length of the diagonal (0 when empty).
  double diagonal() const { return empty() ? 0.0 : norm(hi - lo); }
  Vec3 center() const { return 0.5 * (lo + hi); }
};

/// The point of triangle (a, b, c) closest to a query point, its barycentric coordinates, and
/// whether it lies inside the triangle (not on an edge or a corner).
struct TrianglePoint {
  Vec3 point{};
  Vec3 bary{};
  bool interior = false;
};

/// The point of triangle (a, b, c) closest to x (Ericson, Real-Time Collision Detection §5.1.5:
/// the Voronoi regions of corners, edges, face): the mesh's surface locator and the contact's
/// obstacle hierarchy both stand on it.
TrianglePoint closest_point_on_triangle(const Vec3 &x, const Vec3 &a, const Vec3 &b, const Vec3 &c);

/// n nearly uniform points on the unit sphere (Fibonacci lattice): the proxy and equivalent
/// surfaces of the compressions and of the fast interior evaluation.
std::vector<Vec3> unit_sphere_points(int n);

} // namespace hssbem
