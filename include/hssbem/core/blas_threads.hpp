/// \file blas_threads.hpp
/// Keep threaded BLAS out of loops that are already parallel over clusters.
///
/// The HSS and H² engines run a tree level's clusters on OpenMP threads; if each of them also called a
/// multithreaded BLAS, the cores would be oversubscribed (and OpenBLAS threads spin). While a
/// SerialBlas is alive, OpenBLAS runs on one thread; levels with fewer clusters than threads run
/// their clusters one after another with BLAS threaded instead. With another BLAS this does nothing.
#pragma once

#include "hssbem/core/lapack.hpp"

#include <algorithm>
#include <cstddef>
#include <exception>
#include <vector>

namespace hssbem {

class SerialBlas {
public:
  explicit SerialBlas(bool active = true);
  ~SerialBlas();
  SerialBlas(const SerialBlas &) = delete;
  SerialBlas &operator=(const SerialBlas &) = delete;
  /// While a caller knows that no other thread calls BLAS (the others wait), let BLAS run on the
  /// threads it had before (true), or on one again (false).
  void widen(bool on) const;

private:
  int m_saved = 0;
};

/// C ← alpha op(A) op(B) + beta C (as lapack::gemm; T = double or float) split over the OpenMP
/// threads, each block a serial BLAS call: for code that keeps OpenBLAS on one thread
/// (SerialBlas) so that its own OpenMP loops and BLAS never spin against each other. Serial when
/// small. A wide C is split by column blocks; a tall, narrow one (n < m) by row blocks, so that
/// op(A) is streamed once and not once per column block: for C = A B with A 3 015², B 3 015×100
/// in single precision, 33 ms in 12 column blocks against 10 ms in row blocks (2 cores).
template <class T>
void gemm_over_threads(char transa, char transb, int m, int n, int k, T alpha, const T *a, int lda, const T *b, int ldb, T beta, T *c, int ldc)
{
  const bool par = static_cast<double>(m) * n * k > 2e6 && std::max(m, n) >= 16;
  const SerialBlas serial(par);
  if (par && n < m) { // row blocks of C: rows of op(A)
    const int nb = std::max(1, std::min(m / 64, 16)), height = (m + nb - 1) / nb;
#pragma omp parallel for schedule(dynamic, 1)
    for (int i = 0; i < nb; ++i) {
      const int i0 = i * height, h = std::min(m, i0 + height) - i0;
      if (h <= 0) continue;
      const T *ai = transa == 'N' ? a + i0 : a + static_cast<std::size_t>(i0) * lda;
      lapack::gemm(transa, transb, h, n, k, alpha, ai, lda, b, ldb, beta, c + i0, ldc);
    }
    return;
  }
  const int nb = par ? std::max(1, std::min(n / 8, 64)) : 1, width = (n + nb - 1) / nb;
#pragma omp parallel for schedule(dynamic, 1) if (par)
  for (int j = 0; j < nb; ++j) {
    const int j0 = j * width, w = std::min(n, j0 + width) - j0;
    if (w <= 0) continue;
    const T *bj = transb == 'N' ? b + static_cast<std::size_t>(j0) * ldb : b + j0;
    lapack::gemm(transa, transb, m, w, k, alpha, a, lda, bj, ldb, beta, c + static_cast<std::size_t>(j0) * ldc, ldc);
  }
}

/// Threads available to the *_over_threads products (1 without OpenMP).
int blas_loop_threads();

/// y ← A x (A m×n, column-major; T = double or float) split over the OpenMP threads by column
/// blocks, each thread streaming a contiguous slab of A into its own partial sum.
template <class T>
void gemv_over_threads(int m, int n, const T *a, int lda, const T *x, T *y)
{
  if (m == 0) return;
  const int threads = static_cast<double>(m) * n > 1e6 ? blas_loop_threads() : 1;
  const SerialBlas serial;
  if (threads == 1 || n < 2 * threads) {
    lapack::gemv('N', m, n, T(1), a, lda, x, T(0), y);
    return;
  }
  std::vector<T> part(static_cast<std::size_t>(threads) * m, T(0));
  const int width = (n + threads - 1) / threads;
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int t = 0; t < threads; ++t) {
    const int j0 = t * width, w = std::min(n, j0 + width) - j0;
    if (w > 0) lapack::gemv('N', m, w, T(1), a + static_cast<std::size_t>(j0) * lda, lda, x + j0, T(0), &part[static_cast<std::size_t>(t) * m]);
  }
  for (int i = 0; i < m; ++i) {
    T s = 0;
    for (int t = 0; t < threads; ++t) s += part[static_cast<std::size_t>(t) * m + i];
    y[i] = s;
  }
}

/// Whether a level with `clusters` independent clusters should run them on parallel threads.
bool parallel_over_clusters(std::size_t clusters);

/// fn(c) for every c in `clusters` (independent of each other): on parallel threads with serial
/// BLAS when there are enough of them, else one after another with threaded BLAS. An exception
/// thrown by fn stops nothing else; the first one is rethrown after the loop.
template <class Fn>
void for_each_cluster(const std::vector<int> &clusters, const Fn &fn)
{
  const bool par = parallel_over_clusters(clusters.size());
  SerialBlas serial(par);
  std::exception_ptr error;
#pragma omp parallel for schedule(dynamic, 1) if (par)
  for (std::size_t t = 0; t < clusters.size(); ++t) {
    try {
      fn(clusters[t]);
    } catch (...) {
#pragma omp critical(hssbem_for_each_cluster_error)
      if (!error) error = std::current_exception();
    }
  }
  if (error) std::rethrow_exception(error);
}

} // namespace hssbem
