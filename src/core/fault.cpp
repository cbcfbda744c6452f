#include "hssbem/core/fault.hpp"

#include <chrono>
#include <new>
#include <stdexcept>
#include <thread>

// The controls of the test shim that replaces operator new (tests/mpi/fail_new.cpp); null unless
// a test preloads it.
extern "C" {
void hssbem_fail_new_arm(long nth) __attribute__((weak));
void hssbem_fail_new_disarm() __attribute__((weak));
}

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
  else if (name == "unreadable") *kind = FaultKind::Unreadable;
  else if (name == "alloc") *kind = FaultKind::Allocation;
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
  case FaultKind::Unreadable: break; // acts through fault_path()
  case FaultKind::Allocation:
    if (!hssbem_fail_new_arm) throw std::logic_error("-hssbem_fault_kind alloc needs the allocation shim of the tests preloaded");
    hssbem_fail_new_arm(g_plan.count);
    break;
  }
}

void fault_end(const char *site)
{
  if (g_armed && g_plan.site == site && g_plan.kind == FaultKind::Allocation && hssbem_fail_new_disarm) hssbem_fail_new_disarm();
}

std::string fault_path(const char *site, const std::string &path)
{
  if (!fault_armed(site) || g_plan.kind != FaultKind::Unreadable) return path;
  const std::size_t slash = path.find_last_of('/');
  const std::size_t name  = slash == std::string::npos ? 0 : slash + 1;
  return path.substr(0, name) + "injected-unreadable/" + path.substr(name); // a folder that does not exist
}

} // namespace hssbem
