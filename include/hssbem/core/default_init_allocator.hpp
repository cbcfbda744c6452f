/// \file default_init_allocator.hpp
/// An allocator whose value-less construct() default-initialises (for double: leaves the value
/// as it is) instead of zeroing: a std::vector<double, DefaultInitAllocator<double>> resized to
/// gigabytes that are overwritten at once (a factorization read from a file) is not first
/// filled with zeros, a pass over memory that buys nothing.
#pragma once

#include <memory>
#include <utility>

namespace hssbem {

template <class T> struct DefaultInitAllocator : std::allocator<T> {
  template <class U> struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  DefaultInitAllocator() noexcept = default;
  template <class U> DefaultInitAllocator(const DefaultInitAllocator<U> &) noexcept {}
  /// resize(n) and vector(n): default-initialised elements (indeterminate for double).
  template <class U> void construct(U *p) noexcept(noexcept(::new (static_cast<void *>(p)) U)) { ::new (static_cast<void *>(p)) U; }
  /// Everything else as std::allocator does it (assign(n, 0.0) still writes zeros).
  template <class U, class... Args> void construct(U *p, Args &&...args) { ::new (static_cast<void *>(p)) U(std::forward<Args>(args)...); }
};

} // namespace hssbem
