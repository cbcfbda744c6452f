#include "hssbem/core/fault.hpp"

#include <chrono>
#include <new>
#include <stdexcept>
#include <thread>

namespace hssbem {

namespace {

FaultPlan g_plan;     // the armed site; empty: none
bool      g_armed = false;

} // namespace

void arm_fault(const FaultPlan &plan, int this_rank)
{
  g_plan  = plan;
  g_armed = !plan.site.empty() && (plan.rank < 0 || plan.rank == this_rank);
}

bool parse_fault_kind(const std::string &name, FaultKind *kind)
{
  if (name == "error") *kind = FaultKind::Error;
  else if (name == "oom") *kind = FaultKind::OutOfMemory;
  else if (name == "pause") *kind = FaultKind::Pause;
  else return false;
  return true;
}

bool fault_armed(const char *site) { return g_armed && g_plan.site == site; }

void fault_point(const char *site)
{
  if (!g_armed || g_plan.site != site) return;
  switch (g_plan.kind) {
  case FaultKind::Error: throw std::runtime_error("injected fault at " + g_plan.site);
  case FaultKind::OutOfMemory: throw std::bad_alloc();
  case FaultKind::Pause: std::this_thread::sleep_for(std::chrono::duration<double>(g_plan.seconds)); break;
  }
}

} // namespace hssbem
