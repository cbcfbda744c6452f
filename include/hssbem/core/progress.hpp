/// \file progress.hpp
/// Progress of long work (compression, factorization levels, GMRES, scene set-up and frames),
/// reported to an optional hook that the host installs (the PETSc layer prints it on rank 0:
/// -hssbem_progress): the phase, the share of it done, the seconds since it began. The work calls
/// Progress::report() at its checkpoints (a level done, an iteration); without a hook that costs
/// one comparison. Call it from the thread that created the Progress, outside OpenMP regions.
#pragma once

#include "hssbem/core/timer.hpp"

#include <exception>

namespace hssbem {

/// Called with done in [0, 1); and once with done = 1 when the phase ends.
using ProgressHook = void (*)(const char *phase, double done, double seconds);

/// Install (or with nullptr remove) the hook; not thread-safe, call it once at start-up.
void set_progress_hook(ProgressHook hook);
/// The hook installed (null: none), for hosts that report progress of their own work (GMRES).
ProgressHook progress_hook();

/// One phase's progress, from construction (its start) to destruction (its end, reported as done;
/// not when an exception ends it).
class Progress {
public:
  explicit Progress(const char *phase) : m_phase(phase), m_exceptions(std::uncaught_exceptions()) {}
  ~Progress();
  Progress(const Progress &) = delete;
  Progress &operator=(const Progress &) = delete;
  /// The share of the phase done so far (clamped to [0, 1)).
  void report(double done) const;

private:
  const char *m_phase;
  int m_exceptions;
  Timer m_timer;
};

} // namespace hssbem
