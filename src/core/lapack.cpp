// Thin wrappers over the Fortran BLAS/LAPACK routines declared in lapack.hpp.
#include "hssbem/core/lapack.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

namespace hssbem::lapack {

int geqp3(int m, int n, double *a, int lda, int *jpvt, double *tau)
{
  std::fill(jpvt, jpvt + n, 0);
  int info = 0, lwork = -1;
  double query = 0;
  dgeqp3_(&m, &n, a, &lda, jpvt, tau, &query, &lwork, &info);
  if (info != 0) return info;
  // The query may come back a hair below the needed integer; never go under dgeqp3's minimum.
  lwork = std::max({1, 3 * n + 1, static_cast<int>(query + 0.5)});
  std::vector<double> work(static_cast<std::size_t>(lwork));
  dgeqp3_(&m, &n, a, &lda, jpvt, tau, work.data(), &lwork, &info);
  return info;
}

void trsm(char side, char uplo, char transa, char diag, int m, int n, double alpha, const double *a, int lda, double *b, int ldb)
{
  dtrsm_(&side, &uplo, &transa, &diag, &m, &n, &alpha, a, &lda, b, &ldb);
}

void laswp(int ncols, double *a, int lda, int k, const int *piv)
{
  const int one = 1;
  if (k > 0 && ncols > 0) dlaswp_(&ncols, a, &lda, &one, &k, piv, &one);
}

void trsv(char uplo, char diag, int n, const double *a, int lda, double *x)
{
  const int one = 1;
  if (n > 0) dtrsv_(&uplo, "N", &diag, &n, a, &lda, x, &one);
}

void gemm(char transa, char transb, int m, int n, int k, double alpha, const double *a, int lda, const double *b, int ldb, double beta, double *c, int ldc)
{
  if (m == 0 || n == 0) return;
  if (k == 0) { // nothing to multiply; dgemm would also reject a zero leading dimension
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < m; ++i) c[i + static_cast<long>(j) * ldc] = beta == 0.0 ? 0.0 : beta * c[i + static_cast<long>(j) * ldc];
    return;
  }
  dgemm_(&transa, &transb, &m, &n, &k, &alpha, a, &lda, b, &ldb, &beta, c, &ldc);
}

int gesvd(int m, int n, double *a, int lda, double *s, double *u, int ldu, double *vt, int ldvt)
{
  int info = 0, lwork = -1;
  double query = 0;
  dgesvd_("S", "S", &m, &n, a, &lda, s, u, &ldu, vt, &ldvt, &query, &lwork, &info);
  if (info != 0) return info;
  lwork = std::max(1, static_cast<int>(query + 0.5));
  std::vector<double> work(static_cast<std::size_t>(lwork));
  dgesvd_("S", "S", &m, &n, a, &lda, s, u, &ldu, vt, &ldvt, work.data(), &lwork, &info);
  return info;
}

int gesdd(int m, int n, double *a, int lda, double *s, double *u, int ldu, double *vt, int ldvt)
{
  int info = 0, lwork = -1;
  double query = 0;
  std::vector<int> iwork(8 * static_cast<std::size_t>(std::max(1, std::min(m, n))));
  dgesdd_("S", &m, &n, a, &lda, s, u, &ldu, vt, &ldvt, &query, &lwork, iwork.data(), &info);
  if (info != 0) return info;
  lwork = std::max(1, static_cast<int>(query + 0.5));
  std::vector<double> work(static_cast<std::size_t>(lwork));
  dgesdd_("S", &m, &n, a, &lda, s, u, &ldu, vt, &ldvt, work.data(), &lwork, iwork.data(), &info);
  return info;
}

int syev(int n, double *a, double *w)
{
  int info = 0, lwork = -1;
  double query = 0;
  dsyev_("V", "U", &n, a, &n, w, &query, &lwork, &info);
  lwork = static_cast<int>(query);
  std::vector<double> work(std::max(1, lwork));
  dsyev_("V", "U", &n, a, &n, w, work.data(), &lwork, &info);
  return info;
}

int gesv(int n, int nrhs, double *a, double *b)
{
  int info = 0;
  std::vector<int> piv(n);
  dgesv_(&n, &nrhs, a, &n, piv.data(), b, &n, &info);
  return info;
}

namespace {
/// Run a LAPACK routine that takes a workspace: query its size, then call it for real.
template <class F> int with_workspace(F &&call)
{
  int info = 0, lwork = -1;
  double query = 0;
  call(&query, &lwork, &info);
  if (info != 0) return info;
  lwork = std::max(1, static_cast<int>(query + 0.5));
  std::vector<double> work(static_cast<std::size_t>(lwork));
  call(work.data(), &lwork, &info);
  return info;
}
} // namespace

int geqrf(int m, int n, double *a, int lda, double *tau)
{
  if (m == 0 || n == 0) return 0;
  return with_workspace([&](double *w, int *lw, int *info) { dgeqrf_(&m, &n, a, &lda, tau, w, lw, info); });
}

int gelqf(int m, int n, double *a, int lda, double *tau)
{
  if (m == 0 || n == 0) return 0;
  return with_workspace([&](double *w, int *lw, int *info) { dgelqf_(&m, &n, a, &lda, tau, w, lw, info); });
}

int ormqr(char side, char trans, int m, int n, int k, const double *a, int lda, const double *tau, double *c, int ldc)
{
  if (m == 0 || n == 0 || k == 0) return 0;
  return with_workspace([&](double *w, int *lw, int *info) { dormqr_(&side, &trans, &m, &n, &k, a, &lda, tau, c, &ldc, w, lw, info); });
}

int geqrt3(int m, int n, double *a, int lda, double *t, int ldt)
{
  if (m == 0 || n == 0) return 0;
  int info = 0;
  dgeqrt3_(&m, &n, a, &lda, t, &ldt, &info);
  return info;
}

void larfb_left(char trans, int m, int n, int k, const double *v, int ldv, const double *t, int ldt, double *c, int ldc)
{
  if (m == 0 || n == 0 || k == 0) return;
  const char side = 'L', direct = 'F', storev = 'C';
  std::vector<double> work(static_cast<std::size_t>(n) * static_cast<std::size_t>(k));
  dlarfb_(&side, &trans, &direct, &storev, &m, &n, &k, v, &ldv, t, &ldt, c, &ldc, work.data(), &n);
}

int ormlq(char side, char trans, int m, int n, int k, const double *a, int lda, const double *tau, double *c, int ldc)
{
  if (m == 0 || n == 0 || k == 0) return 0;
  return with_workspace([&](double *w, int *lw, int *info) { dormlq_(&side, &trans, &m, &n, &k, a, &lda, tau, c, &ldc, w, lw, info); });
}

int getrf(int n, double *a, int lda, int *ipiv)
{
  if (n == 0) return 0;
  int info = 0;
  dgetrf_(&n, &n, a, &lda, ipiv, &info);
  return info;
}

int getrs(char trans, int n, int nrhs, const double *a, int lda, const int *ipiv, double *b, int ldb)
{
  if (n == 0 || nrhs == 0) return 0;
  int info = 0;
  dgetrs_(&trans, &n, &nrhs, a, &lda, ipiv, b, &ldb, &info);
  return info;
}

void gemv(char trans, int m, int n, double alpha, const double *a, int lda, const double *x, double beta, double *y)
{
  const int one = 1;
  const int ny = trans == 'N' ? m : n;
  if (ny == 0) return;
  if (m == 0 || n == 0) {
    for (int i = 0; i < ny; ++i) y[i] = beta == 0.0 ? 0.0 : beta * y[i];
    return;
  }
  dgemv_(&trans, &m, &n, &alpha, a, &lda, x, &one, &beta, y, &one);
}

void syrk_t(int n, int m, double alpha, const double *a, int lda, double beta, double *c, int ldc)
{
  if (n == 0) return;
  dsyrk_("U", "T", &n, &m, &alpha, a, &lda, &beta, c, &ldc);
}

int pstrf_upper(int n, double *a, int lda, int *piv, double tol)
{
  if (n == 0) return 0;
  std::vector<double> work(2 * static_cast<std::size_t>(n));
  int rank = 0, info = 0;
  dpstrf_("U", &n, a, &lda, piv, &rank, &tol, work.data(), &info);
  if (info < 0) throw std::runtime_error("dpstrf: argument " + std::to_string(-info) + " is invalid");
  return rank;
}

void gemm(char transa, char transb, int m, int n, int k, float alpha, const float *a, int lda, const float *b, int ldb, float beta, float *c, int ldc)
{
  if (m == 0 || n == 0) return;
  if (k == 0) {
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < m; ++i) c[i + static_cast<long>(j) * ldc] = beta == 0.0f ? 0.0f : beta * c[i + static_cast<long>(j) * ldc];
    return;
  }
  sgemm_(&transa, &transb, &m, &n, &k, &alpha, a, &lda, b, &ldb, &beta, c, &ldc);
}

void gemv(char trans, int m, int n, float alpha, const float *a, int lda, const float *x, float beta, float *y)
{
  const int one = 1, ny = trans == 'N' ? m : n;
  if (ny == 0) return;
  if (m == 0 || n == 0) {
    for (int i = 0; i < ny; ++i) y[i] = beta == 0.0f ? 0.0f : beta * y[i];
    return;
  }
  sgemv_(&trans, &m, &n, &alpha, a, &lda, x, &one, &beta, y, &one);
}

int getrf(int n, float *a, int lda, int *ipiv)
{
  if (n == 0) return 0;
  int info = 0;
  sgetrf_(&n, &n, a, &lda, ipiv, &info);
  return info;
}

int getrs(char trans, int n, int nrhs, const float *a, int lda, const int *ipiv, float *b, int ldb)
{
  if (n == 0 || nrhs == 0) return 0;
  int info = 0;
  sgetrs_(&trans, &n, &nrhs, a, &lda, ipiv, b, &ldb, &info);
  return info;
}

namespace {
/// getri for either precision: query the workspace, then invert.
template <class T, class F> int getri_with(int n, T *a, int lda, const int *ipiv, F &&routine)
{
  if (n == 0) return 0;
  int info = 0, lwork = -1;
  T query = 0;
  routine(&n, a, &lda, ipiv, &query, &lwork, &info);
  if (info != 0) return info;
  lwork = std::max(n, static_cast<int>(query + 0.5f));
  std::vector<T> work(static_cast<std::size_t>(lwork));
  routine(&n, a, &lda, ipiv, work.data(), &lwork, &info);
  return info;
}
} // namespace

int getri(int n, double *a, int lda, const int *ipiv) { return getri_with(n, a, lda, ipiv, dgetri_); }
int getri(int n, float *a, int lda, const int *ipiv) { return getri_with(n, a, lda, ipiv, sgetri_); }

} // namespace hssbem::lapack
