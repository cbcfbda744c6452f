/// \file hss_distributed.hpp
/// The HSS matrix distributed over ranks, and its product.
///
/// Layout (as the distributed H² matrix's, core/tree_ownership.hpp): the cluster tree's top
/// levels are a partition of the dof nodes (one part per rank, METIS in bem/node_partition.hpp);
/// rank p owns part p's subtree (its clusters' transfer matrices, its inner clusters' sibling
/// couplings, its leaves' diagonal blocks) and the rows and columns of part p's points, which are
/// consecutive in cluster order; rank 0 also owns the clusters above the parts (the top log₂ P
/// levels: transfer matrices and couplings between skeletons only). Every rank knows the tree and
/// every skeleton (index lists), not the generators of other ranks.
///
/// The product y = K x on rank p, from x's values at p's points:
///  1. upward over p's subtree: x̂_c = V_cᵀ x(c), up to the part's root;
///  2. the parts' roots' x̂ to rank 0;
///  3. rank 0: upward over the top clusters, then downward from the root: sibling couplings
///     ŷ_a += B_ab x̂_b and transfers ŷ_children += U_c ŷ_c, down to the parts' roots, whose ŷ go
///     back to their ranks;
///  4. downward over p's subtree, and its leaves: y(c) = D_c x(c) + U_c ŷ_c.
/// Only the parts' roots' skeleton coefficients cross ranks (one message up and one down per
/// rank and product).
#pragma once

#include "hssbem/core/cluster_exchange.hpp"
#include "hssbem/core/rank_comm.hpp"
#include "hssbem/hss/hss_matrix.hpp"

#include <vector>

namespace hssbem {

/// This rank's clusters of a distributed HSS matrix, in the order of the passes over them (also
/// those of the factorization and the truncation): per level, deepest first (up) or top first
/// (down), within the part (below) and above the parts (top, rank 0's).
struct HssPasses {
  std::vector<std::vector<int>> up, top_up, top_down, down;
  std::vector<char> above; ///< per cluster: above the parts
  int first = 0, count = 0; ///< this rank's points: positions [first, first + count) of cluster order
  /// Collective-free: from K's owners. Throws std::logic_error when K's rank is not comm's.
  HssPasses(const HssMatrix &K, const RankComm &comm);
};

class HssDistributedProduct {
public:
  /// Plans the exchanges (collective). K and comm must outlive this object.
  HssDistributedProduct(const HssMatrix &K, const RankComm &comm);

  const HssMatrix &matrix() const { return m_K; }
  /// This rank's points: positions [first_point(), first_point() + num_points()) of cluster order.
  int first_point() const { return m_passes.first; }
  int num_points() const { return m_passes.count; }

  /// Y = this rank's rows of K X (collective): X holds col_block() values per point of this rank
  /// (cluster order, leading dimension ldx), Y receives row_block() per point (ldy).
  void apply(const double *X, int ldx, double *Y, int ldy, int nrhs = 1) const;

  /// Per product with one column: values and messages this rank sends.
  long long values_sent() const { return m_values_sent; }
  long long messages_sent() const { return m_messages_sent; }

private:
  const HssMatrix &m_K;
  const RankComm &m_comm;
  HssPasses m_passes;
  ClusterExchange m_moments, m_potentials; ///< the parts' roots' x̂ up, their ŷ down
  long long m_values_sent = 0, m_messages_sent = 0;
};

} // namespace hssbem
