/// \file quadrature.hpp
/// Integrals of Kelvin's kernels times P1 shape functions over one flat triangle.
///
/// Three regimes, chosen per (collocation point, triangle):
/// - the point lies on the triangle: Duffy transformation on sub-triangles with apex at the point
///   (the 1/r of u*, and p* times (N_a - w_a), become smooth);
/// - the point is near (distance / diameter below `near_ratio`): the triangle is split in four,
///   recursively, up to `max_depth` levels;
/// - otherwise a symmetric rule: 7 points (degree 5), or optionally 3 points (degree 2) beyond
///   `far_ratio` (dense path only).
#pragma once

#include "hssbem/bem/kelvin.hpp"
#include "hssbem/core/geometry.hpp"
#include "hssbem/core/option_table.hpp"

#include <array>
#include <vector>

namespace hssbem {

struct PointList; // quadrature.cpp

/// Quadrature settings (options -mat_bem_*).
struct QuadratureOptions {
  int duffy_order = option_default::mat_bem_quad_order;   ///< Gauss-Legendre points per direction on singular triangles
  double near_ratio = option_default::mat_bem_near_ratio; ///< subdivide while distance/diameter is below this
  /// 3-point rule beyond this distance/diameter; 0 (the default): never. The HSS path needs 0:
  /// with one rule everywhere beyond near_ratio, each column of the discrete operator is a fixed
  /// sum of point sources outside its near zone, which proxy surfaces capture to any tolerance.
  double far_ratio = option_default::mat_bem_far_ratio;
  int max_depth = option_default::mat_bem_max_depth; ///< subdivision levels for nearly singular triangles
};

/// Kernel constants of one material.
struct KelvinConstants {
  double cu, cu_diag; ///< u* = cu/r [cu_diag δ + r_i r_j]
  double cp, one_m_2nu; ///< p* = cp/r² [...]
  explicit KelvinConstants(const Material &m);
};

/// A flat triangle: corners, unit normal, area.
struct Triangle {
  std::array<Vec3, 3> p;
  Vec3 n;
  double area;
};

/// Integrals of one triangle for one collocation point: for each corner a, the 3x3 matrices
/// G[a] = ∫ u* N_a and H[a] = ∫ p* (N_a - w_a) (row-major, row = load direction).
struct ElementIntegrals {
  std::array<Mat3, 3> G, H;
  void clear();
};

class ElementQuadrature {
public:
  ElementQuadrature(const Material &material, const QuadratureOptions &options);

  /// Integrals over `tri` for a point x not on it. w_a = 0.
  void regular(const Vec3 &x, const Triangle &tri, ElementIntegrals &out) const;
  /// Integrals over `tri` for a point x on it with barycentric coordinates `bx`; the p* part is
  /// integrated against N_a - bx[a] (the rigid-body subtraction keeps it weakly singular).
  void singular(const Vec3 &x, const std::array<double, 3> &bx, const Triangle &tri, ElementIntegrals &out) const;

  const QuadratureOptions &options() const { return m_opt; }

private:
  struct Sub { std::array<Vec3, 3> p; std::array<std::array<double, 3>, 3> b; };
  // The rules gather their points (position, weight, shape values) into a PointList, which one
  // vectorised pass then sums.
  void subdivide(const Vec3 &x, const Sub &s, int depth, PointList &P) const;
  template <int NQ>
  void gather_rule(const Sub &s, const double (&rule)[NQ][4], PointList &P) const;
  void duffy_split(const Vec3 &x, const std::array<double, 3> &bx, const Sub &s, PointList &P) const;
  void duffy(const Vec3 &x, const std::array<double, 3> &bx, const Sub &s, PointList &P) const;

  KelvinConstants m_k;
  QuadratureOptions m_opt;
  std::vector<double> m_gl_x, m_gl_w; ///< Gauss-Legendre on [0, 1]
};

} // namespace hssbem
