// The H² factorization's dense top block (see top_block.hpp).
#include "top_block.hpp"

#include "hssbem/h2factor/h2_breakdown.hpp"

#include "hssbem/core/dense_ops.hpp"
#include "hssbem/core/fault.hpp"
#include "hssbem/core/lapack.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <limits>
#include <stdexcept>

namespace hssbem::h2f {

namespace {

/// Refinement steps before a solve counts as not converging (LAPACK dsgesv's ITERMAX).
constexpr int kMaxSteps = 30;

double inf_norm(const double *v, int n)
{
  double s = 0;
  for (int i = 0; i < n; ++i) s = std::max(s, std::abs(v[i]));
  return s;
}

} // namespace

// ---------------------------------------------------------------------------------------------
// The factorization and the solve.

bool TopBlock::factor(DenseMatrix A, int mixed_from)
{
  const int n = A.m;
  m_n = n;
  m_mixed = false;
  if (mixed_from > 0 && n >= mixed_from) {
    m_lu.resize(A.a.size());
    std::vector<double> rows(n, 0.0), b(n), x(n), ones(n, 1.0);
    for (std::size_t j = 0; j < static_cast<std::size_t>(n); ++j) // rounded, and ‖A‖_∞'s row sums, in one pass
      for (std::size_t i = 0; i < static_cast<std::size_t>(n); ++i) {
        m_lu[i + j * n] = static_cast<float>(A.a[i + j * n]);
        rows[i] += std::abs(A.a[i + j * n]);
      }
    m_norm = inf_norm(rows.data(), n);
    m_piv.resize(n);
    if (lapack::getrf(n, m_lu.data(), n, m_piv.data()) == 0) {
      m_A = std::move(A);
      m_mixed = true;
      lapack::gemv('N', n, n, 1.0, m_A.data(), m_A.ld(), ones.data(), 0.0, b.data()); // a trial solve: b = A·1
      if (refine(b.data(), x.data())) return true;
      A = std::move(m_A); // the single-precision factor does not contract: LU in double
      m_mixed = false;
    }
    std::vector<float>().swap(m_lu);
  }
  m_A = std::move(A);
  return dense::lu_regular(m_A, m_piv);
}

bool TopBlock::refine(const double *b, double *x) const
{
  const int n = m_n;
  const double eps = std::numeric_limits<double>::epsilon(), cte = m_norm * eps * std::sqrt(static_cast<double>(n));
  std::vector<double> r(b, b + n);
  std::vector<float> d(n);
  std::fill(x, x + n, 0.0);
  double last = HUGE_VAL;
  for (int step = 1; step <= kMaxSteps; ++step) {
    std::copy(r.begin(), r.end(), d.begin());
    lapack::getrs('N', n, 1, m_lu.data(), n, m_piv.data(), d.data(), n);
    for (int i = 0; i < n; ++i) x[i] += d[i];
    std::copy(b, b + n, r.begin());
    lapack::gemv('N', n, n, -1.0, m_A.data(), m_A.ld(), x, 1.0, r.data());
    const double rn = inf_norm(r.data(), n);
    if (rn <= inf_norm(x, n) * cte) return true;
    if (!(rn < 0.5 * last)) { // stalled or diverging: keep the better of the last two iterates
      if (!(rn <= last))
        for (int i = 0; i < n; ++i) x[i] -= d[i];
      return false;
    }
    last = rn;
  }
  return false;
}

void TopBlock::solve(double *x) const
{
  const int n = m_n;
  if (n == 0) return;
  if (!m_mixed) {
    lapack::getrs('N', n, 1, m_A.data(), m_A.ld(), m_piv.data(), x, n);
    return;
  }
  std::vector<double> b(x, x + n);
  refine(b.data(), x); // should it stall (the trial solve did not), x is its better last iterate
}

// ---------------------------------------------------------------------------------------------
// The top spread over the ranks.

int SpreadTop::local_column(int c) const
{
  const int j = c / kBlock;
  if (j % m_ranks != m_rank) return -1;
  return (j / m_ranks) * kBlock + c % kBlock;
}

void SpreadTop::factor(const RankComm &comm, int n, std::vector<float> local, std::vector<double> row_sums, double trial_tol)
{
  m_comm = &comm;
  m_n = n;
  m_ranks = comm.size();
  m_rank = comm.rank();
  collectively(comm, [&] {
    check_spread_size(n, kBlock, m_ranks);
    if (local.size() != static_cast<std::size_t>(n) * spread_columns(n, kBlock, m_rank, m_ranks) || row_sums.size() != static_cast<std::size_t>(n))
      throw std::logic_error("H2 factorization: a spread top of the wrong size");
    m_lu = std::move(local);
    m_piv.assign(n, 0);
  });
  if (n == 0) return;
  const int info = comm.spread_getrf(n, kBlock, m_lu.data(), m_piv.data());
  if (info == 0) { // the same on every rank
    comm.sum(row_sums.data(), n); // b = A·1
    solve(row_sums.data());
  }
  // Each rank judges the trial on its own copy of x (the sums' rounding may differ by rank), and
  // the agreement makes one verdict of them: a breakdown on any rank is one on every rank.
  collectively<H2Breakdown>(comm, [&] {
    m_trial = HUGE_VAL;
    if (info == 0) {
      m_trial = 0;
      for (double v : row_sums) m_trial = std::max(m_trial, std::abs(v - 1.0));
    }
    if (m_trial <= trial_tol && !fault_armed("SpreadTopBreakdown")) return; // false for NaN too
    char trial[32];
    std::snprintf(trial, sizeof trial, info != 0 ? "a zero pivot" : "a trial solve off by %.1e", m_trial);
    throw H2Breakdown("H2 factorization broke down: the top block (" + std::to_string(n) + " unknowns, spread over the ranks) is singular to single precision (" + trial +
                      (fault_armed("SpreadTopBreakdown") ? ", injected fault at SpreadTopBreakdown" : "") + "; a tolerance below 1e-5 factors it in double)");
  });
}

void SpreadTop::solve(double *x) const
{
  const int n = m_n, blocks = (n + kBlock - 1) / kBlock;
  if (n == 0) return;
  const std::size_t ld = static_cast<std::size_t>(n);
  const RankComm &comm = *m_comm;
  std::vector<double> u, y, part, v;
  collectively(comm, [&] {
    for (auto *w : {&u, &y, &v}) w->assign(n, 0.0);
    part.resize(kBlock);
  });
  for (int i = 0; i < n; ++i)
    if (m_piv[i] - 1 != i) std::swap(x[i], x[m_piv[i] - 1]);
  // Forward, L unit lower: u gathers this rank's columns' updates; the owner of block k takes
  // the sum of every rank's to its rows, and solves.
  for (int k = 0; k < blocks; ++k) {
    const int c0 = k * kBlock, c1 = std::min(n, c0 + kBlock), w = c1 - c0;
    std::copy(u.begin() + c0, u.begin() + c1, part.begin());
    comm.sum(part.data(), w);
    if (k % m_ranks != m_rank) continue;
    const float *col0 = m_lu.data() + static_cast<std::size_t>(local_column(c0)) * ld;
    for (int i = 0; i < w; ++i) y[c0 + i] = x[c0 + i] - part[i];
    for (int j = 0; j < w; ++j) {
      const float *col = col0 + j * ld;
      const double yj = y[c0 + j];
      for (int i = j + 1; i < w; ++i) y[c0 + i] -= static_cast<double>(col[c0 + i]) * yj;
      for (int i = c1; i < n; ++i) u[i] += static_cast<double>(col[i]) * yj;
    }
  }
  // Backward, U: v gathers the updates from the right; the result goes to x, zero where other
  // ranks solve, and one sum makes it whole everywhere.
  std::fill(x, x + n, 0.0);
  for (int k = blocks - 1; k >= 0; --k) {
    const int c0 = k * kBlock, c1 = std::min(n, c0 + kBlock), w = c1 - c0;
    std::copy(v.begin() + c0, v.begin() + c1, part.begin());
    comm.sum(part.data(), w);
    if (k % m_ranks != m_rank) continue;
    const float *col0 = m_lu.data() + static_cast<std::size_t>(local_column(c0)) * ld;
    for (int i = 0; i < w; ++i) x[c0 + i] = y[c0 + i] - part[i];
    for (int j = w - 1; j >= 0; --j) {
      const float *col = col0 + j * ld;
      x[c0 + j] /= static_cast<double>(col[c0 + j]);
      const double xj = x[c0 + j];
      for (int i = 0; i < j; ++i) x[c0 + i] -= static_cast<double>(col[c0 + i]) * xj;
      for (int i = 0; i < c0; ++i) v[i] += static_cast<double>(col[i]) * xj;
    }
  }
  comm.sum(x, n);
}

// ---------------------------------------------------------------------------------------------
// The stored form (persistence).

void TopBlock::pack(PackWriter &w) const
{
  w.put(m_n), w.put(m_mixed ? 1 : 0), w.put(m_norm);
  w.put(m_A), w.put(m_lu), w.put(m_piv);
}

void TopBlock::unpack(PackReader &r)
{
  m_n = r.get_int(0, INT32_MAX, "top size");
  m_mixed = r.get_int(0, 1, "top kind") == 1;
  m_norm = r.get_double();
  r.get(m_A), r.get(m_lu), r.get(m_piv);
  const std::size_t n = static_cast<std::size_t>(m_n);
  if (m_A.m != m_n || m_A.n != m_n || m_A.a.size() != n * n || m_piv.size() != n || m_lu.size() != (m_mixed ? n * n : 0))
    throw std::invalid_argument("damaged: the top does not fit its size");
  for (int p : m_piv)
    if (p < 1 || p > m_n) throw std::invalid_argument("damaged: a pivot of the top out of range");
}

void SpreadTop::pack(PackWriter &w) const
{
  w.put(m_n), w.put(m_ranks), w.put(m_rank), w.put(m_trial);
  w.put(m_lu), w.put(m_piv);
}

void SpreadTop::unpack(const RankComm &comm, PackReader &r)
{
  m_comm = &comm;
  m_n = r.get_int(0, INT32_MAX, "top size");
  m_ranks = r.get_int(), m_rank = r.get_int();
  m_trial = r.get_double();
  r.get(m_lu), r.get(m_piv);
  if (m_ranks != comm.size() || m_rank != comm.rank()) throw std::invalid_argument("damaged: the top is another rank's share");
  if (m_lu.size() != static_cast<std::size_t>(m_n) * spread_columns(m_n, kBlock, m_rank, m_ranks) || m_piv.size() != static_cast<std::size_t>(m_n))
    throw std::invalid_argument("damaged: the top does not fit its size");
  for (int p : m_piv)
    if (p < 0 || p > m_n) throw std::invalid_argument("damaged: a pivot of the top out of range");
}

} // namespace hssbem::h2f
