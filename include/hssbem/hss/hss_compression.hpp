/// \file hss_compression.hpp
/// Entries-only HSS compression of the BEM operator K = [H, G(, Gn)] (docs/hss.md), on the
/// skeletonizer of compress/ (K's column layout: compress/compression.hpp).
///
/// Construction, bottom-up over the cluster tree (one level at a time, clusters in parallel):
///  - the row skeleton of a cluster τ comes from an interpolative decomposition (ID) of its
///    candidate rows against (a) Kelvin point sources at proxy points on a sphere of radius
///    proxy_ratio·r_τ around τ, standing in for every source outside that sphere, and (b) the true
///    entries of the active columns of the other clusters whose quadrature can reach inside it;
///  - the column skeleton likewise, against the fields of τ's columns at the proxy points and
///    the true entries of the active rows inside the proxy sphere;
///  - the proxy spheres are large enough that everything outside sees each triangle of τ through
///    the same regular quadrature rule (near_ratio diameters; the 3-point far rule must be off),
///    so the discrete operator, not just the continuous one, is captured to the tolerance;
///  - candidates of an inner cluster are its children's skeletons (nested bases); skeleton
///    couplings and leaf blocks are true entries.
/// No N×N array is formed; memory is O(N·r).
///
/// The rigid-body terms of H (docs/discretisation.md, the rigid-body mode) are not integrated: the compressed H without them is
/// applied to the three translations, and the result, which must vanish for the full H, gives
/// them (D_i = −Σ_j H⁰(i, j)). A node collocated inside a triangle spreads its term over that
/// triangle's corner nodes; such rows and columns are kept in the skeletons wherever the
/// coupling crosses a cluster boundary, so the terms land in true-entry blocks.
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/core/option_table.hpp"
#include "hssbem/core/rank_comm.hpp"
#include "hssbem/hss/hss_matrix.hpp"

#include <vector>

namespace hssbem {

/// Parameters of the HSS compression; the defaults are the options' (-mat_hss_*, core/option_table.def).
struct HssOptions {
  double rel_tol = option_default::mat_hss_rel_tol;         ///< relative tolerance of each interpolative decomposition
  int max_rank = option_default::mat_hss_max_rank;          ///< cap on each skeleton; negative: none
  int leaf_size = option_default::mat_hss_leaf_size;        ///< dof nodes per leaf cluster (at most); below ~150 nodes the ranks are full at 1e-6
  double proxy_ratio = option_default::mat_hss_proxy_ratio; ///< proxy sphere radius / cluster radius (> 1)
  int proxy_points = option_default::mat_hss_proxy_points;  ///< points on each proxy sphere; 0: default_proxy_points(rel_tol)
  bool pressure_columns = false; ///< also compress Gn (slot 6), for pressure loads
};

/// Compress K = [H, G] (and Gn if asked) of `op` at the given accuracy, rigid-body terms
/// included (computed by fast matvecs). The operator's quadrature must have far_ratio = 0.
/// Throws std::invalid_argument for bad options.
HssMatrix compress_bem_operator_hss(const BemOperator &op, const HssOptions &options);

/// The same, distributed over the ranks of `comm` (hss_distributed.hpp): node_part[i] (dof node
/// i) in [0, P) with P = comm.size() or, on one rank, any P (the tree then has the partition's
/// top but one rank holds everything); empty: one part. The tree's top levels are the parts
/// (ClusterTree's partition constructor); rank p owns part p's clusters and the levels above the
/// parts belong to rank 0. Each rank skeletonizes its own clusters (skeleton indices cross ranks
/// level by level), forms its inner clusters' couplings and its leaves' diagonal blocks; rank 0
/// forms the top's couplings; the rigid-body terms come from one distributed product (a term
/// whose coupling lies above the parts goes to rank 0). Collective; a fault on one rank throws
/// on every rank (PeerFault on the others).
HssMatrix compress_bem_operator_hss(const BemOperator &op, const HssOptions &options, const std::vector<int> &node_part, const RankComm &comm);

} // namespace hssbem
