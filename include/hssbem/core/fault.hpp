/// \file fault.hpp
/// Fault injection, for tests only: code marks the places where a failure must be survivable with
/// fault_point("Site") (and a file it opens with fault_path("Site", path)); a test arms one site (from the command line: -hssbem_fault, read by the
/// PETSc face at HssbemInitializePackage()) to throw an error, throw std::bad_alloc, or pause
/// there (so that a test can signal the process at a known moment), or make a file unreadable
/// there. Unarmed, a fault point costs one comparison.
#pragma once

#include <string>

namespace hssbem {

enum class FaultKind {
  Error,       ///< throw std::runtime_error("injected fault at <site>")
  OutOfMemory, ///< throw std::bad_alloc
  Pause,       ///< sleep `seconds`, then go on
  Unreadable,  ///< fault_path() gives a path that cannot be opened; fault_point() does nothing
  /// From the site's fault point to its fault_end(), the `count`th large allocation (operator
  /// new) throws std::bad_alloc: needs the test shim that replaces operator new
  /// (tests/mpi/fail_new.cpp, preloaded), else the fault point throws std::logic_error.
  Allocation
};

/// One armed site. rank < 0: every rank; else only the process whose rank (in the world
/// communicator, given to arm_fault) is `rank`.
struct FaultPlan {
  std::string site;
  FaultKind kind = FaultKind::Error;
  int rank = -1;
  double seconds = 0;
  long count = 0; ///< Allocation: which large allocation fails (0: none, they are only counted)
};

/// Arm `plan` for this process (rank `this_rank`); an empty site disarms. Not thread-safe: call
/// it once at start-up.
void arm_fault(const FaultPlan &plan, int this_rank);

/// The kind named "error", "oom", "pause", "unreadable" or "alloc"; false for any other name.
bool parse_fault_kind(const std::string &name, FaultKind *kind);

/// A place where a failure must be handled cleanly: does what the armed plan says when it names
/// `site` (and this rank), nothing otherwise. Call it outside OpenMP regions.
void fault_point(const char *site);

/// The end of the work a fault point marks, for kinds that act over a stretch of it (Allocation).
void fault_end(const char *site);

/// The file to open at `site`: `path`, or, when `site` is armed for this rank with
/// FaultKind::Unreadable, the same name in a folder "injected-unreadable" beside it that does
/// not exist (so the reader's own error for a
/// file it cannot open is what the test sees). Other kinds act through fault_point().
std::string fault_path(const char *site, const std::string &path);

/// True when `site` is armed for this rank: for sites that raise an error type of their own (a
/// factorization breakdown, say) instead of fault_point()'s.
bool fault_armed(const char *site);

} // namespace hssbem
