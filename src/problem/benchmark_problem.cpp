#include "hssbem/problem/benchmark_problem.hpp"

#include <algorithm>
#include <vector>

namespace hssbem {

SystemSelection clamped_lower_half(const Discretization &disc, const Vec3 &traction)
{
  const int n = disc.num_nodes();
  std::vector<double> z(n);
  for (int i = 0; i < n; ++i) z[i] = disc.node_position(i)[2];
  std::vector<double> zs(z);
  std::nth_element(zs.begin(), zs.begin() + n / 2, zs.end());
  const double zmid = zs[n / 2];
  SystemSelection sel;
  sel.displacement_known.resize(n);
  sel.known.assign(n, Vec3{0, 0, 0});
  for (int i = 0; i < n; ++i) {
    const bool clamped = z[i] < zmid;
    sel.displacement_known[i] = {clamped, clamped, clamped};
    if (!clamped) sel.known[i] = traction;
  }
  return sel;
}

} // namespace hssbem
