// The target side of the fast interior evaluation: the target tree, the far and near lists,
// the downward pass and the leaves (see interior_evaluation.hpp).
#include "interior_evaluation_impl.hpp"

#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/timer.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace hssbem {

namespace {

ClusterTreeOptions target_leaves(int n)
{
  ClusterTreeOptions o;
  o.leaf_size = std::max(1, n);
  o.refine_splits = false; // points of a grid: median splits give boxes already
  return o;
}

/// One evaluation: the tree over the points, its clusters' far and near sources and the
/// downward pass, for this rank's share of the points.
///
/// The lists are built top-down: each target cluster receives the source clusters its parent
/// could not take as far, takes those now far from it, splits the larger ones, and passes the
/// rest on. A cluster left with nothing to pass on is *final*: every source is in its far field
/// (its own or an ancestor's), so its points take their values from its outer forces alone and
/// its subtree is never visited (deep inside a body, large clusters end there). A leaf is final
/// too, with the source leaves left over as its near field.
///
/// A cluster with fewer points than half its check points is *small*: fitting its outer forces
/// (three outputs per check point) would cost more than evaluating its far sources' forces at
/// each of its points (nine outputs, about twice the work), so it has none; its
/// points take the outer forces of their nearest ancestor that has them, plus the far sources of
/// the small clusters in between, directly.
class TargetPass {
public:
  TargetPass(const InteriorEvaluator::Impl &s, const std::vector<Vec3> &points, int part, int parts, InteriorEvaluationStats &stats);
  void run(std::vector<double> &out);

private:
  bool mine(int a) const { const Cluster &c = m_tree.cluster(a); return c.end > m_lo && c.begin < m_hi; }
  void sort_sources(int a);
  void downward(int a);
  /// The far sources of the small clusters from a up to the cluster whose outer forces serve a.
  std::vector<int> deferred_sources(int a) const;
  void finish_points(int a, int begin, int end, std::vector<double> &out) const;
  void add_local(int a, const Vec3 &x, double *v) const;

  const InteriorEvaluator::Impl &m_s;
  const std::vector<Vec3> &m_points;
  ClusterTree m_tree;
  std::vector<double> m_R;
  int m_lo = 0, m_hi = 0;                          ///< this share's positions in cluster order
  std::vector<std::vector<int>> m_pending;         ///< per target cluster: source clusters to sort (from its parent)
  std::vector<std::vector<int>> m_far, m_near;     ///< far source clusters; near source leaves (final clusters)
  std::vector<char> m_final;
  std::vector<std::vector<double>> m_local;        ///< per target cluster: the forces on its outer sphere (empty: none)
  std::vector<std::vector<float>> m_localf;        ///< the same in single precision (the evaluation at points)
  std::vector<int> m_owner;                        ///< per target cluster: the cluster whose outer forces serve it (−1: none)
  InteriorEvaluationStats &m_stats;
};

TargetPass::TargetPass(const InteriorEvaluator::Impl &s, const std::vector<Vec3> &points, int part, int parts, InteriorEvaluationStats &stats)
  : m_s(s), m_points(points), m_tree(points, target_leaves(s.opt.target_leaf)), m_stats(stats)
{
  m_R.resize(m_tree.num_clusters());
  for (int c = 0; c < m_tree.num_clusters(); ++c) m_R[c] = m_tree.cluster(c).radius;
  for (int l = m_tree.levels() - 1; l >= 0; --l)
    for (int c : m_tree.clusters_at_level(l)) {
      const Cluster &cl = m_tree.cluster(c);
      if (cl.left >= 0)
        for (int child : {cl.left, cl.right}) m_R[c] = std::max(m_R[c], norm(m_tree.cluster(child).centre - cl.centre) + m_R[child]);
    }
  const long long n = m_tree.num_points();
  m_lo = static_cast<int>(n * part / parts);
  m_hi = static_cast<int>(n * (part + 1) / parts);
  const int nc = m_tree.num_clusters();
  m_pending.assign(nc, {});
  m_far.assign(nc, {});
  m_near.assign(nc, {});
  m_final.assign(nc, 0);
  m_local.assign(nc, {});
  m_localf.assign(nc, {});
  m_owner.assign(nc, -1);
}

/// Sort a's pending sources into far, near (a leaf) or passed on to the children (see the class).
void TargetPass::sort_sources(int a)
{
  const Cluster &ta = m_tree.cluster(a);
  const bool leaf = ta.left < 0;
  std::vector<int> stack = std::move(m_pending[a]), keep;
  while (!stack.empty()) {
    const int b = stack.back();
    stack.pop_back();
    const Cluster &sb = m_s.tree.cluster(b);
    if (m_s.far(ta.centre, m_R[a], b)) m_far[a].push_back(b);
    else if (sb.left < 0 || (!leaf && m_s.R[b] <= m_R[a])) keep.push_back(b);
    else stack.push_back(sb.left), stack.push_back(sb.right);
  }
  if (leaf || keep.empty()) {
    m_final[a] = 1;
    m_near[a] = std::move(keep);
    return;
  }
  m_pending[ta.left] = keep;
  m_pending[ta.right] = std::move(keep);
}

/// The forces on a's outer sphere: fitted at its inner check points to the far sources' forces
/// and the parent's forces.
void TargetPass::downward(int a)
{
  const Cluster &ta = m_tree.cluster(a);
  const detail::Fit &down = m_s.down, &up = m_s.up;
  const int parent = ta.parent, pc = down.pc();
  m_owner[a] = parent >= 0 ? m_owner[parent] : -1;
  const bool inherit = parent >= 0 && !m_local[parent].empty();
  if (2 * ta.size() < pc || (!inherit && m_far[a].empty())) return; // small, or no far field yet
  m_owner[a] = a;
  // The check points relative to a's centre, in floats; the far field summed pair by pair.
  std::vector<float> check(3 * static_cast<std::size_t>(pc));
  const double rc = m_R[a] * down.r_check;
  for (int i = 0; i < pc; ++i)
    check[i] = static_cast<float>(rc * down.check.x[i]), check[pc + i] = static_cast<float>(rc * down.check.y[i]), check[2 * pc + i] = static_cast<float>(rc * down.check.z[i]);
  const float *const p[3] = {check.data(), check.data() + pc, check.data() + 2 * pc};
  const SomiglianaConstants &k = m_s.src.constants();
  std::vector<double> field(3 * pc, 0.0);
  if (inherit) detail::add_forces_to(k, p, pc, m_tree.cluster(parent).centre - ta.centre, m_R[parent] * down.r_equiv, down.equiv, m_localf[parent].data(), field.data());
  for (int b : m_far[a]) detail::add_forces_to(k, p, pc, m_s.C[b] - ta.centre, m_s.R[b] * up.r_equiv, up.equiv, m_s.qf[b].data(), field.data());
  down.solve(m_R[a], field, m_local[a]);
  m_localf[a] = detail::to_float(m_local[a]);
#pragma omp atomic
  m_stats.kernel_fit += static_cast<long long>(pc) * down.pe() * (static_cast<long long>(m_far[a].size()) + inherit);
}

/// v += the far field at x (in cluster a) of the forces on a's outer sphere.
void TargetPass::add_local(int a, const Vec3 &x, double *v) const
{
  if (m_localf[a].empty()) return;
  detail::add_forces_field(m_s.src.constants(), x, m_tree.cluster(a).centre, m_R[a] * m_s.down.r_equiv, m_s.down.equiv, m_localf[a].data(), v);
}

std::vector<int> TargetPass::deferred_sources(int a) const
{
  std::vector<int> out;
  for (int c = a; c >= 0 && c != m_owner[a]; c = m_tree.cluster(c).parent) out.insert(out.end(), m_far[c].begin(), m_far[c].end());
  return out;
}

/// The points at positions [begin, end) of final cluster a: its far field (outer forces, and the
/// deferred far sources directly) and its near sources. Source by source, so that a near leaf's
/// particles stay in cache for all the points; each point sums in the same order whatever the range.
void TargetPass::finish_points(int a, int begin, int end, std::vector<double> &out) const
{
  const std::vector<int> deferred = deferred_sources(a);
  InteriorEvaluationStats s;
  auto value = [&](int p) { return &out[static_cast<std::size_t>(m_tree.perm()[p]) * field_outputs]; };
  auto point = [&](int p) -> const Vec3 & { return m_points[m_tree.perm()[p]]; };
  if (m_owner[a] >= 0)
    for (int p = begin; p < end; ++p) add_local(m_owner[a], point(p), value(p));
  for (int b : deferred)
    for (int p = begin; p < end; ++p) m_s.add_equivalent(point(p), b, value(p));
  for (int b : m_near[a])
    for (int p = begin; p < end; ++p) m_s.add_leaf(point(p), b, value(p), s);
  const long long n = end - begin, pe = m_s.up.pe();
  s.kernel_far += n * (pe * static_cast<long long>(deferred.size()) + (m_owner[a] >= 0 ? pe : 0));
#pragma omp critical(interior_stats)
  {
    m_stats.direct_far += static_cast<long long>(deferred.size()) * n;
    m_stats.kernel_far += s.kernel_far;
    m_stats.kernel_near += s.kernel_near;
    m_stats.kernel_inner += s.kernel_inner;
    m_stats.adaptive_triangles += s.adaptive_triangles;
  }
}

void TargetPass::run(std::vector<double> &out)
{
  const SerialBlas serial; // the fits' products run inside the loops over clusters
  Timer timer;
  m_pending[0] = {0};
  std::vector<int> level{0}, finals;
  while (!level.empty()) {
#pragma omp parallel for schedule(dynamic)
    for (std::size_t i = 0; i < level.size(); ++i) {
      sort_sources(level[i]);
      downward(level[i]);
    }
    std::vector<int> next;
    for (int a : level) {
      m_stats.far_pairs += static_cast<long long>(m_far[a].size());
      m_stats.local_fits += m_owner[a] == a;
      if (m_final[a]) {
        finals.push_back(a);
        continue;
      }
      const Cluster &ta = m_tree.cluster(a);
      for (int child : {ta.left, ta.right})
        if (mine(child)) next.push_back(child);
    }
    level.swap(next);
  }
  m_stats.downward_seconds += timer.seconds();
  timer.restart();
  // Work items of at most 128 points of the final clusters, within this share.
  std::vector<std::array<int, 3>> items;
  for (int a : finals) {
    const Cluster &ta = m_tree.cluster(a);
    m_stats.near_pairs += static_cast<long long>(m_near[a].size());
    for (int b : m_near[a]) m_stats.near_triangle_visits += static_cast<long long>(std::min(ta.end, m_hi) - std::max(ta.begin, m_lo)) * m_s.tree.cluster(b).size();
    for (int p = std::max(ta.begin, m_lo); p < std::min(ta.end, m_hi); p += 128) items.push_back({a, p, std::min({p + 128, ta.end, m_hi})});
  }
#pragma omp parallel for schedule(dynamic)
  for (std::size_t i = 0; i < items.size(); ++i) finish_points(items[i][0], items[i][1], items[i][2], out);
  m_stats.near_seconds += timer.seconds();
  m_stats.target_clusters += m_tree.num_clusters();
}

} // namespace

std::vector<double> InteriorEvaluator::evaluate(const std::vector<Vec3> &points, int part, int parts) const
{
  std::vector<double> out(points.size() * field_outputs, 0.0);
  m_stats = InteriorEvaluationStats{};
  m_stats.source_clusters = m_impl->tree.num_clusters();
  if (points.empty()) return out;
  if (m_impl->opt.direct) {
    const long long n = static_cast<long long>(points.size()), lo = n * part / parts, hi = n * (part + 1) / parts;
#pragma omp parallel for schedule(dynamic, 16)
    for (long long i = lo; i < hi; ++i) m_impl->src.add_all(points[i], &out[static_cast<std::size_t>(i) * field_outputs]);
    return out;
  }
  TargetPass(*m_impl, points, part, parts, m_stats).run(out);
  return out;
}

std::vector<FieldValue> evaluate_interior(const SomiglianaSources &src, const SurfaceLocator &locator, const SurfaceMesh &mesh,
                                          const std::vector<std::array<Vec3, 3>> &corner_u, const std::vector<std::array<Voigt, 3>> &corner_stress,
                                          const std::vector<Vec3> &points, const InteriorPlanOptions &plan, const InteriorEvaluationOptions &fast,
                                          std::vector<PointKind> *kinds)
{
  const InteriorPlan p(locator, mesh, points, plan);
  if (kinds) {
    kinds->resize(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) (*kinds)[i] = p.kind(i);
  }
  const InteriorEvaluator evaluator(src, fast);
  return p.finish(evaluator.evaluate(p.evaluation_points()), corner_u, corner_stress);
}

} // namespace hssbem
