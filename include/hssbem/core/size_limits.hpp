/// \file size_limits.hpp
/// What each operator path can take: the index width and the memory of the machine. A problem
/// beyond them is refused before anything is allocated, naming its size and a path that can
/// take it (the PETSc face checks in HssbemCreateSystem(); -bem_mat_type auto picks within them).
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

/// What else than its type and size decides an operator's memory.
struct SizeOptions {
  bool   single_precision = false; ///< H²: single-precision blocks
  double h2_rel_tol = 1e-5;        ///< H²: the compression's tolerance
  bool   h2_factored = false;      ///< H²: PC h2 factors it (GMRES + PC h2, or a direct solve)
};

/// Bytes the operator `type` needs at its peak for `unknowns` unknowns (whole run):
/// - dense: the matrix and its LU factor, 16 N² (PETSc's dense LU and ScaLAPACK keep both);
/// - H²: the matrix, 23.8 kB per unknown with single-precision blocks at tol 1e-5 up to 40 000
///   unknowns (the disk organ at 40k, the largest of the sweep: 18.6–19.2 kB on spheres), falling
///   as (N / 40 000)^-0.06 beyond (the disk organ: 22.4, 21.6 and 21.0 kB at 80k, 160k and 300k),
///   times (1e-5 / tol)^0.135 (measured from 1e-4 to 1e-5: 14.8, 17.5 and 20.1 kB on a 20k
///   sphere) and 1.8 times that in double precision; PC h2's factorization adds 40 kB (its
///   factors, workspace and the rest of the driver at its peak: 300k through the driver with
///   GMRES + PC h2 peaked at 60.7 kB per unknown on the disk organ, 39.7 kB beyond its matrix,
///   and 45.7 kB on the sphere, 27 kB beyond); all plus 10 % margin;
/// - HSS: measured 268 MB at 2 994 unknowns at tol 1e-8, growing as N^1.5 (the ranks grow as the
///   square root of a cluster's size), plus 25 % margin.
/// Estimates for a refusal with a margin, not a forecast.
double estimated_bytes(OperatorType type, long long unknowns, const SizeOptions &o);

/// Why `type` cannot take `unknowns` unknowns on this machine: its entries or a rank's block
/// exceed the index width, or it needs more memory than the nodes have (dense, H² and HSS are
/// split over the ranks, a node holding its ranks' shares, HSS's rank 0 a quarter of a share more
/// for the top above the parts); with the size, the
/// need and the options that can take it (another operator, single precision, Jacobi instead of
/// PC h2, a looser H² tolerance). Empty when it fits. (On several ranks, `-pc_type h2` gathers the
/// H² matrix on rank 0, which this check does not foresee.)
std::string size_refusal(OperatorType type, long long unknowns, const SizeOptions &o, const MachineLimits &m);

} // namespace hssbem
