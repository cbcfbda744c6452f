/// \file dense_ops.hpp
/// Block operations on DenseMatrix shared by the HSS algorithms (ULV factorization, truncation):
/// sub-blocks, concatenation, products. Each returns a new matrix unless it says otherwise.
#pragma once

#include "hssbem/core/dense_matrix.hpp"

#include <vector>

namespace hssbem::dense {

/// Rows [r0, r0 + nr) and columns [c0, c0 + nc) of M.
DenseMatrix sub(const DenseMatrix &M, int r0, int nr, int c0, int nc);
/// Rows [r0, r0 + nr) of M (all columns).
inline DenseMatrix row_block(const DenseMatrix &M, int r0, int nr) { return sub(M, r0, nr, 0, M.n); }
/// The rows of M listed in idx, in that order.
DenseMatrix rows_at(const DenseMatrix &M, const std::vector<int> &idx);
/// Write S into M with its top-left corner at (r0, c0), in place.
void put(DenseMatrix &M, int r0, int c0, const DenseMatrix &S);
/// [A, B] (same number of rows).
DenseMatrix hcat(const DenseMatrix &A, const DenseMatrix &B);
/// [A; B] (same number of columns).
DenseMatrix vcat(const DenseMatrix &A, const DenseMatrix &B);
/// op(A) op(B), with op = 'N' or 'T'.
DenseMatrix product(const DenseMatrix &A, char ta, const DenseMatrix &B, char tb);
/// LU with partial pivoting of A in place (getrf); false when A is singular to working precision
/// (a zero pivot, or the smallest |U_ii| at most 1e-14 of the largest |A_ij|).
bool lu_regular(DenseMatrix &A, std::vector<int> &piv);
/// max |M(i, j)| (0 for an empty matrix).
double max_abs(const DenseMatrix &M);
/// The largest Euclidean norm of one of M's columns (0 for an empty matrix).
double largest_col_norm(const DenseMatrix &M);
/// The largest Euclidean norm of one of M's rows (0 for an empty matrix).
double largest_row_norm(const DenseMatrix &M);

} // namespace hssbem::dense
