// The elimination steps of the H² factorization as the solve replays them (see elimination_step.hpp):
// on one right-hand side by matrix-vector products, on a block by matrix products, so that the
// factors stream once per block (the solve is memory-bound).
#include "elimination_step.hpp"

#include "hssbem/core/lapack.hpp"

namespace hssbem::h2f {

namespace {

/// y += alpha A x for a column-major float matrix A (m × n).
void gemv_single(int m, int n, double alpha, const float *A, const double *x, double *y)
{
  for (int j = 0; j < n; ++j) {
    const float *a = A + static_cast<std::size_t>(j) * m;
    const double xj = alpha * x[j];
    for (int i = 0; i < m; ++i) y[i] += static_cast<double>(a[i]) * xj;
  }
}

/// Rows idx of X (leading dimension ld, nrhs columns) into the packed |idx| × nrhs block B, or back.
void gather(const std::vector<int> &idx, const double *X, std::size_t ld, int nrhs, std::vector<double> &B)
{
  const std::size_t m = idx.size();
  B.resize(m * nrhs);
  for (int c = 0; c < nrhs; ++c)
    for (std::size_t i = 0; i < m; ++i) B[i + c * m] = X[idx[i] + c * ld];
}

void scatter(const std::vector<int> &idx, const std::vector<double> &B, int nrhs, double *X, std::size_t ld)
{
  const std::size_t m = idx.size();
  for (int c = 0; c < nrhs; ++c)
    for (std::size_t i = 0; i < m; ++i) X[idx[i] + c * ld] = B[i + c * m];
}

/// C (m × nrhs, packed) += alpha op(A) B (B packed, inner dimension k): one column by GEMV, which
/// reads A once where a GEMM of one column would pack it first.
void multiply(char ta, int m, int nrhs, int k, double alpha, const double *A, int lda, const double *B, double *C)
{
  if (nrhs == 1) lapack::gemv(ta, ta == 'N' ? m : k, ta == 'N' ? k : m, alpha, A, lda, B, 1.0, C);
  else lapack::gemm(ta, 'N', m, nrhs, k, alpha, A, lda, B, k, 1.0, C, m);
}

/// C (m × nrhs) −= P B for a panel P (m × k) in double, or in single precision in Ps: one column
/// straight from the floats, a block through P widened into buf.
void panel_update(const DenseMatrix &P, const std::vector<float> &Ps, int m, int nrhs, int k, const double *B, double *C, std::vector<double> &buf)
{
  if (Ps.empty()) return multiply('N', m, nrhs, k, -1.0, P.data(), m, B, C);
  if (nrhs == 1) return gemv_single(m, k, -1.0, Ps.data(), B, C);
  buf.assign(Ps.begin(), Ps.end());
  lapack::gemm('N', 'N', m, nrhs, k, -1.0, buf.data(), m, B, k, 1.0, C, m);
}

/// B (n × nrhs, packed) ← op(T)⁻¹ B for a triangle T of an LU (uplo, diag as in trsv).
void triangular(char uplo, char diag, int n, int nrhs, const DenseMatrix &LU, double *B)
{
  if (nrhs == 1) lapack::trsv(uplo, diag, n, LU.data(), LU.ld(), B);
  else lapack::trsm('L', uplo, 'N', diag, n, nrhs, 1.0, LU.data(), LU.ld(), B, n);
}

} // namespace

std::size_t Step::bytes() const
{
  const std::size_t panels = Lps.empty() ? Lp.bytes() + Up.bytes() : (Lps.size() + Ups.size()) * sizeof(float);
  return panels + T.bytes() + LU.bytes() + D.bytes() + (box.size() + dpiv.size() + S.size() + R.size() + I.size() + piv.size()) * sizeof(int);
}

void Step::demote()
{
  Lps.assign(Lp.a.begin(), Lp.a.end());
  Ups.assign(Up.a.begin(), Up.a.end());
  Lp.a.clear();
  Lp.a.shrink_to_fit();
  Up.a.clear();
  Up.a.shrink_to_fit();
}

void Step::forward(double *X, std::size_t ld, int nrhs, Work &w) const
{
  const int k = static_cast<int>(S.size()), r = static_cast<int>(R.size()), nI = static_cast<int>(I.size());
  if (r == 0) return;
  gather(R, X, ld, nrhs, w.r);
  if (k > 0) {
    gather(S, X, ld, nrhs, w.s);
    multiply('T', r, nrhs, k, -1.0, T.data(), T.ld(), w.s.data(), w.r.data());
  }
  lapack::laswp(nrhs, w.r.data(), r, r, piv.data());
  triangular('L', 'U', r, nrhs, LU, w.r.data());
  if (nI > 0) {
    gather(I, X, ld, nrhs, w.i);
    panel_update(Lp, Lps, nI, nrhs, r, w.r.data(), w.i.data(), w.panel);
    scatter(I, w.i, nrhs, X, ld);
  }
  scatter(R, w.r, nrhs, X, ld);
}

void Step::backward(double *X, std::size_t ld, int nrhs, Work &w) const
{
  const int k = static_cast<int>(S.size()), r = static_cast<int>(R.size()), nI = static_cast<int>(I.size());
  if (r > 0) {
    gather(R, X, ld, nrhs, w.r);
    if (nI > 0) {
      gather(I, X, ld, nrhs, w.i);
      panel_update(Up, Ups, r, nrhs, nI, w.i.data(), w.r.data(), w.panel);
    }
    triangular('U', 'N', r, nrhs, LU, w.r.data());
    scatter(R, w.r, nrhs, X, ld);
    if (k > 0) {
      gather(S, X, ld, nrhs, w.s);
      multiply('N', k, nrhs, r, -1.0, T.data(), T.ld(), w.r.data(), w.s.data());
      scatter(S, w.s, nrhs, X, ld);
    }
  }
  // The unknowns were A_XX x: x = A_XX⁻¹ (that).
  const int m = static_cast<int>(box.size());
  if (m == 0) return;
  gather(box, X, ld, nrhs, w.s);
  lapack::getrs('N', m, nrhs, D.data(), D.ld(), dpiv.data(), w.s.data(), m);
  scatter(box, w.s, nrhs, X, ld);
}

} // namespace hssbem::h2f
