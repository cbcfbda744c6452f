/// \file far_sketch.hpp
/// Random sketches of the far-field couplings of an H² matrix, the weights that turn its nested
/// bases into features for the factorization's skeletons: for cluster a, Z_a Ω / √p with Z_a =
/// K(S_a, F_a) what a's row skeleton sees beyond its close neighbours and Ω Gaussian with p
/// columns (Z_a Z_aᵀ in expectation), likewise for the columns; one H² product pass each
/// (H2Matrix::skeleton_far_field and its transpose). They depend on K only: any
/// boundary-condition pattern reuses them (docs/h2-factorization.md).
#pragma once

#include "hssbem/core/dense_matrix.hpp"
#include "hssbem/h2/h2_distributed.hpp"
#include "hssbem/h2/h2_matrix.hpp"

#include <cstddef>
#include <vector>

namespace hssbem {

struct FarFieldSketch {
  int columns = 0;              ///< p
  std::vector<DenseMatrix> row; ///< per cluster: |row skeleton| × p (empty without a basis)
  std::vector<DenseMatrix> col; ///< per cluster: |column skeleton| × p
  std::size_t bytes() const;
};

/// Sketches with p columns; deterministic for a given seed. Works in chunks of columns, so the
/// random inputs never take more than a few tens of vectors at a time.
FarFieldSketch far_field_sketch(const H2Matrix &K, int p, unsigned seed = 20241);

/// The same on a distributed H² matrix (collective): the rows of the clusters this rank holds
/// (the others' are 0 × p), from the same random inputs (every rank draws all of them, in
/// cluster order), so they agree with the one-rank sketch of the same tree to rounding.
FarFieldSketch far_field_sketch(const H2DistributedProduct &K, int p, unsigned seed = 20241);

} // namespace hssbem
