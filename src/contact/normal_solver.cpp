// Frictionless contact (contact_points.hpp): a primal–dual active set on the normal compliance,
// the inverse of its active block kept from iteration to iteration and from frame to frame.
#include "contact_points.hpp"

#include "hssbem/core/blas_threads.hpp"

#include <algorithm>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace hssbem::contact_detail {

namespace {

/// Two points load and measure alike: a node added to the capacitance with one stays valid.
bool same_point(const ContactPoint &a, const ContactPoint &b)
{
  return a.key == b.key && a.terms == b.terms && a.term_node == b.term_node && a.mw == b.mw && a.lw == b.lw && a.frame == b.frame;
}

constexpr int k_refresh = 32; // incremental updates between rebuilds (rounding), as in scenes

} // namespace

/// The normal compliance over the points' keys: entry (i, j) of the current frame's points of keys i, j.
class NormalSolver::Entries final : public MatrixEntries {
public:
  explicit Entries(int num_keys) : point_of(num_keys, -1) {}
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
    for (int k : keys) point_of[k] = -1;
    keys.clear();
    D = &c;
    for (int i = 0; i < c.size(); ++i) point_of[c.point(i).key] = i, keys.push_back(c.point(i).key);
  }
  const Compliance *D = nullptr;
  std::vector<int> point_of, keys;
};

NormalSolver::NormalSolver(int num_keys) : m_entries(std::make_shared<Entries>(num_keys)), m_cap(m_entries, num_keys), m_signature(num_keys) {}

void NormalSolver::reset() { m_stale = true; }

void NormalSolver::sync(const Compliance &D, const std::vector<int> &active_keys, bool *rebuilt)
{
  std::vector<char> want(m_signature.size(), 0), keep(m_signature.size(), 0);
  for (int n : active_keys) want[n] = 1;
  std::vector<int> drop, add;
  for (int n : m_cap.indices()) {
    const int c = m_entries->point_of[n];
    if (want[n] && c >= 0 && same_point(m_signature[n], D.point(c))) keep[n] = 1;
    else drop.push_back(n);
  }
  for (int n : active_keys)
    if (!keep[n]) add.push_back(n);
  if (drop.empty() && add.empty() && !m_stale) return;
  const double k = m_cap.size(), inc = CapacitanceInverse::update_flops(k, drop.size(), add.size());
  bool rebuild = m_stale || m_updates >= k_refresh || CapacitanceInverse::rebuild_flops(static_cast<double>(active_keys.size())) <= inc;
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
    try {
      m_cap.rebuild(active_keys);
    } catch (const std::runtime_error &) {
      throw std::runtime_error("contact: the touching points' compliance is singular (dependent contact constraints)");
    }
    m_updates = 0;
    m_stale = false;
  }
  *rebuilt = *rebuilt || rebuild;
  for (int n : add) m_signature[n] = D.point(m_entries->point_of[n]);
  if (rebuild)
    for (int n : active_keys) m_signature[n] = D.point(m_entries->point_of[n]);
}

namespace {

/// How far the points are from Signorini's conditions: the largest penetration of a watched
/// inactive leading point (of the mesh's size, `size`) and the most negative pressure of an
/// active one (of the largest pressure).
std::string signorini_residual(const Compliance &D, const std::vector<char> &active, const std::vector<int> &inactive, const std::vector<double> &g,
                               const std::vector<Vec3> &lambda, double size)
{
  double pen = 0, pull = 0, top = 0;
  for (std::size_t r = 0; r < inactive.size(); ++r) pen = std::max(pen, -g[r]);
  for (int c = 0; c < D.size(); ++c)
    if (active[c] && D.point(c).lead < 0) pull = std::max(pull, -lambda[c][0]), top = std::max(top, std::abs(lambda[c][0]));
  char text[160];
  std::snprintf(text, sizeof text, "residual %.2e (the largest penetration %.2e of the mesh's size, the most negative pressure %.2e of the largest)",
                std::max(pen / size, top > 0 ? pull / top : 0.0), pen / size, top > 0 ? pull / top : 0.0);
  return text;
}

} // namespace

NormalSolver::Result NormalSolver::solve(const Compliance &D, const std::vector<Vec3> &wf, const std::vector<char> &warm, const std::vector<char> &zone, double tol_gap,
                                         double size, int max_it, std::vector<Vec3> &lambda, const std::function<void(int, long long, long long)> &monitor)
{
  m_entries->attach(D);
  const int n = D.size();
  std::vector<char> active(n, 0);
  for (int c = 0; c < n; ++c) active[c] = !warm.empty() && warm[D.point(c).key];
  for (int c = 0; c < n; ++c) // a follower is active with its lead
    if (D.point(c).lead >= 0) active[c] = active[D.point(c).lead];
  Result r;
  std::vector<int> inactive;
  std::vector<double> g;
  for (r.iterations = 1; r.iterations <= max_it; ++r.iterations) {
    std::vector<int> keys, points; // in the points' order: their rows increase
    for (int c = 0; c < n; ++c)
      if (active[c]) keys.push_back(D.point(c).key), points.push_back(c);
    D.require(points); // the active points' columns: the others' gaps read these columns' rows
    sync(D, keys, &r.rebuilt);
    resolve(D, wf, lambda);
    std::vector<int> loaded;
    std::vector<Vec3> lambda_loaded;
    inactive.clear();
    for (int c = 0; c < n; ++c)
      if (active[c]) loaded.push_back(c), lambda_loaded.push_back(lambda[c]);
      else if (zone[c] && D.point(c).lead < 0) inactive.push_back(c);
    g.assign(inactive.size(), 0.0);
    for (std::size_t r = 0; r < inactive.size(); ++r) g[r] = wf[inactive[r]][0];
    D.apply_normal(inactive, loaded, lambda_loaded.data(), g.data());
    long long changed = 0, count = 0;
    std::vector<char> next(n, 0);
    for (int c = 0; c < n; ++c)
      if (active[c] && D.point(c).lead < 0) next[c] = lambda[c][0] >= 0;
    for (std::size_t r = 0; r < inactive.size(); ++r) next[inactive[r]] = g[r] < -tol_gap;
    for (int c = 0; c < n; ++c)
      if (D.point(c).lead >= 0) next[c] = next[D.point(c).lead];
    for (int c = 0; c < n; ++c) changed += next[c] != active[c], count += next[c];
    if (monitor) monitor(r.iterations, count, changed);
    if (changed == 0) return r;
    active.swap(next);
  }
  throw std::runtime_error("the active set did not settle in " + std::to_string(max_it) + " iterations (-contact_max_it): " +
                           signorini_residual(D, active, inactive, g, lambda, size));
}

void NormalSolver::resolve(const Compliance &D, const std::vector<Vec3> &wf, std::vector<Vec3> &lambda) const
{
  lambda.assign(D.size(), Vec3{0, 0, 0});
  const std::vector<int> &J = m_cap.indices();
  std::vector<double> rhs(J.size()), s(J.size());
  for (std::size_t p = 0; p < J.size(); ++p) rhs[p] = -wf[m_entries->point_of[J[p]]][0];
  if (!m_cap.solve(rhs.data(), s.data())) throw std::runtime_error("the active block's inverse lost its accuracy");
  for (std::size_t p = 0; p < J.size(); ++p) lambda[m_entries->point_of[J[p]]][0] = s[p];
}

void NormalSolver::haptic(const Compliance &D, const std::vector<Vec3> &wf, double tol_gap, std::vector<Vec3> &lambda) const
{
  resolve(D, wf, lambda);
  const std::vector<int> &J = m_cap.indices();
  std::vector<int> points(J.size());
  std::vector<double> y(J.size());
  for (std::size_t p = 0; p < J.size(); ++p) points[p] = m_entries->point_of[J[p]], y[p] = lambda[points[p]][0];
  const int m = static_cast<int>(J.size());
  const auto column = [&](const std::vector<int> &qs, double *out) {
    for (std::size_t j = 0; j < qs.size(); ++j)
      for (int p = 0; p < m; ++p) out[p + j * m] = m_cap.inverse_entry(p, qs[j]);
  };
  const std::vector<double> l = open_pulling_points(D, points, 1, y, column, tol_gap);
  for (int p = 0; p < m; ++p) lambda[points[p]][0] = l[p];
}

} // namespace hssbem::contact_detail
