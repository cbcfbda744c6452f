/// \file blas_threads.hpp
/// Keep threaded BLAS out of loops that are already parallel over clusters.
///
/// The HSS engine runs a tree level's clusters on OpenMP threads; if each of them also called a
/// multithreaded BLAS, the cores would be oversubscribed (and OpenBLAS threads spin). While a
/// SerialBlas is alive, OpenBLAS runs on one thread; levels with fewer clusters than threads run
/// their clusters one after another with BLAS threaded instead. With another BLAS this does nothing.
#pragma once

#include <cstddef>

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

/// Whether a level with `clusters` independent clusters should run them on parallel threads.
bool parallel_over_clusters(std::size_t clusters);

} // namespace hssbem
