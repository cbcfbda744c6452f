/// \file bounding_box.hpp
/// Private to bem/ (the surface checks): an axis-aligned bounding box.
#pragma once

#include "hssbem/core/geometry.hpp"

#include <algorithm>
#include <cmath>

namespace hssbem::detail {

/// An axis-aligned box, empty until a point is added.
struct Box {
  Vec3 lo{HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};

  void add(const Vec3 &x)
  {
    for (int i = 0; i < 3; ++i) lo[i] = std::min(lo[i], x[i]), hi[i] = std::max(hi[i], x[i]);
  }
  void add(const Box &b) { add(b.lo), add(b.hi); }
  /// The boxes share a point, each grown by `pad` (≥ 0).
  bool overlaps(const Box &b, double pad = 0) const
  {
    for (int i = 0; i < 3; ++i)
      if (b.lo[i] > hi[i] + pad || b.hi[i] < lo[i] - pad) return false;
    return true;
  }
  /// x lies in the box grown by `pad` (≥ 0).
  bool contains(const Vec3 &x, double pad = 0) const
  {
    for (int i = 0; i < 3; ++i)
      if (x[i] < lo[i] - pad || x[i] > hi[i] + pad) return false;
    return true;
  }
  double diagonal() const { return lo[0] <= hi[0] ? norm(hi - lo) : 0.0; }
  Vec3 center() const { return 0.5 * (lo + hi); }
};

} // namespace hssbem::detail
