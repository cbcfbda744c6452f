/// \file tree_ownership.hpp
/// Which rank holds which cluster of a cluster tree whose top levels are a partition (one part
/// per rank, ClusterTree's partition constructor): shared by every format distributed over ranks
/// (the H² matrix, h2/h2_distributed.hpp; the HSS matrix, hss/hss_distributed.hpp).
///
/// Rank p owns the clusters of part p's subtree; the few clusters above the parts belong to
/// rank 0. On one rank every cluster is rank 0's.
#pragma once

#include "hssbem/core/cluster_tree.hpp"

#include <vector>

namespace hssbem {

/// Per cluster: its part, or -1 for a cluster above the parts.
std::vector<int> cluster_parts(const ClusterTree &tree);

/// Per cluster, its owner: the rank of its part, rank 0 above the parts. On one rank every
/// cluster is rank 0's. Throws std::invalid_argument when ranks > 1 differs from the tree's parts.
std::vector<int> cluster_owners(const ClusterTree &tree, int ranks);

/// The clusters of a list grouped by level: deepest level first (up = true) or top first; empty
/// levels are left out.
std::vector<std::vector<int>> clusters_by_level(const ClusterTree &tree, const std::vector<int> &clusters, bool up);

/// The owners of a distributed matrix's clusters, as this rank sees them.
class ClusterOwners {
public:
  /// owner: one rank per cluster (cluster_owners()), or empty for "this rank holds everything".
  /// Throws std::invalid_argument for a list of the wrong length.
  void set(std::vector<int> owner, int rank, int clusters);
  int owner(int c) const { return m_owner.empty() ? m_rank : m_owner[c]; }
  bool holds(int c) const { return m_owner.empty() || m_owner[c] == m_rank; }
  bool holds_all() const;
  int rank() const { return m_rank; }

private:
  std::vector<int> m_owner;
  int m_rank = 0;
};

} // namespace hssbem
