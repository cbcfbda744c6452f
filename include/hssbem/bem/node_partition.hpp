/// \file node_partition.hpp
/// The dof nodes of a surface split into parts (one per MPI rank) by METIS: the graph has a
/// vertex per dof node (weight 3, its unknowns) and an edge between two nodes that share a
/// triangle or a mesh vertex (the double nodes of a sharp edge), so a part is a patch of the
/// surface and the cut is where its rows couple to other parts' columns through the near field.
#pragma once

#include "hssbem/bem/discretization.hpp"

#include <vector>

namespace hssbem {

struct NodePartitionStats {
  int parts = 0;
  long edge_cut = 0;        ///< graph edges between nodes of different parts
  long edges = 0;           ///< graph edges in all
  double imbalance = 1;     ///< largest part's nodes over the mean
  int min_nodes = 0, max_nodes = 0;
  int disconnected_parts = 0; ///< parts that are not one connected patch (a disjoint body, say)
};

/// part[i] in [0, nparts) for dof node i; every part non-empty. One part: all zeros, no METIS.
/// k-way METIS (contiguous parts where the surface is connected, recursive bisection when
/// k-way leaves a part empty), deterministic for a given mesh and nparts. Throws
/// std::invalid_argument when nparts < 1 or the surface has fewer than k_min_nodes_per_part
/// nodes per part (more ranks than the surface can feed).
std::vector<int> partition_nodes(const Discretization &disc, int nparts, NodePartitionStats *stats = nullptr);

/// The least number of dof nodes a part must have (partition_nodes refuses smaller parts).
constexpr int k_min_nodes_per_part = 4;

} // namespace hssbem
