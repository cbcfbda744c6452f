/// \file regular_rule.hpp
/// The regular (7-point) rule of ElementQuadrature on many triangles at once: what nearly every
/// kernel entry of a compressed operator costs. For one point x and a list of triangles, the
/// rule's 15 kernel numbers per quadrature point (u* symmetric 6, p* symmetric 6 and
/// antisymmetric 3) are summed against the three corner shape functions with the triangles as
/// SIMD lanes, from per-triangle data prepared once (quadrature points, normal, area, the near
/// threshold). It gives the same integrals as ElementQuadrature::regular wherever that applies the
/// 7-point rule to the whole triangle (up to rounding); `is_regular` tells which pairs those are.
#pragma once

#include "hssbem/bem/quadrature.hpp"

#include <cmath>
#include <vector>

namespace hssbem {

/// Corner sums of one triangle: for corner c, v[c][0..5] = u* (xx, yy, zz, xy, xz, yz),
/// v[c][6..11] = the symmetric part of p* (same order), v[c][12..14] = its antisymmetric part (xy,
/// xz, yz), each integrated against the corner's shape function (KernelSums in quadrature.cpp
/// holds the same numbers).
struct CornerSums {
  static constexpr int size = 15;
  double v[3][size];
  /// Expand corner c into 3x3 blocks (row-major, row = load direction), as ElementIntegrals.
  void expand(int c, double G[9], double H[9]) const { expand(v[c], G, H); }
  static void expand(const double *v, double G[9], double H[9]);
  /// The 15 numbers of 3x3 blocks G (symmetric) and H (inverse of expand, up to rounding).
  static void compress(const double G[9], const double H[9], double *v);
};

class RegularRule {
public:
  RegularRule(const Material &material, const QuadratureOptions &options, const std::vector<Triangle> &triangles);

  /// True when ElementQuadrature::regular(x, t) would apply the 7-point rule to all of t (x is
  /// at least near_ratio diameters from its centroid, and short of the 3-point far rule).
  bool is_regular(const Vec3 &x, int t) const
  {
    const TriangleData &d = m_tri[t];
    const double d0 = x[0] - d.centroid[0], d1 = x[1] - d.centroid[1], d2 = x[2] - d.centroid[2];
    const double r2 = d0 * d0 + d1 * d1 + d2 * d2;
    return r2 >= d.near2 && r2 < d.far2;
  }

  /// Corner sums of triangles tris[0..n) at x (out[k] for tris[k]); each must be regular at x.
  void sums(const Vec3 &x, const int *tris, int n, CornerSums *out) const;

  /// The other way round, for blocks with many rows: one triangle t at `lanes` points at once,
  /// given by coordinates x[0][k], x[1][k], x[2][k] (aligned to 64 bytes).
  static constexpr int lanes = 8;
  /// Bit k set when t is regular at point k (is_regular for each lane).
  unsigned regular_lanes(const double (&x)[3][lanes], int t) const;
  /// True when t is regular at every point within `radius` of `centre` (a cheap test that lets
  /// a group of points skip regular_lanes; false says nothing).
  bool regular_in_ball(const Vec3 &centre, double radius, int t) const
  {
    const TriangleData &d = m_tri[t];
    const double d0 = centre[0] - d.centroid[0], d1 = centre[1] - d.centroid[1], d2 = centre[2] - d.centroid[2];
    const double dist = std::sqrt(d0 * d0 + d1 * d1 + d2 * d2), lo = dist - radius, hi = dist + radius;
    return lo > 0 && lo * lo >= d.near2 && hi * hi < d.far2;
  }
  /// out[c][m][k]: corner c's sum m (CornerSums layout) of t at point k. Lanes at which t is not
  /// regular get meaningless (possibly infinite) numbers that the caller must not use.
  void lane_sums(const double (&x)[3][lanes], int t, double (&out)[3][CornerSums::size][lanes]) const;
  /// dest[c][m · lanes + k] += lane_sums' out[c][m][k] for each corner c whose dest is not null
  /// (all lanes: every one must be regular, or its lanes ignored by the caller).
  void add_lane_sums(const double (&x)[3][lanes], int t, double *const dest[3]) const;

private:
  struct TriangleData {
    double q[3][8];     ///< quadrature points (coordinate, point), the 8th unused
    double n[3];        ///< unit normal
    double area;
    double centroid[3];
    double near2, far2; ///< squared distances bounding the 7-point zone
  };
  /// The 15 kernel numbers, weights included, at the 7 points (point, number, lane).
  void lane_kernels(const double (&x)[3][lanes], int t, double (&K)[7][CornerSums::size][lanes]) const;
  template <int B>
  void batch(const Vec3 &x, const int *tris, CornerSums *out) const;

  KelvinConstants m_k;
  std::vector<TriangleData> m_tri;
};

} // namespace hssbem
