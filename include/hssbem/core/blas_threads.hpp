/// \file blas_threads.hpp
/// Keep threaded BLAS out of loops that are already parallel over clusters.
///
/// The HSS and H² engines run a tree level's clusters on OpenMP threads; if each of them also called a
/// multithreaded BLAS, the cores would be oversubscribed (and OpenBLAS threads spin). While a
/// SerialBlas is alive, OpenBLAS runs on one thread; levels with fewer clusters than threads run
/// their clusters one after another with BLAS threaded instead. With another BLAS this does nothing.
#pragma once

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

private:
  int m_saved = 0;
};

/// C ← alpha op(A) op(B) + beta C (as lapack::gemm) split over the OpenMP threads by column blocks
/// of C, each block a serial BLAS call: for code that keeps OpenBLAS on one thread (SerialBlas)
/// so that its own OpenMP loops and BLAS never spin against each other. Serial when small.
void gemm_over_threads(char transa, char transb, int m, int n, int k, double alpha, const double *a, int lda, const double *b, int ldb, double beta, double *c, int ldc);
/// y ← op(A) x (A m×n, column-major) split over the OpenMP threads by row blocks (transa 'N').
void gemv_over_threads(int m, int n, const double *a, int lda, const double *x, double *y);

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
