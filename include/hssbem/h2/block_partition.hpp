/// \file block_partition.hpp
/// The strong-admissibility block partition of K over a cluster tree (the H² format's block
/// structure): a dual traversal from (root, root) sorts every pair of clusters it meets into
///  - far: admissible, |centre_a − centre_b| > (1 + eta)(R_a + R_b); the block K(a, b) is
///    compressed through a's row basis and b's column basis;
///  - near: both leaves and not admissible; the block is stored with true entries;
///  - close: not admissible; the pair is split, both clusters when both have children, else the
///    one that has (so leaves of different depths meet correctly).
/// Every (row, column) pair lies in exactly one far or near block. R is a radius per cluster;
/// when it bounds both its collocation points and its support triangles, every rigid-body term
/// (which couples a collocation point to the corners of a triangle holding it) lies in a near
/// block. The traversal is symmetric: b is far (near, close)
/// for a exactly when a is for b.
#pragma once

#include "hssbem/core/cluster_tree.hpp"

#include <vector>

namespace hssbem {

struct BlockPartition {
  std::vector<std::vector<int>> far;   ///< far[a]: clusters b with (a, b) a far block, ascending
  std::vector<std::vector<int>> near;  ///< near[a] (a leaf): leaves b with (a, b) a near block, ascending
  std::vector<std::vector<int>> close; ///< close[a]: clusters b with (a, b) met and not admissible (a itself included), ascending
  /// has_far[c]: c or one of its ancestors has a far block. Only such clusters need bases: the
  /// others' rows and columns are reached through near blocks and their descendants' far blocks.
  std::vector<char> has_far;

  bool is_far(int a, int b) const;
  bool is_close(int a, int b) const;
};

/// Partition for cluster radii `radius` (one per cluster) and eta ≥ 0. Throws
/// std::invalid_argument for eta < 0 or a radius vector of the wrong size.
BlockPartition strong_block_partition(const ClusterTree &tree, const std::vector<double> &radius, double eta);

} // namespace hssbem
