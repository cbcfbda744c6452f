/// \file hss_matrix.hpp
/// A hierarchically semi-separable (HSS) matrix with nested bases in interpolative form.
///
/// Rows and columns follow one ClusterTree: point k of cluster order carries `row_block` rows
/// (3 displacement components) and `col_block` columns (for K = [H, G(, Gn)] of the BEM: 6 or 7).
/// Global row r = row_block·k + c and global column q = col_block·k + s, both in cluster order.
///
/// Every cluster τ except the root has
///  - row skeleton S_τ (global rows) and U_τ: its candidate rows ≈ U_τ · (those rows at S_τ),
///    away from τ's diagonal block. Candidate rows are all rows of a leaf, and the children's
///    skeletons (left then right) for an inner cluster, so U of an inner cluster is the usual
///    HSS transfer matrix. U is an interpolation matrix: the identity on the skeleton rows;
///  - column skeleton and V_τ the same way for columns: K(outside, candidates) ≈
///    K(outside, skeleton) · V_τᵀ.
/// A leaf stores its diagonal block D_τ = K(rows, columns); an inner cluster with children a, b
/// stores the true entries B_ab = K(S_a, C_b) and B_ba = K(S_b, C_a) between the children's row
/// skeletons S and column skeletons C. Then, with nested bases,
///     K(a, b) ≈ U_a B_ab V_bᵀ,
/// and the whole matrix is applied in O(N·r) operations (apply()).
#pragma once

#include "hssbem/compress/nested_basis.hpp"
#include "hssbem/core/cluster_tree.hpp"
#include "hssbem/core/dense_matrix.hpp"
#include "hssbem/core/tree_ownership.hpp"

#include <cstddef>
#include <vector>

namespace hssbem {

/// One cluster's generators (see the file comment): its nested bases, and
struct HssCluster : NestedBasis {
  DenseMatrix D;             ///< leaf: its rows × its columns
  DenseMatrix B12, B21;      ///< inner: K(row_skel(left), col_skel(right)), K(row_skel(right), col_skel(left))
};

/// Rank and memory figures per tree level, and work counters.
struct HssLevelStats {
  int clusters = 0;
  int max_row_rank = 0, max_col_rank = 0;
  double mean_row_rank = 0, mean_col_rank = 0;
};

struct HssStats {
  std::vector<HssLevelStats> levels; ///< index = tree level (0 = root)
  std::size_t memory_bytes = 0;      ///< generators, skeleton lists and diagonal blocks (held on this rank)
  std::size_t top_bytes = 0;         ///< of which the generators of the clusters above the parts (a distributed matrix's top, rank 0)
  int top_clusters = 0;              ///< clusters above the parts (0 without a partition)
  long long entries_evaluated = 0;   ///< operator entries computed (near field, proxies, couplings, leaves)
  double time_tree = 0, time_near_field = 0, time_ids = 0, time_couplings = 0, time_leaves = 0, time_rigid = 0; ///< seconds
  int proxy_points = 0;
  int max_row_rank() const;
  int max_col_rank() const;
};

class HssMatrix {
public:
  HssMatrix(ClusterTree tree, int row_block, int col_block);

  const ClusterTree &tree() const { return m_tree; }
  int row_block() const { return m_row_block; }
  int col_block() const { return m_col_block; }
  int num_rows() const { return m_row_block * m_tree.num_points(); }
  int num_cols() const { return m_col_block * m_tree.num_points(); }
  HssCluster &cluster(int i) { return m_clusters[i]; }
  const HssCluster &cluster(int i) const { return m_clusters[i]; }
  /// Candidate rows of cluster c (global, cluster order): a leaf's rows, or the children's skeletons.
  std::vector<int> candidate_rows(int c) const;
  std::vector<int> candidate_cols(int c) const;

  /// Column scaling by slot: the matrix held is K S with S = diag(col_scale(q % col_block)), so
  /// that H and the (much smaller, ~1/μ) G columns are compressed to the same relative accuracy.
  /// apply() computes K S X; callers divide the G entries of X by the scale (see HssBemSystem).
  double col_scale(int slot) const { return m_col_scale[slot]; }
  void set_col_scales(std::vector<double> s) { m_col_scale = std::move(s); }

  /// Y = K X for nrhs columns, both in cluster order, column-major: X is num_cols() × nrhs with
  /// leading dimension ldx, Y num_rows() × nrhs with leading dimension ldy. O(N·r) per column.
  void apply(const double *X, int ldx, double *Y, int ldy, int nrhs = 1) const;

  /// Distributed over ranks (hss_distributed.hpp): owner(c) is the rank holding cluster c's
  /// generators (U, V, and D or B12, B21); every rank knows every skeleton. Without owners (the
  /// default) this rank holds everything.
  void set_owners(std::vector<int> owner, int rank) { m_owners.set(std::move(owner), rank, m_tree.num_clusters()); }
  int owner(int c) const { return m_owners.owner(c); }
  bool holds(int c) const { return m_owners.holds(c); }
  bool holds_all() const { return m_owners.holds_all(); }
  int rank() const { return m_owners.rank(); }
  const ClusterOwners &owners() const { return m_owners; }
  void set_owners(const ClusterOwners &owners) { m_owners = owners; }

  /// Recompute rank and memory figures (levels, memory_bytes, top_bytes) from the generators:
  /// ranks of every cluster (skeletons are known everywhere), memory of the clusters held here.
  void update_stats();
  HssStats &stats() { return m_stats; }
  const HssStats &stats() const { return m_stats; }

private:
  ClusterTree m_tree;
  int m_row_block, m_col_block;
  std::vector<double> m_col_scale;
  std::vector<HssCluster> m_clusters;
  ClusterOwners m_owners;
  HssStats m_stats;
};

} // namespace hssbem
