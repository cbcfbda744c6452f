// One cluster's steps of the HSS product, shared by the whole matrix's (HssMatrix::apply) and the
// distributed one's (HssDistributedProduct::apply). Private to hss/.
#pragma once

#include "hssbem/hss/hss_matrix.hpp"

#include <vector>

namespace hssbem::hss_steps {

/// Upward: xh[c] = V_cᵀ (c's candidate part of X): for a leaf from X, whose first row is the
/// first column of point `first` (cluster order); for an inner cluster from its children's xh.
void upward(const HssMatrix &K, int c, const double *X, int ldx, int first, int nrhs, std::vector<DenseMatrix> &xh);

/// Downward for an inner cluster c: the children's potentials yh gain the sibling couplings
/// (B12 x̂_b, B21 x̂_a) and, below the root, U_c yh[c]. A child's yh is made (zero) here unless
/// it has its shape already (a potential received from another rank is kept).
void downward_inner(const HssMatrix &K, int c, int nrhs, const std::vector<DenseMatrix> &xh, std::vector<DenseMatrix> &yh);

/// Downward for a leaf c: Y(rows of c) = D_c X(columns of c) + U_c yh[c] (no U for the root), Y's
/// first row and X's first column being point `first`'s.
void leaf(const HssMatrix &K, int c, const double *X, int ldx, double *Y, int ldy, int first, int nrhs, const std::vector<DenseMatrix> &yh);

} // namespace hssbem::hss_steps
