#include "hssbem/core/phase.hpp"

namespace hssbem {

namespace {
PhaseHook g_hook = nullptr;
}

void set_phase_hook(PhaseHook hook) { g_hook = hook; }

PhaseScope::PhaseScope(Phase phase) : m_phase(phase)
{
  if (g_hook) g_hook(m_phase, true);
}

PhaseScope::~PhaseScope()
{
  if (g_hook) g_hook(m_phase, false);
}

} // namespace hssbem
