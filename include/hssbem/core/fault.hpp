/// \file fault.hpp
/// Fault injection, for tests only: code marks the places where a failure must be survivable with
/// fault_point("Site"); a test arms one site (from the command line: -hssbem_fault, read by the
/// PETSc face at HssbemInitializePackage()) to throw an error, throw std::bad_alloc, or pause
/// there (so that a test can signal the process at a known moment). Unarmed, a fault point costs
/// one comparison.
#pragma once

#include <string>

namespace hssbem {

enum class FaultKind {
  Error,       ///< throw std::runtime_error("injected fault at <site>")
  OutOfMemory, ///< throw std::bad_alloc
  Pause        ///< sleep `seconds`, then go on
};

/// One armed site. rank < 0: every rank; else only the process whose rank (in the world
/// communicator, given to arm_fault) is `rank`.
struct FaultPlan {
  std::string site;
  FaultKind kind = FaultKind::Error;
  int rank = -1;
  double seconds = 0;
};

/// Arm `plan` for this process (rank `this_rank`); an empty site disarms. Not thread-safe: call
/// it once at start-up.
void arm_fault(const FaultPlan &plan, int this_rank);

/// The kind named "error", "oom" or "pause"; false for any other name.
bool parse_fault_kind(const std::string &name, FaultKind *kind);

/// A place where a failure must be handled cleanly: does what the armed plan says when it names
/// `site` (and this rank), nothing otherwise. Call it outside OpenMP regions.
void fault_point(const char *site);

/// True when `site` is armed for this rank: for sites that raise an error type of their own (a
/// factorization breakdown, say) instead of fault_point()'s.
bool fault_armed(const char *site);

} // namespace hssbem
