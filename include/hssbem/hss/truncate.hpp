/// \file truncate.hpp
/// Recompression of an HSS matrix to a looser tolerance without evaluating any kernel entry,
/// e.g. a preconditioner at 1e-3 from an operator compressed at 1e-8.
///
/// The result approximates the matrix *as represented* by K (K_hss below), so its error against
/// the true operator is about K's own error plus the truncation's. Each cluster's new skeleton is
/// chosen from its new candidates (a leaf's rows, or the children's new skeletons) by an
/// interpolative decomposition (ID) of a compact form of its off-diagonal block row (column),
/// as in the compressor but with the represented block instead of proxy samples. Leaf D blocks
/// are copied; transfer matrices are the new IDs' interpolation matrices; couplings are the
/// entries of K_hss between the new skeletons, which are products of K's generators (and plain
/// sub-blocks of K's couplings where a new skeleton is a subset of the old one). The forced
/// skeleton entries (rigid-body terms, HssCluster::row_forced/col_forced) are kept, first, and,
/// as in the compressor, interpolate nothing; their rows and columns of the couplings are exact.
/// See truncate.cpp for the formulas.
#pragma once

#include "hssbem/core/rank_comm.hpp"
#include "hssbem/hss/hss_matrix.hpp"

namespace hssbem {

/// A copy of K recompressed to a looser tolerance without evaluating any kernel entry: each
/// cluster's new skeleton is chosen among its new candidates (forced entries kept) by an ID of
/// the compact form of its off-diagonal block row/column as represented by K; couplings are
/// K's represented entries at the new skeletons (sub-blocks of K's where the skeleton shrank),
/// transfer matrices are the new IDs, leaf D blocks are copied.
///
/// rel_tol as in HssOptions: per-ID relative tolerance (pivots above rel_tol·|R_11| are kept),
/// in (0, 1). max_rank < 0: no cap; otherwise each skeleton has at most max(max_rank, forced)
/// entries (forced entries are never dropped). Stats: update_stats() is called; K's timing,
/// entry and proxy figures are kept (they describe how the original was built).
/// Throws std::invalid_argument for bad arguments, std::logic_error if K's forced entries are
/// not nested (a parent's forced entry missing from its child's forced entries).
HssMatrix truncate_hss(const HssMatrix &K, double rel_tol, int max_rank = -1);

/// The same for K distributed over the ranks of comm (hss_distributed.hpp; collective): the
/// bottom-up steps run within each part and then above the parts (rank 0), the top-down step the
/// other way round; only the parts' roots' compact factors (k × k) and new skeletons cross ranks.
/// The result is distributed like K, and every rank knows its every new skeleton.
HssMatrix truncate_hss(const HssMatrix &K, double rel_tol, int max_rank, const RankComm &comm);

} // namespace hssbem
