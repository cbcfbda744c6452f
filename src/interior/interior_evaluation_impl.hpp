// Private to the fast interior evaluation: the fits on spheres and the source side
// (interior_evaluation.cpp), shared with the target side (interior_targets.cpp).
#pragma once

#include "hssbem/interior/interior_evaluation.hpp"

#include <memory>
#include <vector>

namespace hssbem::detail {

/// Points on a sphere, structure of arrays (and in single precision for the far-field loops).
struct SpherePoints {
  std::vector<double> x, y, z;
  std::vector<float> fx, fy, fz;
  int size() const { return static_cast<int>(x.size()); }
};

/// out[0..9) += displacement and stress at x of the forces q (SoA, 3n) at centre + r · s, summed
/// in single precision relative to the centre (the far field: twice the SIMD lanes of doubles;
/// the tests check the evaluation against the direct sums).
void add_forces_field(const SomiglianaConstants &k, const Vec3 &x, const Vec3 &centre, double r, const SpherePoints &s, const float *q, double *out);

/// field (SoA, 3 m) += the displacement at the m points p (floats, relative to an origin) of the
/// forces q (SoA floats, 3n) at c + r · s (c relative to the same origin). The SIMD loop runs over
/// the points, force by force, and each call sums in floats: the fits' many pairs.
void add_forces_to(const SomiglianaConstants &k, const float *const p[3], int m, const Vec3 &c, double r, const SpherePoints &s, const float *q, double *field);

/// Single-precision copy of a force vector.
inline std::vector<float> to_float(const std::vector<double> &v) { return std::vector<float>(v.begin(), v.end()); }

/// u[0..3) += the displacement at x of the forces q (SoA: q[j], q[n + j], q[2n + j]) at the
/// points centre + r · s, summed in doubles (the upward pass).
void add_forces_at(const SomiglianaConstants &k, const Vec3 &x, const Vec3 &centre, double r, const SpherePoints &s, const double *q, double *u);

/// One unit configuration of the fits: equivalent points (where the fitted forces sit, radius
/// r_equiv) and check points (where the field is matched, radius r_check), and the
/// pseudo-inverse of U(check, equivalent). A cluster of radius R scales both spheres by R.
struct Fit {
  SpherePoints equiv, check;
  double r_equiv = 0, r_check = 0;
  std::vector<double> pinv; ///< 3 pe × 3 pc, column-major

  Fit(const SomiglianaConstants &k, int pe, int pc, double r_equiv, double r_check);
  int pe() const { return equiv.size(); }
  int pc() const { return check.size(); }
  /// The forces (SoA, 3 pe) whose field matches `field` (SoA, 3 pc) at the check points of a
  /// cluster of radius R: R · pinv · field.
  void solve(double R, const std::vector<double> &field, std::vector<double> &forces) const;
  /// The check point i of a cluster at `centre` of radius R.
  Vec3 check_point(const Vec3 &centre, double R, int i) const
  {
    const double s = R * r_check;
    return {centre[0] + s * check.x[i], centre[1] + s * check.y[i], centre[2] + s * check.z[i]};
  }
};

/// The sources' particles in the order of the source tree (a leaf's are contiguous): in double
/// (the upward pass) and in single precision relative to the centre of their source leaf (the
/// evaluation at points, x − centre formed in doubles, then rounded), for SIMD loops over a leaf.
struct OrderedParticles {
  std::vector<double> y[3], f[3], m[3], n[3];
  std::vector<float> ys[3], fs[3], ms[3], ns[3];
  /// out[0..9) += the field at x of particles [begin, end) of the leaf centred at `centre`, each
  /// weighted by weight[j − begin] (1: its triangle is regular at x, 0: split elsewhere), or all
  /// taken where weight is null.
  void add_regular(const SomiglianaConstants &k, const Vec3 &x, const Vec3 &centre, std::size_t begin, std::size_t end, const float *weight, double *out) const;
};

} // namespace hssbem::detail

namespace hssbem {

struct InteriorEvaluator::Impl {
  const SomiglianaSources &src;
  InteriorEvaluationOptions opt;
  detail::Fit up;   ///< sources: equivalent sphere inside, check sphere outside
  detail::Fit down; ///< targets: check sphere inside, equivalent sphere outside
  std::unique_ptr<detail::Fit> inner; ///< source leaves, closer: check sphere at inner_ratio (none without inner_points)
  ClusterTree tree; ///< over the triangles' centroids
  std::vector<Vec3> C;                ///< per source cluster: the centre of its spheres (see source_centres)
  std::vector<double> R, reach;       ///< per source cluster: ball of its triangles (enlarged for the upward pass, see nest_radii), of their near zones
  std::vector<std::vector<double>> q; ///< per source cluster: equivalent forces (SoA, 3 pe)
  std::vector<std::vector<float>> qf; ///< the same in single precision (the evaluation at points)
  std::vector<std::vector<float>> qi; ///< per source leaf: its inner forces (SoA, 3 inner pe) where upward_leaf made them, else empty
  detail::OrderedParticles particles; ///< in the tree's order

  Impl(const SomiglianaSources &s, const InteriorEvaluationOptions &o);

  void order_particles();
  /// out[0..9) += the field at x of the triangles of source leaf b: through its equivalent
  /// forces where x is far from it, else its particles (adaptive where near). Counts the kernel
  /// evaluations into `s`.
  void add_leaf(const Vec3 &x, int b, double *out, InteriorEvaluationStats &s) const;
  /// out[0..9) += the field at x of source cluster b's equivalent forces.
  void add_equivalent(const Vec3 &x, int b, double *out) const;
  /// Centres closer to those of the smallest balls around the clusters' triangles than their
  /// boxes' centres (smaller balls are far sooner): a leaf's by Bădoiu–Clarkson steps over its
  /// triangles, a parent's over its leaves' balls.
  void source_centres();
  void source_radii();
  /// field (SoA, 3 pc) = the displacement of leaf c's particles at the check points of `fit`.
  void leaf_field(int c, const detail::Fit &fit, std::vector<double> &field) const;
  void upward_leaf(int c);
  void upward_inner(int c);
  void upward();
  /// Whether source cluster b is far from a target ball (centre ca, radius Ra).
  bool far(const Vec3 &ca, double Ra, int b) const;
};

} // namespace hssbem
