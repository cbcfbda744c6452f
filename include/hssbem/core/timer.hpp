/// \file timer.hpp
/// The one clock behind the seconds the library reports: the engine's phase times (HssStats,
/// H2Stats), PC hss's view and the result file's /timings. Log events (petsc/log.h) are the
/// profiler's view of the same phases; this is for figures that are printed or stored.
#pragma once

#include <chrono>

namespace hssbem {

/// Wall-clock seconds (a steady clock) since construction or the last restart().
class Timer {
public:
  double seconds() const { return std::chrono::duration<double>(Clock::now() - m_start).count(); }
  void restart() { m_start = Clock::now(); }

private:
  using Clock = std::chrono::steady_clock;
  Clock::time_point m_start = Clock::now();
};

} // namespace hssbem
