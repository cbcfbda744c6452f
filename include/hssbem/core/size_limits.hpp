/// \file size_limits.hpp
/// What each operator path can take: the index width and the memory of the machine. A problem
/// beyond them is refused before anything is allocated, naming its size and a path that can
/// take it (the PETSc face checks in HssbemCreateSystem(); -bem_mat_type auto picks within them).
/// The model and the peaks it was fitted to: docs/limits.md.
#pragma once

#include "hssbem/core/operator_type.hpp"

#include <string>

namespace hssbem {

/// The machine as the size check sees it.
struct MachineLimits {
  double    node_memory_bytes = 0; ///< memory of one node (the smallest, over the ranks' nodes)
  int       ranks = 1;             ///< ranks in the run
  int       ranks_per_node = 1;    ///< ranks that share a node (the most on any node)
  long long index_max = 2147483647; ///< largest index of the linear-algebra library (PetscInt)
};

/// What else than its type and size decides an operator's memory (with its default solver).
struct SizeOptions {
  bool   single_precision = false; ///< H²: single-precision blocks
  double h2_rel_tol = 1e-5;        ///< H²: the compression's tolerance
  bool   h2_factored = false;      ///< H²: PC h2 factors it (GMRES + PC h2, or a direct solve)
  double pc_h2_rel_tol = 2e-3;     ///< PC h2: the factorization's tolerance (-pc_h2_rel_tol)
  long long pc_h2_top_size = 2000; ///< PC h2: unknowns left for the dense top (-pc_h2_top_size)
  long long pc_h2_mixed_top = 4000; ///< PC h2: top size from which its LU is in single precision (-pc_h2_mixed_top; ≤ 0: never)
  bool   pc_h2_spread_top = true;  ///< PC h2: a single-precision top spread over the ranks (-pc_h2_spread_top)
  int    krylov_vectors = 101;     ///< H²: vectors of the Krylov method (GMRES(100): 101; preonly: 0)
  double hss_rel_tol = 1e-8;       ///< HSS: the compression's tolerance (its ULV factors follow it)
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

/// PC h2's dense top: bytes on the node that holds it (rank 0's; a spread top's share per rank
/// times the node's ranks), for a top of at most o.pc_h2_top_size unknowns.
double h2_top_bytes(long long unknowns, const SizeOptions &o, const MachineLimits &m);

/// Why `type` cannot take `unknowns` unknowns on this machine: its entries or a rank's block
/// exceed the index width, or it needs more memory than the nodes have (node_bytes()); with the
/// size, the need and the options that can take it (another operator, single precision,
/// Jacobi instead of PC h2, a looser H² tolerance). Empty when it fits.
std::string size_refusal(OperatorType type, long long unknowns, const SizeOptions &o, const MachineLimits &m);

} // namespace hssbem
