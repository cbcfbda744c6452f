// The H² factorization's dense top block (see top_block.hpp).
#include "top_block.hpp"

#include "frontier.hpp"

#include "hssbem/core/lapack.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

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

bool TopBlock::factor(DenseMatrix A, int mixed_from)
{
  const int n = A.m;
  m_mixed = false;
  m_lu.clear();
  m_steps = 0;
  if (mixed_from > 0 && n >= mixed_from) {
    m_lu.assign(A.a.begin(), A.a.end());
    m_piv.resize(n);
    if (lapack::getrf(n, m_lu.data(), n, m_piv.data()) == 0) {
      // ‖A‖_∞ for the stopping test, then a trial solve: b = A·1.
      std::vector<double> rows(n, 0.0);
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) rows[i] += std::abs(A(i, j));
      m_norm = inf_norm(rows.data(), n);
      m_A = std::move(A);
      m_mixed = true;
      std::vector<double> b(n), x(n), ones(n, 1.0);
      lapack::gemv('N', n, n, 1.0, m_A.data(), m_A.ld(), ones.data(), 0.0, b.data());
      if (refine(b.data(), x.data())) return true;
      A = std::move(m_A); // the single-precision factor does not contract: LU in double
      m_mixed = false;
    }
    m_lu.clear();
    m_lu.shrink_to_fit();
  }
  m_A = std::move(A);
  return lu_regular(m_A, m_piv);
}

bool TopBlock::refine(const double *b, double *x) const
{
  const int n = m_A.m;
  const double eps = std::numeric_limits<double>::epsilon(), cte = m_norm * eps * std::sqrt(static_cast<double>(n));
  std::vector<double> r(b, b + n);
  std::vector<float> d(n);
  std::fill(x, x + n, 0.0);
  double last = HUGE_VAL;
  for (m_steps = 1; m_steps <= kMaxSteps; ++m_steps) {
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
  const int n = m_A.m;
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
