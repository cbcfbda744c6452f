/// \file h2_matrix.hpp
/// An H² matrix: nested bases in interpolative form (nested_basis.hpp) on a strong-admissibility
/// block partition (block_partition.hpp).
///
/// Rows and columns follow one ClusterTree, indexed as in HssMatrix (cluster order, `row_block`
/// rows and `col_block` columns per point). With the partition's far blocks (a, b) and near
/// blocks (leaf a, leaf b),
///     K(a, b) ≈ U_a K(S_a, C_b) V_bᵀ   (far; U_a, V_b expanded through the nested bases),
///     K(a, b) = D_ab                    (near, true entries),
/// where S_a (C_b) is a's row (b's column) skeleton. Unlike HSS, a cluster's basis only has to
/// capture its interaction with what is far from it or from one of its ancestors, not with its
/// neighbours, so on a surface its rank stays bounded as the tree grows instead of growing with
/// the cluster's boundary. The product costs O(N·r) with bounded r.
#pragma once

#include "hssbem/compress/nested_basis.hpp"
#include "hssbem/core/cluster_tree.hpp"
#include "hssbem/core/dense_matrix.hpp"
#include "hssbem/h2/block_partition.hpp"

#include <cstddef>
#include <vector>

namespace hssbem {

/// One stored block of an H² matrix: far (skeleton × skeleton) or near (leaf × leaf), in double
/// precision (M) or, to halve the memory, in single precision (`single`, column-major with M's
/// dimensions, M.a then empty). Products always compute in double: a single block is widened
/// on the fly, so only its storage rounds (relative 6e-8 per entry).
struct H2Block {
  int col_cluster = -1;
  DenseMatrix M;
  std::vector<float> single;

  bool is_single() const { return !single.empty(); }
  /// Move the entries to single precision (no-op for an empty block).
  void demote();
  double entry(int i, int j) const { return is_single() ? single[i + static_cast<std::size_t>(j) * M.m] : M(i, j); }
  void add(int i, int j, double v)
  {
    if (is_single()) single[i + static_cast<std::size_t>(j) * M.m] += static_cast<float>(v);
    else M(i, j) += v;
  }
  std::size_t bytes() const { return M.bytes() + single.size() * sizeof(float); }
  /// The entries in double: M's data, or `single` widened into buf.
  const double *data(std::vector<double> &buf) const;
  /// Y += B X for nrhs columns (X: M.n × nrhs, Y: M.m × nrhs, column-major). A single block
  /// with one column is widened entry by entry inside the product, so it reads 4 bytes per
  /// entry instead of widening the block into buf first (the product is memory-bound); with
  /// more columns it goes through data(buf) and one GEMM.
  void multiply_add(const double *X, int ldx, double *Y, int ldy, int nrhs, std::vector<double> &buf) const;
};

struct H2LevelStats {
  int clusters = 0; ///< clusters with a basis
  int max_row_rank = 0, max_col_rank = 0;
  double mean_row_rank = 0, mean_col_rank = 0;
  long far_blocks = 0;
};

struct H2Stats {
  std::vector<H2LevelStats> levels; ///< index = tree level (0 = root)
  std::size_t memory_bytes = 0;     ///< all of the below
  std::size_t basis_bytes = 0, far_bytes = 0, near_bytes = 0;
  long far_blocks = 0, near_blocks = 0;
  long long entries_evaluated = 0;
  double time_tree = 0, time_near_field = 0, time_ids = 0, time_far = 0, time_near = 0, time_rigid = 0; ///< seconds (ID samples and IDs in thread-seconds)
  int proxy_points = 0;
  double eta = 0;
  int max_row_rank() const;
  int max_col_rank() const;
};

class H2Matrix {
public:
  H2Matrix(ClusterTree tree, int row_block, int col_block);

  const ClusterTree &tree() const { return m_tree; }
  int row_block() const { return m_row_block; }
  int col_block() const { return m_col_block; }
  int num_rows() const { return m_row_block * m_tree.num_points(); }
  int num_cols() const { return m_col_block * m_tree.num_points(); }

  /// Column scaling by slot, as HssMatrix::col_scale: the matrix held is K S.
  double col_scale(int slot) const { return m_col_scale[slot]; }
  void set_col_scales(std::vector<double> s) { m_col_scale = std::move(s); }

  BlockPartition &partition() { return m_partition; }
  const BlockPartition &partition() const { return m_partition; }
  NestedBasis &basis(int c) { return m_bases[c]; }
  const NestedBasis &basis(int c) const { return m_bases[c]; }
  std::vector<NestedBasis> &bases() { return m_bases; }
  /// Far blocks of row cluster a: K(S_a, C_b), one per b in partition().far[a], same order.
  std::vector<H2Block> &far_blocks(int a) { return m_far[a]; }
  const std::vector<H2Block> &far_blocks(int a) const { return m_far[a]; }
  /// Near blocks of leaf a: K(rows of a, columns of b), one per b in partition().near[a].
  std::vector<H2Block> &near_blocks(int a) { return m_near[a]; }
  const std::vector<H2Block> &near_blocks(int a) const { return m_near[a]; }
  /// The near block of leaves (a, b), or null when (a, b) is no near block.
  H2Block *near_block(int a, int b);
  const H2Block *near_block(int a, int b) const;

  /// Y = K X for nrhs columns in cluster order, as HssMatrix::apply. O(N·r) per column.
  void apply(const double *X, int ldx, double *Y, int ldy, int nrhs = 1) const;
  /// The far field of X at every row skeleton: out[a] (|S_a| × nrhs) is what the far blocks of a
  /// and of its ancestors contribute to K(S_a, :) X (no near blocks). X: col_block() rows per
  /// point, cluster order. The product's upward, far and downward passes without the leaves.
  std::vector<DenseMatrix> skeleton_far_field(const double *X, int ldx, int nrhs) const;
  /// The same for Kᵀ: out[b] (|C_b| × nrhs) is what the far blocks of b and of its ancestors
  /// contribute to (Kᵀ Y)(C_b, :), for Y with row_block() rows per point.
  std::vector<DenseMatrix> skeleton_far_field_transposed(const double *Y, int ldy, int nrhs) const;

  /// Recompute rank, block and memory figures.
  void update_stats();
  H2Stats &stats() { return m_stats; }
  const H2Stats &stats() const { return m_stats; }

private:
  ClusterTree m_tree;
  int m_row_block, m_col_block;
  std::vector<double> m_col_scale;
  BlockPartition m_partition;
  std::vector<NestedBasis> m_bases;
  std::vector<std::vector<H2Block>> m_far, m_near;
  H2Stats m_stats;
};

} // namespace hssbem
