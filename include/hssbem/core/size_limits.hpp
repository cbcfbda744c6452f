/// \file size_limits.hpp
/// What each operator path can take: the index width and the memory of the machine. A problem
/// beyond them is refused before anything is allocated, naming its size and a path that can
/// take it (the PETSc face checks in HssbemCreateSystem(); -bem_mat_type auto picks within them).
/// The model and the peaks it was fitted to: docs/limits.md.
#pragma once

#include "hssbem/core/operator_type.hpp"
#include "hssbem/core/option_table.hpp"

#include <string>

namespace hssbem {

/// The machine as the size check sees it.
struct MachineLimits {
  double    node_memory_bytes = 0; ///< memory of one node (the smallest, over the ranks' nodes)
  int       ranks = 1;             ///< ranks in the run
  int       ranks_per_node = 1;    ///< ranks that share a node (the most on any node)
  long long index_max = 2147483647; ///< largest index of the linear-algebra library (PetscInt)
};

/// What else than its type and size decides an operator's memory (with its default solver); the
/// defaults are the options' (core/option_table.def).
struct SizeOptions {
  bool   single_precision = option_default::mat_h2_single_precision; ///< H²: single-precision blocks
  double h2_rel_tol = option_default::mat_h2_rel_tol;                ///< H²: the compression's tolerance
  bool   h2_factored = option_default::pc_type == "h2";              ///< H²: PC h2 factors it (GMRES + PC h2, or a direct solve)
  double pc_h2_rel_tol = option_default::pc_h2_rel_tol;              ///< PC h2: the factorization's tolerance (-pc_h2_rel_tol)
  long long pc_h2_top_size = option_default::pc_h2_top_size;         ///< PC h2: unknowns left for the dense top (-pc_h2_top_size)
  long long pc_h2_mixed_top = option_default::pc_h2_single_top_from; ///< PC h2: top size from which its LU is in single precision (-pc_h2_single_top_from; ≤ 0: never)
  bool   pc_h2_spread_top = option_default::pc_h2_spread_top;        ///< PC h2: a single-precision top spread over the ranks (-pc_h2_spread_top)
  int    krylov_vectors = option_default::ksp_gmres_restart + 1;     ///< H²: vectors of the Krylov method (GMRES(restart): restart + 1; preonly: 0)
  double hss_rel_tol = option_default::mat_hss_rel_tol;              ///< HSS: the compression's tolerance (its ULV factors follow it)
};

/// Bytes one rank alone needs at its peak for `unknowns` unknowns with the operator `type` and
/// its default solver, the driver included (node_bytes() with one rank on one node).
double estimated_bytes(OperatorType type, long long unknowns, const SizeOptions &o);

/// Bytes the most loaded node needs at its peak: each of its ranks' process and driver data
/// (mesh, operator, vectors: every rank holds them whole), and its ranks' shares of the
/// operator and solver, which the ranks split — plus, on rank 0's node, HSS's top above the
/// parts and PC h2's dense top (unless spread). Fitted above the measured peaks (dense + LU,
/// H² + GMRES + PC h2, HSS + ULV, at three sizes each on 1 and 2 ranks) by at most 25 %:
/// docs/limits.md.
double node_bytes(OperatorType type, long long unknowns, const SizeOptions &o, const MachineLimits &m);

/// The H² factorization keeps its elimination panels in single precision when asked (1), never
/// (0), or by default (-1) at a tolerance of k_h2_single_panel_tol or looser, where single
/// precision's rounding stays below the tolerance. The factorization decides by this, and so
/// does the size model.
inline constexpr double k_h2_single_panel_tol = 1e-5;
bool h2_single_panels(double rel_tol, int single_panels);

/// How PC h2 factors its dense top: a double LU on rank 0 (Double); from single_top_from
/// unknowns on, with double panels a single-precision LU refined in double beside the block
/// (Mixed), with single panels a single-precision LU alone (Single), spread over the ranks when
/// there are several and spread_top (Spread). The one rule the factorization (h2factor/
/// factor_top.cpp) follows and the size model counts by.
enum class H2TopKind { Double, Mixed, Single, Spread };
H2TopKind h2_top_kind(long long top_unknowns, bool single_panels, long long single_top_from, bool spread_top, int ranks);

/// The one model of PC h2's dense top's memory: the bytes a top of `kind` and `top_unknowns`
/// unknowns adds to the peak of the node that holds it (rank 0's; a spread top's share per rank
/// times the node's ranks), fitted to the measured peaks (docs/limits.md). Per entry: a double
/// top 16 bytes (its LU, 8, and as much again: the top's rows arriving beside the block, which
/// the measured peaks hold), a mixed one 12 on one rank (the double block and the single LU) and
/// 16 on several, a single one 4 (its LU), a spread one 4 divided over the ranks; and 32 bytes
/// per unknown (pivots, offsets, the trial's and the solves' vectors).
double h2_top_bytes(H2TopKind kind, long long top_unknowns, const MachineLimits &m);

/// PC h2's dense top for the size check, from the options: about k_h2_top_fill (0.8) times
/// o.pc_h2_top_size unknowns (the factorization stops at the first level at or below it), of
/// the kind h2_top_kind() gives; 0 without PC h2.
double h2_top_bytes(long long unknowns, const SizeOptions &o, const MachineLimits &m);

/// Why `type` cannot take `unknowns` unknowns on this machine: its entries or a rank's block
/// exceed the index width, or it needs more memory than the nodes have (node_bytes()); with the
/// size, the need and the options that can take it (another operator, single precision,
/// Jacobi instead of PC h2, a looser H² tolerance). Empty when it fits.
std::string size_refusal(OperatorType type, long long unknowns, const SizeOptions &o, const MachineLimits &m);

} // namespace hssbem
