/// \file interpolative.hpp
/// Interpolative decompositions (IDs) for HSS skeletonization, from column-pivoted QR.
///
/// Column ID of an m×n matrix A: k skeleton columns S and a k×(n−k) interpolation matrix T with
///
///     A(:, R) ≈ A(:, S) T,   so   A ≈ A(:, S) [I T] Pᵀ,
///
/// where R are the other (redundant) columns and P the permutation that lists S then R.
/// Row ID of A: the column ID of Aᵀ. It returns skeleton rows S, redundant rows R and the same
/// kind of k×(m−k) matrix T, and the relation reads transposed:
///
///     A(R, :) ≈ Tᵀ A(S, :),   so   A ≈ P [I T]ᵀ A(S, :).
///
/// In both, T(i, j) is the weight of skeleton index skeleton[i] in redundant index redundant[j].
///
/// Construction: a column-pivoted QR A P = Q R; S is the first k pivots and T = R11⁻¹ R12. From
/// min(m, n) = 128 up, the pivots come from sampled_pivoted_qr (sampled_qr.hpp, level-3 BLAS),
/// which stops at the first k where every remaining column norm is ≤ rel_tol·(largest column norm
/// of A). Below that, dgeqp3 (after an unpivoted QR when A is tall) gives non-increasing |R_ii|,
/// and k is the number of leading diagonal entries with |R_ii| > rel_tol·|R_11| — the same rule,
/// since |R_kk| is the largest remaining column norm. Either way k is then capped by max_rank, and
/// because the remaining columns are all below the threshold, the error satisfies
///
///     ‖A(:, R) − A(:, S) T‖_F = ‖R22‖_F ≤ sqrt(n−k) · max_j ‖R22(:, j)‖ ≤ rel_tol · sqrt(n−k) · ‖A‖_F
///
/// when the rank cap is inactive (the largest column norm of A is at most ‖A‖_F).
/// With IdOptions::gram (and rel_tol ≥ gram_min_tol) the pivots and R come from a pivoted
/// Cholesky factorization of AᵀA (dpstrf) instead: greedy pivots, the same stopping rule.
/// Entries of T are small in practice (bounded by 1 for a strong rank-revealing QR; plain
/// column pivoting carries no such guarantee but stays near it on kernel matrices).
/// Inputs must be free of NaN and Inf; this is not checked.
#pragma once

#include <vector>

namespace hssbem {

/// Accuracy controls of an ID.
struct IdOptions {
  double rel_tol = 1e-8; ///< keep pivots with |R_ii| > rel_tol·|R_11|; must be ≥ 0 (the ID's own, not an option's default)
  int max_rank = -1;     ///< cap on k; negative: no cap
  /// Take the pivots from a pivoted Cholesky factorization of AᵀA instead of a pivoted QR of A
  /// when rel_tol ≥ gram_min_tol: the same greedy pivots and stopping rule (the Cholesky factor is
  /// R), one symmetric rank-k update of A at full level-3 speed instead of Householder updates.
  /// The Gram matrix resolves residual norms down to about sqrt(machine epsilon)·‖A‖ ≈ 1.5e-8·‖A‖,
  /// hence the floor (seven times above that). False: always QR.
  bool gram = false;
};

/// Tolerances from which IdOptions::gram takes effect.
constexpr double gram_min_tol = 1e-7;

/// Result of a column ID (and, read transposed, of a row ID; see the file comment).
struct ColumnId {
  std::vector<int> skeleton;  ///< S: k indices, in pivot order (most significant first)
  std::vector<int> redundant; ///< R: the other indices, in pivot order; S ∪ R = 0..n−1
  std::vector<double> T;      ///< k × (n−k), column-major (leading dimension k); empty if k = 0 or k = n
  /// k, the number of skeleton indices.
  int rank() const { return static_cast<int>(skeleton.size()); }
};

/// Column ID of the m×n matrix A (column-major, leading dimension lda ≥ max(1, m)):
/// A(:, R) ≈ A(:, S) T. A is not modified. m = 0 or n = 0 give k = 0.
/// Throws std::invalid_argument on bad sizes or options, std::runtime_error if LAPACK fails.
ColumnId column_id(const double *A, int m, int n, int lda, const IdOptions &options = {});

/// Row ID of the m×n matrix A: the column ID of Aᵀ, so skeleton/redundant are row indices in
/// 0..m−1 and T is k×(m−k) with A(R, :) ≈ Tᵀ A(S, :). A is not modified.
ColumnId row_id(const double *A, int m, int n, int lda, const IdOptions &options = {});

/// Column ID of a matrix A from its Gram matrix AᵀA (n×n, upper triangle, leading dimension n;
/// overwritten) by the pivots of IdOptions::gram, for a caller that sums the Gram matrix of a
/// matrix it never forms (the H² factorization's skeletons).
ColumnId gram_column_id(double *G, int n, const IdOptions &options = {});

/// Reconstruct A ≈ A(:, S) [I T] Pᵀ from a column ID `id` of A into `out` (m×n, leading
/// dimension ldout ≥ max(1, m)): skeleton columns are copied, redundant ones interpolated.
void column_id_reconstruct(const ColumnId &id, const double *A, int m, int n, int lda, double *out, int ldout);

/// Reconstruct A ≈ P [I T]ᵀ A(S, :) from a row ID `id` of A into `out` (m×n, leading dimension
/// ldout ≥ max(1, m)): skeleton rows are copied, redundant ones interpolated.
void row_id_reconstruct(const ColumnId &id, const double *A, int m, int n, int lda, double *out, int ldout);

} // namespace hssbem
