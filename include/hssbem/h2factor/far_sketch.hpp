/// \file far_sketch.hpp
/// Random sketches of the far-field couplings of an H² matrix, the weights that turn its nested
/// bases into features for the factorization's skeletons (h2_factorization.hpp).
///
/// For cluster a with row skeleton S_a, the H² matrix holds every entry that a's rows see beyond
/// its close neighbours as K(rows_a, F_a) = Û_a Z_a, Z_a = K(S_a, F_a) (through a's far blocks
/// and its ancestors'). A row ID of Û_a Z_a restricted to some rows needs Z_a Z_aᵀ, not Z_a; the
/// sketch Z_a Ω / √p, Ω Gaussian with p columns, has that Gram in expectation. Likewise for the
/// columns: K(F_b, cols_b) = Z'_b Ŵ_bᵀ with the sketch (Ω'ᵀ Z'_b)ᵀ / √p. Both come from one H²
/// product pass each with p random vectors (H2Matrix::skeleton_far_field and its transpose), and
/// depend on K only: any boundary-condition pattern reuses them. The row sketch covers all of K's
/// H and G columns (slots 0–5), a superset of any pattern's.
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
