// Frictionless contact (contact_points.hpp): a primal–dual active set on the normal compliance,
// the inverse of its active block kept from iteration to iteration and from frame to frame.
#include "contact_points.hpp"

#include "hssbem/core/blas_threads.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace hssbem::contact_detail {

namespace {

/// Two points load and measure alike: a node added to the capacitance with one stays valid.
bool same_point(const ContactPoint &a, const ContactPoint &b)
{
  return a.obstacle == b.obstacle && a.other == b.other && a.terms == b.terms && a.term_node == b.term_node && a.mw == b.mw && a.lw == b.lw && a.frame == b.frame;
}

constexpr int k_refresh = 32; // incremental updates between rebuilds (rounding), as in scenes

} // namespace

/// The normal compliance over dof nodes: entry (i, j) of the current frame's points at nodes i, j.
class NormalSolver::Entries final : public MatrixEntries {
public:
  explicit Entries(int num_nodes) : point_of(num_nodes, -1) {}
  void block(const std::vector<int> &rows, const std::vector<int> &cols, double *out, std::size_t ld) const override
  {
    const int nr = static_cast<int>(rows.size()), nc = static_cast<int>(cols.size());
#pragma omp parallel for schedule(static) if (static_cast<double>(nr) * nc > 65536)
    for (int q = 0; q < nc; ++q)
      for (int p = 0; p < nr; ++p) out[p + q * ld] = D->normal(point_of[rows[p]], point_of[cols[q]]);
  }
  /// Points the entries at a frame's compliance.
  void attach(const Compliance &c)
  {
    for (int n : nodes) point_of[n] = -1;
    nodes.clear();
    D = &c;
    for (int i = 0; i < c.size(); ++i) point_of[c.point(i).node] = i, nodes.push_back(c.point(i).node);
  }
  const Compliance *D = nullptr;
  std::vector<int> point_of, nodes;
};

NormalSolver::NormalSolver(int num_nodes) : m_entries(std::make_shared<Entries>(num_nodes)), m_cap(m_entries, num_nodes), m_signature(num_nodes) {}

void NormalSolver::sync(const Compliance &D, const std::vector<int> &active_nodes, bool *rebuilt)
{
  std::vector<char> want(m_signature.size(), 0), keep(m_signature.size(), 0);
  for (int n : active_nodes) want[n] = 1;
  std::vector<int> drop, add;
  for (int n : m_cap.indices()) {
    const int c = m_entries->point_of[n];
    if (want[n] && c >= 0 && same_point(m_signature[n], D.point(c))) keep[n] = 1;
    else drop.push_back(n);
  }
  for (int n : active_nodes)
    if (!keep[n]) add.push_back(n);
  if (drop.empty() && add.empty()) return;
  const double k = m_cap.size(), inc = CapacitanceInverse::update_flops(k, drop.size(), add.size());
  bool rebuild = m_updates >= k_refresh || CapacitanceInverse::rebuild_flops(static_cast<double>(active_nodes.size())) <= inc;
  const SerialBlas serial; // the updates' products run on OpenMP threads (gemm_over_threads), as in scenes
  if (!rebuild) {
    try {
      m_cap.update(drop, add);
      ++m_updates;
    } catch (const std::runtime_error &) { // a singular Schur complement on the way: start afresh
      rebuild = true;
    }
  }
  if (rebuild) {
    m_cap.rebuild(active_nodes);
    m_updates = 0;
  }
  *rebuilt = *rebuilt || rebuild;
  for (int n : add) m_signature[n] = D.point(m_entries->point_of[n]);
  if (rebuild)
    for (int n : active_nodes) m_signature[n] = D.point(m_entries->point_of[n]);
}

NormalSolver::Result NormalSolver::solve(const Compliance &D, const std::vector<Vec3> &wf, const std::vector<char> &warm, const std::vector<char> &zone, double tol_gap,
                                         int max_it, std::vector<Vec3> &lambda, const std::function<void(int, long long, long long)> &monitor)
{
  m_entries->attach(D);
  const int n = D.size();
  std::vector<char> active(n, 0);
  for (int c = 0; c < n; ++c) active[c] = !warm.empty() && warm[D.point(c).node];
  Result r;
  for (r.iterations = 1; r.iterations <= max_it; ++r.iterations) {
    std::vector<int> nodes, points; // in the points' order: their rows increase
    for (int c = 0; c < n; ++c)
      if (active[c]) nodes.push_back(D.point(c).node), points.push_back(c);
    D.require(points); // the active points' columns: the others' gaps read these columns' rows
    sync(D, nodes, &r.rebuilt);
    resolve(D, wf, lambda);
    std::vector<int> inactive, loaded;
    std::vector<Vec3> lambda_loaded;
    for (int c = 0; c < n; ++c)
      if (active[c]) loaded.push_back(c), lambda_loaded.push_back(lambda[c]);
      else if (zone[c]) inactive.push_back(c);
    std::vector<double> g(inactive.size());
    for (std::size_t r = 0; r < inactive.size(); ++r) g[r] = wf[inactive[r]][0];
    D.apply_normal(inactive, loaded, lambda_loaded.data(), g.data());
    long long changed = 0, count = 0;
    std::vector<char> next(n, 0);
    for (int c = 0; c < n; ++c)
      if (active[c]) next[c] = lambda[c][0] >= 0;
    for (std::size_t r = 0; r < inactive.size(); ++r) next[inactive[r]] = g[r] < -tol_gap;
    for (int c = 0; c < n; ++c) changed += next[c] != active[c], count += next[c];
    if (monitor) monitor(r.iterations, count, changed);
    if (changed == 0) return r;
    active.swap(next);
  }
  throw std::runtime_error("contact: the active set did not settle in " + std::to_string(max_it) + " iterations (-contact_max_it)");
}

void NormalSolver::resolve(const Compliance &D, const std::vector<Vec3> &wf, std::vector<Vec3> &lambda) const
{
  lambda.assign(D.size(), Vec3{0, 0, 0});
  const std::vector<int> &J = m_cap.indices();
  std::vector<double> rhs(J.size()), s(J.size());
  for (std::size_t p = 0; p < J.size(); ++p) rhs[p] = -wf[m_entries->point_of[J[p]]][0];
  if (!m_cap.solve(rhs.data(), s.data())) throw std::runtime_error("contact: the active block's inverse lost its accuracy");
  for (std::size_t p = 0; p < J.size(); ++p) lambda[m_entries->point_of[J[p]]][0] = s[p];
}

} // namespace hssbem::contact_detail
