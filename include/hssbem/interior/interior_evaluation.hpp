/// \file interior_evaluation.hpp
/// Displacement and stress of Somigliana's identities (post/interior_stress.hpp) at many points,
/// in O(points + triangles) work: a fast multipole method on two cluster trees, whose far field
/// goes through proxy spheres (kernel-independent, with equivalent point forces as in Ying, Biros
/// and Zorin, J. Comput. Phys. 196, 2004).
///
/// Sources: a cluster tree over the triangles (their centroids). The far field of a source
/// cluster b (outside its *check sphere*, radius check_ratio · R_b around its centre) is that of
/// point forces at the points of its *equivalent sphere* (equivalent_ratio · R_b), fitted to the
/// cluster's displacement at the check points: at a leaf from its triangles' particles (the
/// 7-point rule), above from its children's equivalent forces (upward pass). R_b is the radius of
/// the ball of b's triangles, enlarged where needed so that b's check sphere lies outside its
/// children's (R_b ≥ R_child + distance / check_ratio), not to hold the children's balls: smaller
/// balls are far sooner (18 % fewer far pairs on a 13k-triangle sphere, the same accuracy).
/// Targets: a cluster tree over the points. The far field inside a target cluster a (its ball
/// of radius R_a) is that of point forces at the points of an outer equivalent sphere
/// (check_ratio · R_a), fitted to the field at inner check points (equivalent_ratio · R_a): from
/// the sources far from a (their equivalent forces) and from a's parent (downward pass); at a
/// leaf it gives every point's displacement and stress (the Kelvin kernels U and D of the forces).
/// A pair of clusters is far when each one's check sphere clears the other's equivalent sphere
/// and the target ball lies outside the near zones of the source's triangles; what is not far at
/// the leaves is near and goes through SomiglianaSources (adaptive quadrature) directly, except
/// that a point between inner_ratio and check_ratio radii from a source leaf (and outside its
/// triangles' near zones) takes the leaf's inner forces: more of them, fitted closer
/// (InteriorEvaluationOptions::inner_points).
///
/// The fits are least squares on spheres scaled from one unit configuration: U(R x, R y) =
/// U(x, y) / R, so two pseudo-inverses (truncated SVD) serve every cluster. The accuracy is set by
/// the number of sphere points (equivalent_points) and the ratio of the spheres; the tests check
/// it against the direct sums.
///
/// Precision: the sums over equivalent forces (at points and at the targets' check points) and
/// over the near leaves' particles run in floats, positions relative to the cluster's centre
/// formed in doubles first (twice the SIMD lanes); the pseudo-inverses, the upward pass and the
/// choice of the triangles split near a point stay in doubles. Fast against direct is unchanged
/// (2–4e-5 in the stress with 128 equivalent points).
///
/// Distribution: every rank runs the upward pass (O(triangles)) and evaluates the target leaves
/// of its share (contiguous, balanced by points); the others' points are left at zero, so a sum
/// over the ranks gives every point once. The values do not depend on the number of ranks.
#pragma once

#include "hssbem/post/interior_stress.hpp"
#include "hssbem/post/near_surface.hpp"
#include "hssbem/core/cluster_tree.hpp"
#include "hssbem/core/option_table.hpp"
#include "hssbem/core/dense_matrix.hpp"

#include <memory>
#include <vector>

namespace hssbem {

struct InteriorEvaluationOptions {
  int equivalent_points = option_default::bem_interior_equivalent_points; ///< points on each equivalent sphere
  double check_factor = 1.25;     ///< points on each check sphere / equivalent_points
  double equivalent_ratio = 1.05; ///< equivalent (sources) or check (targets) sphere radius / cluster radius
  double check_ratio = 2.6;       ///< check (sources) or equivalent (targets) sphere radius / cluster radius
  int source_leaf = option_default::bem_interior_source_leaf; ///< triangles per source leaf (at most)
  int target_leaf = option_default::bem_interior_target_leaf; ///< points per target leaf (at most)
  /// A second, closer representation of each source leaf for the points near it: inner_points
  /// forces on its equivalent sphere fitted at inner_ratio · R (0 points: none). A point between
  /// inner_ratio · R and check_ratio · R from the leaf's centre (and beyond its triangles' near
  /// zones) takes these instead of the leaf's particles (7 per triangle, each about twice a
  /// force's kernel), for leaves where they are fewer kernels.
  int inner_points = option_default::bem_interior_inner_points;
  double inner_ratio = 2.2;
  bool direct = option_default::bem_interior_direct; ///< every point against every triangle (the reference; O(points · triangles))
};

/// Work and time of one evaluation (this rank's share).
struct InteriorEvaluationStats {
  long long far_pairs = 0;        ///< (target cluster, source cluster) pairs in the far field
  long long local_fits = 0;       ///< target clusters with outer forces of their own
  long long direct_far = 0;       ///< (point, far source cluster) pairs evaluated directly (small clusters)
  long long near_pairs = 0, near_triangle_visits = 0;
  long long kernel_far = 0;       ///< point-force kernels at points (outer forces, far sources taken directly, near leaves through their forces)
  long long kernel_fit = 0;       ///< point-force kernels at check points (upward and downward fits)
  long long kernel_near = 0;      ///< particles of near leaves evaluated at points
  long long kernel_inner = 0;     ///< point-force kernels of near leaves' inner forces at points (InteriorEvaluationOptions::inner_points)
  long long adaptive_triangles = 0; ///< (point, triangle) pairs integrated by splitting
  int source_clusters = 0, target_clusters = 0;
  double upward_seconds = 0, lists_seconds = 0, downward_seconds = 0, near_seconds = 0;
};

class InteriorEvaluator {
public:
  /// Builds the source tree and runs the upward pass. `src` must outlive the evaluator.
  InteriorEvaluator(const SomiglianaSources &src, const InteriorEvaluationOptions &options = {});
  ~InteriorEvaluator();
  InteriorEvaluator(const InteriorEvaluator &) = delete;
  InteriorEvaluator &operator=(const InteriorEvaluator &) = delete;

  /// field_outputs values (displacement, stress) per point, in the order of `points`, for the
  /// points of share `part` of `parts` (zero for the others).
  std::vector<double> evaluate(const std::vector<Vec3> &points, int part = 0, int parts = 1) const;

  const InteriorEvaluationStats &stats() const { return m_stats; }
  double upward_seconds() const { return m_upward_seconds; }

  struct Impl; ///< the source side, private to the implementation (src/compress/)

private:
  std::unique_ptr<Impl> m_impl;
  mutable InteriorEvaluationStats m_stats;
  double m_upward_seconds = 0;
};

/// Displacement and stress at `points` on one rank, the whole chain: the plan (which points to
/// integrate, near_surface.hpp), the fast evaluation of its evaluation points and the band's
/// interpolation from the surface fields (per triangle corner). NaN outside the body; the kinds
/// of the points in `kinds` if given. For tests and benchmarks; the driver shares the evaluation
/// out over its ranks (app/).
std::vector<FieldValue> evaluate_interior(const SomiglianaSources &src, const SurfaceLocator &locator, const SurfaceMesh &mesh,
                                          const std::vector<std::array<Vec3, 3>> &corner_u, const std::vector<std::array<Voigt, 3>> &corner_stress,
                                          const std::vector<Vec3> &points, const InteriorPlanOptions &plan = {}, const InteriorEvaluationOptions &fast = {},
                                          std::vector<PointKind> *kinds = nullptr);

} // namespace hssbem
