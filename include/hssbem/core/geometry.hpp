/// \file geometry.hpp
/// Small fixed-size vectors (points, normals) and 3×3 matrices: the geometry shared by every layer,
/// from the cluster tree up to the mesh, the kernels, the quadrature and the result files.
#pragma once

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

/// n nearly uniform points on the unit sphere (Fibonacci lattice): the proxy and equivalent
/// surfaces of the compressions and of the fast interior evaluation.
std::vector<Vec3> unit_sphere_points(int n);

} // namespace hssbem
