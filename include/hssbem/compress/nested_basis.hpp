/// \file nested_basis.hpp
/// One cluster's nested row and column bases in interpolative form, shared by the HSS format
/// (hss/hss_matrix.hpp, weak admissibility) and the H² format (h2/h2_matrix.hpp, strong admissibility).
///
/// Rows and columns follow a ClusterTree: point k of cluster order carries `row_block` rows and
/// `col_block` columns, global row r = row_block·k + c and global column q = col_block·k + s.
/// The *candidates* of a cluster are all its rows (columns) for a leaf, and its children's
/// skeletons, left then right, for an inner cluster. The row skeleton S_τ ⊂ candidates and the
/// interpolation matrix U_τ (candidates × |S_τ|, the identity on S_τ) satisfy
///     K(candidates, far columns) ≈ U_τ K(S_τ, far columns),
/// and the columns likewise with V_τ, where "far" is the format's admissibility.
#pragma once

#include "hssbem/core/cluster_tree.hpp"
#include "hssbem/core/dense_matrix.hpp"

#include <numeric>
#include <vector>

namespace hssbem {

struct NestedBasis {
  std::vector<int> row_skel; ///< global rows, cluster order (empty for the root)
  std::vector<int> col_skel; ///< global columns, cluster order (empty for the root)
  DenseMatrix U;             ///< candidate rows × |row_skel|
  DenseMatrix V;             ///< candidate columns × |col_skel|
  int row_forced = 0;        ///< the first row_forced entries of row_skel must stay (rigid-body terms cross τ's boundary there)
  int col_forced = 0;        ///< likewise for col_skel
};

inline const NestedBasis &basis_ref(const NestedBasis &b) { return b; }
inline const NestedBasis &basis_ref(const NestedBasis *b) { return *b; }

/// Candidate rows (rows = true) or columns of cluster c: a leaf's `block` indices per point, or
/// the children's skeletons, left then right. T is NestedBasis, a type derived from it, or a pointer
/// to NestedBasis.
template <class T>
std::vector<int> basis_candidates(const ClusterTree &tree, const std::vector<T> &bases, int c, int block, bool rows)
{
  const Cluster &cl = tree.cluster(c);
  std::vector<int> out;
  if (cl.left < 0) {
    out.resize(static_cast<std::size_t>(block) * cl.size());
    std::iota(out.begin(), out.end(), block * cl.begin);
    return out;
  }
  const NestedBasis &a = basis_ref(bases[cl.left]), &b = basis_ref(bases[cl.right]);
  out = rows ? a.row_skel : a.col_skel;
  const std::vector<int> &right = rows ? b.row_skel : b.col_skel;
  out.insert(out.end(), right.begin(), right.end());
  return out;
}

} // namespace hssbem
