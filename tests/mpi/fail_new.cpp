// Test-only: a replacement of the global operator new, preloaded into the driver (LD_PRELOAD) by
// tests/mpi/alloc_sweep.py, that fails one chosen large allocation with std::bad_alloc.
//
// The library arms it through its fault injection (core/fault.hpp): with `-hssbem_fault <site>
// -hssbem_fault_kind alloc -hssbem_fault_count N -hssbem_fault_rank r`, rank r calls
// hssbem_fail_new_arm(N) at the site's fault point and hssbem_fail_new_disarm() at its end
// (fault_end). While armed, the allocations of at least HSSBEM_FAIL_NEW_MIN_BYTES bytes (default
// 4096) are counted, on every thread, and the Nth of them throws; N = 0 only counts. At exit, an
// armed-once process appends "<counted> <failed>" to the file HSSBEM_FAIL_NEW_REPORT, when set.
// The nothrow forms are not counted (their callers expect null, not an exception).
#include <atomic>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <new>

namespace {

std::atomic<long> g_nth{-1};  // -1: disarmed
std::atomic<long> g_count{0}; // large allocations since arming
std::atomic<int> g_failed{0};
std::atomic<bool> g_used{false};
std::size_t g_min_bytes = 4096;

void report()
{
  const char *path = std::getenv("HSSBEM_FAIL_NEW_REPORT");
  if (!path || !g_used) return;
  if (FILE *f = std::fopen(path, "a")) {
    std::fprintf(f, "%ld %d\n", g_count.load(), g_failed.load());
    std::fclose(f);
  }
}

void *allocate(std::size_t size, std::size_t align)
{
  if (size >= g_min_bytes && g_nth.load(std::memory_order_relaxed) >= 0) {
    const long k = ++g_count;
    if (k == g_nth.load()) {
      g_failed = 1;
      throw std::bad_alloc();
    }
  }
  if (size == 0) size = 1;
  void *p = align > alignof(std::max_align_t) ? std::aligned_alloc(align, (size + align - 1) / align * align) : std::malloc(size);
  if (!p) throw std::bad_alloc();
  return p;
}

void *allocate_nothrow(std::size_t size, std::size_t align) noexcept
{
  if (size == 0) size = 1;
  return align > alignof(std::max_align_t) ? std::aligned_alloc(align, (size + align - 1) / align * align) : std::malloc(size);
}

} // namespace

extern "C" {

__attribute__((visibility("default"))) void hssbem_fail_new_arm(long nth)
{
  if (const char *m = std::getenv("HSSBEM_FAIL_NEW_MIN_BYTES")) g_min_bytes = std::strtoul(m, nullptr, 10);
  if (!g_used.exchange(true)) std::atexit(report);
  g_count = 0;
  g_nth = nth;
}

__attribute__((visibility("default"))) void hssbem_fail_new_disarm() { g_nth = -1; }
}

void *operator new(std::size_t size) { return allocate(size, 0); }
void *operator new[](std::size_t size) { return allocate(size, 0); }
void *operator new(std::size_t size, std::align_val_t a) { return allocate(size, static_cast<std::size_t>(a)); }
void *operator new[](std::size_t size, std::align_val_t a) { return allocate(size, static_cast<std::size_t>(a)); }
void *operator new(std::size_t size, const std::nothrow_t &) noexcept { return allocate_nothrow(size, 0); }
void *operator new[](std::size_t size, const std::nothrow_t &) noexcept { return allocate_nothrow(size, 0); }
void *operator new(std::size_t size, std::align_val_t a, const std::nothrow_t &) noexcept { return allocate_nothrow(size, static_cast<std::size_t>(a)); }
void *operator new[](std::size_t size, std::align_val_t a, const std::nothrow_t &) noexcept { return allocate_nothrow(size, static_cast<std::size_t>(a)); }
void operator delete(void *p) noexcept { std::free(p); }
void operator delete[](void *p) noexcept { std::free(p); }
void operator delete(void *p, std::size_t) noexcept { std::free(p); }
void operator delete[](void *p, std::size_t) noexcept { std::free(p); }
void operator delete(void *p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void *p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void *p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void *p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void *p, const std::nothrow_t &) noexcept { std::free(p); }
void operator delete[](void *p, const std::nothrow_t &) noexcept { std::free(p); }
