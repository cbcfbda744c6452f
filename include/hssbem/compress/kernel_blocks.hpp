/// \file kernel_blocks.hpp
/// Entries of K = [H, G(, Gn)] addressed by global row and column indices in cluster order, the
/// index space of the compressed formats (see nested_basis.hpp), times the column scale of their
/// slot. The rigid-body terms of H are not included.
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/core/cluster_tree.hpp"

#include <vector>

namespace hssbem {

/// Column scales per slot (`w` = 6 or 7) that give the G (and Gn) part of K the Frobenius norm of
/// the H part, measured on a sample of rows and columns spread over the mesh: G ~ 1/(μ r) and
/// H ~ 1/r² differ by orders of magnitude, and one relative tolerance should resolve both.
std::vector<double> kernel_column_scales(const BemOperator &op, int w);

class KernelBlocks {
public:
  /// `col_block` columns per node: 6 (H, G) or 7 (H, G, Gn).
  KernelBlocks(const BemOperator &op, const ClusterTree &tree, int col_block, std::vector<double> col_scale);

  /// out(r, q) = K(rows[r], cols[q]), stored at out[r·rs + q·cs]. Thread-safe with one
  /// workspace per thread.
  void block(const std::vector<int> &rows, const std::vector<int> &cols, double *out, long rs, long cs, BemOperator::Workspace &ws) const;
  /// out(3p + c, q) = component c at point X[p] of the field of column cols[q], stored at
  /// out[(3p + c)·rs + q·cs].
  void at_points(const std::vector<Vec3> &X, const std::vector<int> &cols, double *out, long rs, long cs, BemOperator::Workspace &ws) const;

private:
  void select_columns(const std::vector<int> &cols, EntrySelection &sel) const;
  void apply_scales(std::size_t nrows, const std::vector<int> &cols, double *out, long rs, long cs) const;

  const BemOperator &m_op;
  const ClusterTree &m_tree;
  int m_w;
  std::vector<double> m_scale;
};

} // namespace hssbem
