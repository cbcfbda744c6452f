// The H² factorization's dense top block (see top_block.hpp).
#include "top_block.hpp"

#include "frontier.hpp"

#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/lapack.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

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
// The factorization and the solve.

bool TopBlock::factor(BlockGrid A, int mixed_from)
{
  const int n = A.size();
  m_n = n;
  m_mixed = false;
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
  if (!m_mixed) {
    m_steps = 0;
    lapack::getrs('N', n, 1, m_A.data(), m_A.ld(), m_piv.data(), x, n);
    return;
  }
  std::vector<double> b(x, x + n);
  refine(b.data(), x); // should it stall (the trial solve did not), x is its better last iterate
}

} // namespace hssbem::h2f
