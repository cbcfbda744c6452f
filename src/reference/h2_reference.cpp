// The reference factorization on the H² path (see h2_reference.hpp).
#include "hssbem/reference/h2_reference.hpp"

#include "hssbem/core/timer.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hssbem {

namespace {

SystemSelection selection_of(const std::vector<char> &pattern)
{
  SystemSelection s;
  s.displacement_known.resize(pattern.size() / 3);
  s.known.assign(pattern.size() / 3, Vec3{0, 0, 0});
  for (std::size_t j = 0; j < pattern.size(); ++j) s.displacement_known[j / 3][j % 3] = pattern[j] != 0;
  return s;
}

} // namespace

H2Reference::H2Reference(const BemOperator &op, std::vector<char> pattern, const H2ReferenceOptions &options, std::unique_ptr<KrylovSolver> krylov)
    : m_pattern(std::move(pattern)), m_opt(options), m_krylov(std::move(krylov))
{
  if (static_cast<int>(m_pattern.size()) != 3 * op.num_nodes()) throw std::invalid_argument("reference: the pattern needs one entry per unknown");
  if (!(m_opt.rtol > 0 && m_opt.rtol < 1) || m_opt.max_it < 1 || m_opt.block < 1)
    throw std::invalid_argument("reference: H2 options out of range (0 < rtol < 1, max_it, block >= 1)");
  if (!m_krylov) throw std::invalid_argument("reference: the H2 reference needs a Krylov solver for its accurate solves (HssbemKrylovCreate)");
  m_sel = selection_of(m_pattern);
  Timer timer;
  H2Options o = m_opt.compression;
  o.pressure_columns = m_opt.with_pressure;
  m_system = std::make_unique<H2BemSystem>(op, o);
  m_stats.compress_seconds = timer.seconds();
  timer.restart();
  m_cache = std::make_unique<H2FactorCache>(m_system->matrix());
  m_factor = std::make_unique<H2Factorization>(*m_cache, m_sel, m_opt.factor);
  m_stats.factor_seconds = timer.seconds();
}

H2Reference::~H2Reference() = default;

void H2Reference::accurate_solve(const double *b, double *x) const
{
  const std::size_t n = m_pattern.size();
  std::fill(x, x + n, 0.0);
  ++m_stats.solves;
  const auto apply = [this](const double *in, double *out) { m_system->apply(m_sel, in, out); };
  const auto precondition = [this](const double *in, double *out) { solve_mesh_order(*m_factor, in, out); };
  m_stats.iterations += m_krylov->solve(static_cast<int>(n), apply, precondition, b, x, m_opt.rtol, m_opt.max_it);
}

void H2Reference::solve(double *X, int nrhs) const
{
  const Timer timer;
  const std::size_t n = m_pattern.size();
  std::vector<double> b(n);
  for (int c = 0; c < nrhs; ++c) {
    double *x = X + static_cast<std::size_t>(c) * n;
    std::copy_n(x, n, b.data());
    accurate_solve(b.data(), x);
  }
  m_stats.solve_seconds += timer.seconds();
}

void H2Reference::reference_columns(const std::vector<int> &js, std::size_t first, int count, double *out) const
{
  const H2Matrix &K = m_system->matrix();
  const int np = K.tree().num_points(), w = K.col_block();
  std::vector<double> X(static_cast<std::size_t>(w) * np * count, 0.0);
  for (int q = 0; q < count; ++q) {
    const int j = js[first + q], c = j % 3;
    const int slot = m_pattern[j] ? c : 3 + c; // H(:, j) where u is known, −G(:, j) where t is
    const double sign = m_pattern[j] ? 1.0 : -1.0;
    X[static_cast<std::size_t>(q) * w * np + static_cast<std::size_t>(w) * K.tree().iperm()[j / 3] + slot] = sign / K.col_scale(slot);
  }
  K.apply(X.data(), w * np, out, 3 * np, count);
}

void H2Reference::columns(const std::vector<int> &js, double *out) const
{
  const Timer timer;
  const std::size_t n = m_pattern.size();
  for (int j : js)
    if (j < 0 || static_cast<std::size_t>(j) >= n) throw std::out_of_range("reference: column " + std::to_string(j) + " out of range");
  const ClusterTree &tree = m_system->matrix().tree();
  std::vector<double> Y;
  for (std::size_t first = 0; first < js.size(); first += m_opt.block) {
    const int count = static_cast<int>(std::min<std::size_t>(m_opt.block, js.size() - first));
    Y.assign(n * count, 0.0);
    reference_columns(js, first, count, Y.data());
    m_factor->solve_block(Y.data(), count, static_cast<int>(n));
    for (int q = 0; q < count; ++q) tree.to_mesh_order(&Y[q * n], out + (first + q) * n, 3);
  }
  m_stats.columns += static_cast<long long>(js.size());
  m_stats.column_seconds += timer.seconds();
}

void H2Reference::free_response(const SystemSelection &sel, std::vector<double> &y) const
{
  const std::size_t n = m_pattern.size();
  if (sel.displacement_known.size() * 3 != n) throw std::invalid_argument("reference: the values do not match the reference's nodes");
  for (std::size_t j = 0; j < n; ++j)
    if (static_cast<char>(sel.displacement_known[j / 3][j % 3]) != m_pattern[j])
      throw std::invalid_argument("reference: the free response needs the reference pattern (unknown " + std::to_string(j) + " differs)");
  const Timer timer;
  const std::vector<double> b = m_system->rhs(sel);
  y.resize(n);
  accurate_solve(b.data(), y.data());
  m_stats.solve_seconds += timer.seconds();
}

std::size_t H2Reference::memory_bytes() const { return m_system->matrix().stats().memory_bytes + m_factor->stats().bytes; }

} // namespace hssbem
