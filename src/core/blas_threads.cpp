// BLAS thread control (OpenBLAS, when present; see blas_threads.hpp).
#include "hssbem/core/blas_threads.hpp"

#include "hssbem/core/lapack.hpp"

#include <algorithm>

#ifdef _OPENMP
#include <omp.h>
#endif

extern "C" {
// Weak: resolved only when the linked BLAS is OpenBLAS.
int openblas_get_num_threads(void) __attribute__((weak));
void openblas_set_num_threads(int) __attribute__((weak));
}

namespace hssbem {

SerialBlas::SerialBlas(bool active)
{
  if (!active || !openblas_get_num_threads || !openblas_set_num_threads) return;
  m_saved = openblas_get_num_threads();
  if (m_saved > 1) openblas_set_num_threads(1);
  else m_saved = 0;
}

SerialBlas::~SerialBlas()
{
  if (m_saved > 1) openblas_set_num_threads(m_saved);
}

void gemm_over_threads(char transa, char transb, int m, int n, int k, double alpha, const double *a, int lda, const double *b, int ldb, double beta, double *c, int ldc)
{
  const bool par = static_cast<double>(m) * n * k > 2e6 && n >= 16;
  const SerialBlas serial(par);
  const int nb = par ? std::min(n / 8, 64) : 1, width = (n + nb - 1) / nb;
#pragma omp parallel for schedule(dynamic, 1) if (par)
  for (int j = 0; j < nb; ++j) {
    const int j0 = j * width, w = std::min(n, j0 + width) - j0;
    if (w <= 0) continue;
    const double *bj = transb == 'N' ? b + static_cast<std::size_t>(j0) * ldb : b + j0;
    lapack::gemm(transa, transb, m, w, k, alpha, a, lda, bj, ldb, beta, c + static_cast<std::size_t>(j0) * ldc, ldc);
  }
}

void gemv_over_threads(int m, int n, const double *a, int lda, const double *x, double *y)
{
  if (m == 0) return;
  const bool par = static_cast<double>(m) * n > 1e6;
  const SerialBlas serial(par);
  const int block = 256, nb = (m + block - 1) / block;
#pragma omp parallel for schedule(static) if (par)
  for (int b = 0; b < nb; ++b) {
    const int r0 = b * block, rows = std::min(m, r0 + block) - r0;
    lapack::gemv('N', rows, n, 1.0, a + r0, lda, x, 0.0, y + r0);
  }
}

bool parallel_over_clusters(std::size_t clusters)
{
#ifdef _OPENMP
  return omp_get_max_threads() > 1 && clusters >= static_cast<std::size_t>(omp_get_max_threads());
#else
  return false;
#endif
}

} // namespace hssbem
