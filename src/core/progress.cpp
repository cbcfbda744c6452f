// Progress of long work (see progress.hpp).
#include "hssbem/core/progress.hpp"

#include <algorithm>

namespace hssbem {

namespace {
ProgressHook g_progress = nullptr;
}

void set_progress_hook(ProgressHook hook) { g_progress = hook; }

ProgressHook progress_hook() { return g_progress; }

void Progress::report(double done) const
{
  if (g_progress) g_progress(m_phase, std::clamp(done, 0.0, 0.999), m_timer.seconds());
}

Progress::~Progress()
{
  if (g_progress && std::uncaught_exceptions() <= m_exceptions) g_progress(m_phase, 1.0, m_timer.seconds());
}

} // namespace hssbem
