/// \file h2_distributed.hpp
/// The H² matrix distributed over ranks, and its product.
///
/// Layout: the cluster tree's top levels are a partition of the dof nodes (one part per rank,
/// METIS in bem/node_partition.hpp); rank p owns the clusters of part p's subtree (their bases,
/// far blocks and, for leaves, near blocks) and the rows and columns of part p's points, which
/// are consecutive in cluster order; rank 0 also owns the few clusters above the parts. Every
/// rank knows the tree, the block partition and every skeleton (index lists), not the bases or
/// blocks of other ranks.
///
/// The product y = K x on rank p, from x's values at p's points:
///  1. upward pass over p's part subtree: the column moments x̂_c = V_cᵀ x(c);
///  2. exchange: the moments of p's clusters that are far partners of other ranks' clusters, and
///     the values of p's leaves that are near other ranks' leaves (the partition's boundary);
///  3. rank 0: upward over the top clusters (from the parts' moments); then the top moments that
///     other ranks' far blocks need;
///  4. far blocks of p's clusters: ŷ_a = Σ_b K(S_a, C_b) x̂_b;
///  5. downward: rank 0 through the top clusters, sending each part its share; then each rank
///     through its subtree, and its leaves: y(a) = U_a ŷ_a + Σ_b D_ab x(b).
/// Only skeleton-level data (moments, potentials) and boundary leaves cross ranks; with a
/// power-of-two number of parts and strong admissibility the top has no far blocks, so steps 3's
/// second half and 5's exchange carry nothing.
#pragma once

#include "hssbem/core/cluster_exchange.hpp"
#include "hssbem/core/rank_comm.hpp"
#include "hssbem/h2/h2_matrix.hpp"

#include <optional>
#include <vector>

namespace hssbem {

class H2DistributedProduct {
public:
  /// Plans the exchanges (collective). Every collective member function is failure-atomic
  /// (rank_comm.hpp).
  H2DistributedProduct(const H2Matrix &K, const RankComm &comm);

  const H2Matrix &matrix() const { return m_K; }
  const RankComm &comm() const { return m_comm; }
  /// This rank's points: positions [first_point(), first_point() + num_points()) of cluster order.
  int first_point() const { return m_first; }
  int num_points() const { return m_count; }

  /// Y = this rank's rows of K X (collective): X holds col_block() values per point of this rank
  /// (cluster order, leading dimension ldx), Y receives row_block() per point (ldy).
  void apply(const double *X, int ldx, double *Y, int ldy, int nrhs = 1) const;

  /// H2Matrix::skeleton_far_field on this rank's clusters (collective): out[a], for each cluster
  /// a this rank holds, is what the far blocks of a and of its ancestors contribute to
  /// K(S_a, :) X (the product's potentials at a's row skeleton before the leaves); the other
  /// entries are empty. X as in apply().
  std::vector<DenseMatrix> skeleton_far_field(const double *X, int ldx, int nrhs) const;
  /// The same for Kᵀ (H2Matrix::skeleton_far_field_transposed): out[b] (|C_b| × nrhs) for the
  /// clusters b this rank holds; Y holds row_block() values per point of this rank. Row moments
  /// Uᵀ Y go up (the parts' roots' to rank 0), each far block's transposed product goes to its
  /// column cluster's owner, and V carries the sums down.
  std::vector<DenseMatrix> skeleton_far_field_transposed(const double *Y, int ldy, int nrhs) const;

  /// Per product with one column: values and messages this rank sends.
  long long values_sent() const { return m_values_sent; }
  long long messages_sent() const { return m_messages_sent; }

private:
  /// Steps 1–5 of the product up to the downward pass through the parts: potentials at the row
  /// skeletons in *yh (far blocks, the top's share sent down); with xv, the boundary leaves'
  /// values that the near blocks read too.
  void far_potentials(const double *X, int ldx, int nrhs, std::vector<DenseMatrix> &yh, std::vector<DenseMatrix> *xv) const;

  const H2Matrix &m_K;
  const RankComm &m_comm;
  int m_first = 0, m_count = 0;
  /// This rank's clusters per pass, a list per level in pass order: upward below and above the
  /// parts, downward above and below.
  std::vector<std::vector<int>> m_up, m_top_up, m_top_down, m_down;
  std::vector<int> m_held, m_leaves, m_boundary; ///< this rank's clusters, leaves, and leaves other ranks read
  ClusterExchange m_low, m_vals, m_top, m_pot;         ///< moments; leaf values; top moments; potentials down
  /// The transposed pass: row moments of the parts' roots to rank 0; far blocks' transposed
  /// products to their column clusters' owners (potentials down reuse m_pot's plan).
  ClusterExchange m_row_up, m_far_t;
  std::vector<char> m_above;                           ///< per cluster: above the parts
  long long m_values_sent = 0, m_messages_sent = 0;
};

} // namespace hssbem

namespace hssbem {

/// The whole matrix on rank `root` (every cluster's bases and blocks, owners cleared), from the
/// parts of a distributed one (collective; the other ranks return an empty optional). For
/// algorithms that still run on one rank (the H² factorization).
std::optional<H2Matrix> gather_h2_matrix(const H2Matrix &K, const RankComm &comm, int root = 0);

} // namespace hssbem
