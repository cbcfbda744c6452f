// Thin wrappers over the Fortran BLAS/LAPACK routines declared in lapack.hpp.
#include "hssbem/core/lapack.hpp"

#include <algorithm>
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

void gemm(char transa, char transb, int m, int n, int k, double alpha, const double *a, int lda, const double *b, int ldb, double beta, double *c, int ldc)
{
  dgemm_(&transa, &transb, &m, &n, &k, &alpha, a, &lda, b, &ldb, &beta, c, &ldc);
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

} // namespace hssbem::lapack
