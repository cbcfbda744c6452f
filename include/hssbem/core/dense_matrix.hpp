/// \file dense_matrix.hpp
/// A small column-major dense matrix: the storage unit of the HSS generators.
#pragma once

#include <cstddef>
#include <vector>

namespace hssbem {

/// m×n, column-major, leading dimension m (0×0 when empty).
struct DenseMatrix {
  int m = 0, n = 0;
  std::vector<double> a;

  DenseMatrix() = default;
  DenseMatrix(int rows, int cols) : m(rows), n(cols), a(static_cast<std::size_t>(rows) * cols, 0.0) {}
  double &operator()(int i, int j) { return a[i + static_cast<std::size_t>(j) * m]; }
  double operator()(int i, int j) const { return a[i + static_cast<std::size_t>(j) * m]; }
  double *data() { return a.data(); }
  const double *data() const { return a.data(); }
  /// Leading dimension for BLAS (at least 1, as BLAS requires even for empty matrices).
  int ld() const { return m > 0 ? m : 1; }
  std::size_t bytes() const { return a.size() * sizeof(double); }
  bool empty() const { return a.empty(); }
};

} // namespace hssbem
