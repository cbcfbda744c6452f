/// \file h2_compression.hpp
/// Entries-only H² compression of the BEM operator K = [H, G(, Gn)] (strong admissibility).
///
/// The same proxy-sphere skeletonization as the HSS compression (compress/skeletonizer.hpp), on the
/// block partition of block_partition.hpp: a cluster is compressed only against the clusters
/// that are far from it or from one of its ancestors, never against its close neighbours, whose
/// interactions are resolved further down the tree and, at the leaves, by near blocks of true
/// entries. Far blocks are true entries between skeletons. A far block may hold entries computed
/// with the near-singular quadrature rule; the IDs sample such entries explicitly (the proxy
/// spheres only stand in for columns that every row sees through the regular rule), so they are
/// captured like any other. The cluster radius of the partition bounds both the collocation
/// points and the support triangles, so every rigid-body term lands in a near block; the
/// rigid-body terms are computed as in the HSS compression, by applying the compressed H without
/// them to the three translations (docs/discretisation.md, the rigid-body mode).
/// No N×N array is formed. Work and memory are O(N·r) with ranks that stay bounded on a surface
/// (measured in benchmarks/), against ranks that grow as the square root of a cluster's size
/// with weak admissibility.
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/core/option_table.hpp"
#include "hssbem/core/rank_comm.hpp"
#include "hssbem/h2/h2_matrix.hpp"

namespace hssbem {

/// Parameters of the H² compression; the defaults are the options' (-mat_h2_*, core/option_table.def).
struct H2Options {
  double rel_tol = option_default::mat_h2_rel_tol;         ///< relative tolerance of each interpolative decomposition
  int max_rank = option_default::mat_h2_max_rank;          ///< cap on each skeleton; negative: none
  int leaf_size = option_default::mat_h2_leaf_size;        ///< dof nodes per leaf cluster (at most)
  double eta = option_default::mat_h2_eta;                 ///< far when |c_a − c_b| > (1 + eta)(R_a + R_b); 0: the clusters' spheres are disjoint
  double proxy_ratio = option_default::mat_h2_proxy_ratio; ///< proxy sphere radius / cluster radius (> 1)
  int proxy_points = option_default::mat_h2_proxy_points;  ///< points on each proxy sphere; 0: default_proxy_points(rel_tol)
  bool pressure_columns = false; ///< also compress Gn (slot 6), for pressure loads
  /// Store far and near blocks in single precision (half the memory; each entry rounds to a
  /// relative 6e-8, harmless for rel_tol ≥ 1e-6). Bases stay in double.
  bool single_precision = option_default::mat_h2_single_precision;
  /// With single_precision: store each far block in low-rank form (an ID at rel_tol / 5, the
  /// skeleton side's entries and the interpolation weights in single precision, no unit rows;
  /// H2Block) when that takes less memory. With either low-rank form the skeletons' IDs run at
  /// 0.7 rel_tol: the product's error comes mostly from them (h2_compression.cpp).
  bool low_rank_far = true;
  /// With single_precision: likewise for the near blocks between different leaves, at rel_tol / 10
  /// of the larger of the block's own largest row norm and that of its row leaf's diagonal block
  /// (those that receive rigid-body terms stay dense).
  bool low_rank_near = true;
};

/// Compress K = [H, G] (and Gn if asked) of `op`, rigid-body terms included. The operator's
/// quadrature must have far_ratio = 0. Throws std::invalid_argument for bad options.
H2Matrix compress_bem_operator_h2(const BemOperator &op, const H2Options &options);

/// The same, distributed over the ranks of `comm` (h2_distributed.hpp): node_part[i] (dof node i)
/// in [0, P) with P = comm.size() or, on one rank, any P (the tree then has the partition's top
/// but one rank holds everything); empty: one part. The tree's top levels are the parts
/// (ClusterTree's partition constructor); rank p owns part p's clusters and the levels above the
/// parts belong to rank 0. Each rank skeletonizes its own clusters (skeleton indices cross ranks
/// level by level), forms its clusters' far blocks and its leaves' near blocks; the rigid-body
/// terms come from one distributed product. Collective; a fault on one rank throws on every rank
/// (PeerFault on the others).
H2Matrix compress_bem_operator_h2(const BemOperator &op, const H2Options &options, const std::vector<int> &node_part, const RankComm &comm);

} // namespace hssbem
