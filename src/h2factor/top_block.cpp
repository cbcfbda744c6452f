// The H² factorization's dense top block (see top_block.hpp).
#include "top_block.hpp"

#include "frontier.hpp"

#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/lapack.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
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

/// x ← (L U)⁻¹ P x with the single-precision factors of getrf, in double arithmetic. A solve
/// that rounded x itself to single precision (sgetrs) would not be a linear operator: GMRES with
/// it as the preconditioner stalled at a true residual of 1.9e-6 (80k sphere on 2 ranks, its
/// recurrence at 6e-8). Rounding only the factors keeps the operator fixed, as the steps' panels
/// do. Column by column, so that each factor is streamed once.
void solve_with_single_lu(int n, const float *lu, const int *piv, double *x)
{
  const std::size_t ld = static_cast<std::size_t>(n);
  for (int i = 0; i < n; ++i)
    if (piv[i] - 1 != i) std::swap(x[i], x[piv[i] - 1]);
  for (int j = 0; j < n; ++j) { // L, unit lower triangular
    const double xj = x[j];
    if (xj == 0) continue;
    const float *col = lu + j * ld;
    for (int i = j + 1; i < n; ++i) x[i] -= static_cast<double>(col[i]) * xj;
  }
  for (int j = n - 1; j >= 0; --j) { // U
    const float *col = lu + j * ld;
    x[j] /= static_cast<double>(col[j]);
    const double xj = x[j];
    if (xj == 0) continue;
    for (int i = 0; i < j; ++i) x[i] -= static_cast<double>(col[i]) * xj;
  }
}

std::vector<int> box_rows(const BlockGrid &G)
{
  std::vector<int> rows(G.boxes());
  std::iota(rows.begin(), rows.end(), 0);
  return rows;
}

} // namespace

// ---------------------------------------------------------------------------------------------
// The grid of blocks.

std::size_t BlockGrid::bytes() const
{
  std::size_t s = off.size() * sizeof(int);
  for (const DenseMatrix &B : blocks) s += B.bytes();
  return s;
}

DenseMatrix BlockGrid::dense() const
{
  const int n = size(), nb = boxes();
  DenseMatrix A(n, n);
  for_each_cluster(box_rows(*this), [&](int s) {
    for (int t = 0; t < nb; ++t) {
      const DenseMatrix &B = block(s, t);
      for (int j = 0; j < B.n; ++j) std::copy_n(B.data() + static_cast<std::size_t>(j) * B.m, B.m, &A(off[s], off[t] + j));
    }
  });
  return A;
}

void BlockGrid::dense_single(float *out, double *norm) const
{
  const std::size_t n = static_cast<std::size_t>(size());
  const int nb = boxes();
  std::vector<double> rows(n, 0.0);
  for_each_cluster(box_rows(*this), [&](int s) { // box s's rows, by one thread
    for (int t = 0; t < nb; ++t) {
      const DenseMatrix &B = block(s, t);
      for (int j = 0; j < B.n; ++j) {
        const double *src = B.data() + static_cast<std::size_t>(j) * B.m;
        float *dst = out + (off[t] + j) * n + off[s];
        double *row = rows.data() + off[s];
        for (int i = 0; i < B.m; ++i) {
          dst[i] = static_cast<float>(src[i]);
          row[i] += std::abs(src[i]);
        }
      }
    }
  });
  *norm = h2f::inf_norm(rows.data(), static_cast<int>(n));
}

void BlockGrid::gemv(double alpha, const double *x, double *y) const
{
  const int nb = boxes();
  for (int s = 0; s < nb; ++s)
    for (int t = 0; t < nb; ++t) {
      const DenseMatrix &B = block(s, t);
      if (B.m > 0 && B.n > 0) lapack::gemv('N', B.m, B.n, alpha, B.data(), B.ld(), x + off[t], 1.0, y + off[s]);
    }
}

// ---------------------------------------------------------------------------------------------
// The sinks.

void GridSink::begin(const std::vector<int> &off)
{
  m_G.off = off;
  const std::size_t nb = off.size() - 1;
  m_G.blocks.assign(nb * nb, DenseMatrix());
}

void GridSink::put(int s, int t, DenseMatrix B) { m_G.blocks[static_cast<std::size_t>(s) * m_G.boxes() + t] = std::move(B); }

void SingleSink::begin(const std::vector<int> &off)
{
  m_off = off;
  m_A.n = off.back();
  // Not cleared first: every entry is written once, by the thread that owns its box row.
  m_A.a.reset(new float[static_cast<std::size_t>(m_A.n) * m_A.n]);
  m_A.row_sums.assign(m_A.n, 0.0);
}

void SingleSink::put(int s, int t, DenseMatrix B)
{
  const std::size_t n = static_cast<std::size_t>(m_A.n);
  if (B.m != m_off[s + 1] - m_off[s] || B.n != m_off[t + 1] - m_off[t]) throw std::logic_error("H2 factorization: a top block of the wrong size");
  double *sums = m_A.row_sums.data() + m_off[s];
  for (int j = 0; j < B.n; ++j) {
    const double *src = B.data() + static_cast<std::size_t>(j) * B.ld();
    float *dst = m_A.a.get() + (m_off[t] + j) * n + m_off[s];
    for (int i = 0; i < B.m; ++i) {
      dst[i] = static_cast<float>(src[i]);
      sums[i] += src[i];
    }
  }
}

// ---------------------------------------------------------------------------------------------
// The factorization and the solve.

bool TopBlock::factor_single(SingleTop A, double trial_tol)
{
  const int n = A.n;
  m_n = n;
  m_mixed = false;
  m_single = true;
  m_steps = 0;
  m_A = DenseMatrix();
  m_grid = BlockGrid();
  m_lu = std::move(A.a);
  m_piv.resize(n);
  if (n == 0) return true;
  if (lapack::getrf(n, m_lu.get(), n, m_piv.data()) != 0) return false;
  // The trial: x = A⁻¹ (A·1) should be 1 to the accuracy a preconditioner needs.
  std::vector<double> x = std::move(A.row_sums);
  solve_with_single_lu(n, m_lu.get(), m_piv.data(), x.data());
  m_trial = 0;
  for (double v : x) m_trial = std::max(m_trial, std::abs(v - 1.0));
  return m_trial <= trial_tol; // false for NaN too
}

bool TopBlock::factor(BlockGrid A, int mixed_from)
{
  const int n = A.size();
  m_n = n;
  m_mixed = false;
  m_single = false;
  m_lu.reset();
  m_steps = 0;
  if (mixed_from > 0 && n >= mixed_from) {
    // Not cleared first: every entry is written once, by the thread that owns its box row.
    m_lu.reset(new float[static_cast<std::size_t>(n) * n]);
    A.dense_single(m_lu.get(), &m_norm);
    m_piv.resize(n);
    if (lapack::getrf(n, m_lu.get(), n, m_piv.data()) == 0) {
      m_grid = std::move(A);
      m_mixed = true;
      // A trial solve: b = A·1.
      std::vector<double> b(n, 0.0), x(n), ones(n, 1.0);
      m_grid.gemv(1.0, ones.data(), b.data());
      if (refine(b.data(), x.data())) return true;
      A = std::move(m_grid); // the single-precision factor does not contract: LU in double
      m_grid = BlockGrid();
      m_mixed = false;
    }
    m_lu.reset();
  }
  m_A = A.dense();
  A = BlockGrid();
  return lu_regular(m_A, m_piv);
}

bool TopBlock::refine(const double *b, double *x) const
{
  const int n = m_n;
  const double eps = std::numeric_limits<double>::epsilon(), cte = m_norm * eps * std::sqrt(static_cast<double>(n));
  std::vector<double> r(b, b + n);
  std::vector<float> d(n);
  std::fill(x, x + n, 0.0);
  double last = HUGE_VAL;
  for (m_steps = 1; m_steps <= kMaxSteps; ++m_steps) {
    std::copy(r.begin(), r.end(), d.begin());
    lapack::getrs('N', n, 1, m_lu.get(), n, m_piv.data(), d.data(), n);
    for (int i = 0; i < n; ++i) x[i] += d[i];
    std::copy(b, b + n, r.begin());
    m_grid.gemv(-1.0, x, r.data());
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
  if (m_single) {
    solve_with_single_lu(n, m_lu.get(), m_piv.data(), x);
    return;
  }
  if (!m_mixed) {
    m_steps = 0;
    lapack::getrs('N', n, 1, m_A.data(), m_A.ld(), m_piv.data(), x, n);
    return;
  }
  std::vector<double> b(x, x + n);
  refine(b.data(), x); // should it stall (the trial solve did not), x is its better last iterate
}

} // namespace hssbem::h2f
