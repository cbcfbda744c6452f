// The reference factorization on the H² path (see h2_reference.hpp).
#include "hssbem/reference/h2_reference.hpp"

#include "hssbem/core/timer.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hssbem {

namespace {

double norm2(const double *a, std::size_t n)
{
  double s = 0;
  for (std::size_t i = 0; i < n; ++i) s += a[i] * a[i];
  return std::sqrt(s);
}

double dot(const double *a, const double *b, std::size_t n)
{
  double s = 0;
  for (std::size_t i = 0; i < n; ++i) s += a[i] * b[i];
  return s;
}

/// The Givens rotations of GMRES's Hessenberg matrix, and its least-squares solve.
struct Hessenberg {
  explicit Hessenberg(int m) : m(m), h(static_cast<std::size_t>(m + 1) * m), cs(m), sn(m), g(m + 1) {}
  double &at(int i, int k) { return h[i + static_cast<std::size_t>(k) * (m + 1)]; }
  /// Column k is in h (rows 0 .. k + 1): rotate it; returns the new residual estimate |g[k + 1]|.
  double rotate(int k)
  {
    for (int i = 0; i < k; ++i) {
      const double a = at(i, k), b = at(i + 1, k);
      at(i, k) = cs[i] * a + sn[i] * b, at(i + 1, k) = -sn[i] * a + cs[i] * b;
    }
    const double a = at(k, k), b = at(k + 1, k), r = std::hypot(a, b);
    cs[k] = r > 0 ? a / r : 1, sn[k] = r > 0 ? b / r : 0;
    at(k, k) = r, at(k + 1, k) = 0;
    g[k + 1] = -sn[k] * g[k], g[k] = cs[k] * g[k];
    return std::abs(g[k + 1]);
  }
  /// y (k entries) of the upper triangular solve R y = g.
  std::vector<double> solution(int k)
  {
    std::vector<double> y(k);
    for (int i = k - 1; i >= 0; --i) {
      double s = g[i];
      for (int j = i + 1; j < k; ++j) s -= at(i, j) * y[j];
      y[i] = at(i, i) != 0 ? s / at(i, i) : 0;
    }
    return y;
  }
  int m;
  std::vector<double> h, cs, sn, g;
};

SystemSelection selection_of(const std::vector<char> &pattern)
{
  SystemSelection s;
  s.displacement_known.resize(pattern.size() / 3);
  s.known.assign(pattern.size() / 3, Vec3{0, 0, 0});
  for (std::size_t j = 0; j < pattern.size(); ++j) s.displacement_known[j / 3][j % 3] = pattern[j] != 0;
  return s;
}

} // namespace

H2Reference::H2Reference(const BemOperator &op, std::vector<char> pattern, const H2ReferenceOptions &options)
    : m_pattern(std::move(pattern)), m_opt(options)
{
  if (static_cast<int>(m_pattern.size()) != 3 * op.num_nodes()) throw std::invalid_argument("reference: the pattern needs one entry per unknown");
  if (!(m_opt.rtol > 0 && m_opt.rtol < 1) || m_opt.max_it < 1 || m_opt.restart < 1 || m_opt.block < 1)
    throw std::invalid_argument("reference: H2 options out of range (0 < rtol < 1, max_it, restart, block >= 1)");
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

void H2Reference::gmres(const double *b, double *x) const
{
  const std::size_t n = m_pattern.size();
  const int m = m_opt.restart;
  const double bn = norm2(b, n);
  std::fill(x, x + n, 0.0);
  ++m_stats.solves;
  m_stats.last_residual = 0;
  if (!(bn > 0)) return;
  std::vector<double> V(static_cast<std::size_t>(m + 1) * n), Z(static_cast<std::size_t>(m) * n), r(n);
  for (int it = 0;;) {
    m_system->apply(m_sel, x, r.data()); // the true residual at every restart
    for (std::size_t i = 0; i < n; ++i) r[i] = b[i] - r[i];
    const double beta = norm2(r.data(), n);
    m_stats.last_residual = beta / bn;
    if (beta <= m_opt.rtol * bn) return;
    if (it >= m_opt.max_it)
      throw std::runtime_error("reference: GMRES on the H2 operator did not reach " + std::to_string(m_opt.rtol) + " in " + std::to_string(it) + " iterations (residual " +
                               std::to_string(beta / bn) + ")");
    Hessenberg H(m);
    H.g[0] = beta;
    for (std::size_t i = 0; i < n; ++i) V[i] = r[i] / beta;
    int k = 0;
    while (k < m && it < m_opt.max_it) {
      double *z = &Z[k * n], *w = &V[(k + 1) * n];
      solve_mesh_order(*m_factor, &V[k * n], z);
      m_system->apply(m_sel, z, w);
      for (int i = 0; i <= k; ++i) { // modified Gram–Schmidt
        const double hik = dot(w, &V[i * n], n);
        H.at(i, k) = hik;
        for (std::size_t p = 0; p < n; ++p) w[p] -= hik * V[i * n + p];
      }
      const double hk = norm2(w, n);
      H.at(k + 1, k) = hk;
      if (hk > 0)
        for (std::size_t p = 0; p < n; ++p) w[p] /= hk;
      ++it, ++m_stats.iterations;
      const double res = H.rotate(k++);
      if (res <= 0.5 * m_opt.rtol * bn || hk == 0) break;
    }
    const std::vector<double> y = H.solution(k);
    for (int j = 0; j < k; ++j)
      for (std::size_t p = 0; p < n; ++p) x[p] += y[j] * Z[j * n + p];
  }
}

void H2Reference::solve(double *X, int nrhs) const
{
  const Timer timer;
  const std::size_t n = m_pattern.size();
  std::vector<double> b(n);
  for (int c = 0; c < nrhs; ++c) {
    double *x = X + static_cast<std::size_t>(c) * n;
    std::copy_n(x, n, b.data());
    gmres(b.data(), x);
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
  gmres(b.data(), y.data());
  m_stats.solve_seconds += timer.seconds();
}

std::size_t H2Reference::memory_bytes() const { return m_system->matrix().stats().memory_bytes + m_factor->stats().bytes; }

} // namespace hssbem
