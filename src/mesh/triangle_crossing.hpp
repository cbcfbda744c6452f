/// \file triangle_crossing.hpp
/// Private to surface_intersection.cpp (and its unit test): whether two triangles cross, as
/// IntersectionOptions defines it (mesh/surface_intersection.hpp).
#pragma once

#include "hssbem/core/geometry.hpp"

#include <array>

namespace hssbem::detail {

using Triangle = std::array<Vec3, 3>;

/// True when `a` and `b` share a point interior to both, or lie in one plane (within `eps`),
/// face the same way and overlap with positive area. Distances up to `eps` (absolute) count as
/// zero, so that triangles that only touch are not taken to cross. Degenerate triangles (no
/// normal) never cross.
bool triangles_cross(const Triangle &a, const Triangle &b, double eps);

} // namespace hssbem::detail
