// Products of single-precision matrices with double vectors, widening each entry as it is used
// (the H² product is memory-bound: it reads 4 bytes per stored number). Private to h2/.
#pragma once

#include <cstddef>

namespace hssbem::mixed {

/// y += A x for a column-major float matrix A (m × n, leading dimension m).
inline void gemv(int m, int n, const float *A, const double *x, double *y)
{
  int j = 0;
  for (; j + 4 <= n; j += 4) {
    const float *a0 = A + static_cast<std::size_t>(j) * m, *a1 = a0 + m, *a2 = a1 + m, *a3 = a2 + m;
    const double x0 = x[j], x1 = x[j + 1], x2 = x[j + 2], x3 = x[j + 3];
    for (int i = 0; i < m; ++i)
      y[i] += (static_cast<double>(a0[i]) * x0 + static_cast<double>(a1[i]) * x1) + (static_cast<double>(a2[i]) * x2 + static_cast<double>(a3[i]) * x3);
  }
  for (; j < n; ++j) {
    const float *a = A + static_cast<std::size_t>(j) * m;
    const double xj = x[j];
    for (int i = 0; i < m; ++i) y[i] += static_cast<double>(a[i]) * xj;
  }
}

/// y = Aᵀ x (beta 0) or y += Aᵀ x (accumulate) for a column-major float A (m × n): one dot
/// product per column.
inline void gemv_t(int m, int n, const float *A, const double *x, double *y, bool accumulate = false)
{
  for (int j = 0; j < n; ++j) {
    const float *a = A + static_cast<std::size_t>(j) * m;
    double s = 0;
    for (int i = 0; i < m; ++i) s += static_cast<double>(a[i]) * x[i];
    y[j] = accumulate ? y[j] + s : s;
  }
}

} // namespace hssbem::mixed
