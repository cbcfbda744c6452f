// BLAS thread control (OpenBLAS, when present; see blas_threads.hpp).
#include "hssbem/core/blas_threads.hpp"

#include "hssbem/core/lapack.hpp"

#include <algorithm>
#include <vector>

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
  int threads = 1;
#ifdef _OPENMP
  if (static_cast<double>(m) * n > 1e6) threads = omp_get_max_threads();
#endif
  if (threads == 1 || n < 2 * threads) {
    const SerialBlas serial;
    lapack::gemv('N', m, n, 1.0, a, lda, x, 0.0, y);
    return;
  }
  // Column blocks: each thread streams a contiguous slab of A into its own partial sum.
  const SerialBlas serial;
  std::vector<double> part(static_cast<std::size_t>(threads) * m, 0.0);
  const int width = (n + threads - 1) / threads;
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int t = 0; t < threads; ++t) {
    const int j0 = t * width, w = std::min(n, j0 + width) - j0;
    if (w > 0) lapack::gemv('N', m, w, 1.0, a + static_cast<std::size_t>(j0) * lda, lda, x + j0, 0.0, &part[static_cast<std::size_t>(t) * m]);
  }
  for (int i = 0; i < m; ++i) {
    double s = 0;
    for (int t = 0; t < threads; ++t) s += part[static_cast<std::size_t>(t) * m + i];
    y[i] = s;
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
