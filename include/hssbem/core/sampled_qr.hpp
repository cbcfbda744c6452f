/// \file sampled_qr.hpp
/// Rank-revealing QR with column pivoting chosen by random sampling, stopped at a tolerance.
///
/// LAPACK's dgeqp3 spends half of its flops in matrix–vector products, because it updates the
/// column norms one pivot at a time; on the ID matrices of the HSS compression (thousands of
/// rows and columns) it runs at about a quarter of the machine's DGEMM rate. The blocked scheme
/// of Martinsson, Quintana-Ortí, Heavner and van de Geijn ("Householder QR factorization with
/// randomization for column pivoting", SIAM J. Sci. Comput. 39, 2017) picks a block of b pivots
/// at a time from a small sketch Y = Ω A (b + p rows), by dgeqp3 on Y, then factorizes those b
/// columns with Householder reflectors and updates the rest with level-3 BLAS. The sketch of the
/// remaining columns is downdated, not recomputed.
///
/// The randomly chosen pivots are not exactly the largest remaining columns, so the stopping rule
/// does not trust |R_kk|: after each block it computes the exact norms of the remaining columns
/// and stops at the smallest k whose remainder R22 has every column norm ≤ rel_tol·max_j ‖A(:, j)‖.
/// Hence
///
///     A P = Q [R11 R12; 0 R22],   max_j ‖R22(:, j)‖ ≤ rel_tol · max_j ‖A(:, j)‖   (unless the rank cap stops it),
///
/// which is the bound dgeqp3 gives when it keeps the pivots with |R_ii| > rel_tol·|R_11|.
#pragma once

#include <cstdint>
#include <vector>

namespace hssbem {

/// Result of sampled_pivoted_qr.
struct SampledQr {
  int rank = 0;          ///< k
  std::vector<int> perm; ///< n column indices: perm[i] is the original column now at position i
};

/// Factorize the m×n matrix a (column-major, leading dimension lda ≥ max(1, m)) in place until
/// the remaining columns' norms are all ≤ rel_tol × A's largest column norm, or k reaches max_rank (negative: no cap) or
/// min(m, n). On return a's columns are permuted by perm, a(0:k, 0:k) is R11 (upper triangular),
/// a(0:k, k:n) is R12; the rest of a is overwritten. `block` is b (pivots per step), `seed` makes
/// the sampling reproducible. Throws std::runtime_error if LAPACK fails.
SampledQr sampled_pivoted_qr(double *a, int m, int n, int lda, double rel_tol, int max_rank, int block = 64,
                             std::uint64_t seed = 20261121);

} // namespace hssbem
