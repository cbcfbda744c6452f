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

void SerialBlas::widen(bool on) const
{
  if (m_saved > 1) openblas_set_num_threads(on ? m_saved : 1);
}

int blas_loop_threads()
{
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
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
