// What every compression of K shares (see compression.hpp).
#include "hssbem/compress/compression.hpp"

#include <algorithm>
#include <cmath>

namespace hssbem {

int default_proxy_points(double rel_tol)
{
  // Enough points to resolve the far field's spherical harmonics up to the degree where they
  // fall below the tolerance (they decay like (1/proxy_ratio)^degree); measured on the test meshes.
  const double digits = std::max(1.0, -std::log10(rel_tol));
  return std::clamp(static_cast<int>(std::lround(6.0 * digits * digits + 40)), 64, 1024);
}

std::vector<Vec3> collocation_points(const Discretization &disc)
{
  std::vector<Vec3> points(disc.num_nodes());
  for (int i = 0; i < disc.num_nodes(); ++i) points[i] = disc.node(i).point;
  return points;
}

} // namespace hssbem
