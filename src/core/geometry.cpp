// Geometry shared by every layer (geometry.hpp).
#include "hssbem/core/geometry.hpp"

#include <algorithm>
#include <cmath>

namespace hssbem {

std::vector<Vec3> unit_sphere_points(int n)
{
  std::vector<Vec3> p(n);
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / n, r = std::sqrt(std::max(0.0, 1.0 - z * z)), phi = golden * i;
    p[i] = {r * std::cos(phi), r * std::sin(phi), z};
  }
  return p;
}

} // namespace hssbem
