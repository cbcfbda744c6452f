// Interior points: outside, on the surface, in the band along it, or deep (see near_surface.hpp).
#include "hssbem/bem/near_surface.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hssbem {

namespace {

/// A support point at depth s along the line must lie at least this fraction of s from the
/// surface: its nearest surface is (nearly) the one the line starts from, so the line does not
/// reach across a thin wall or towards another face.
constexpr double support_clearance = 0.9;

double longest_edge(const SurfaceMesh &mesh, int t)
{
  const auto &v = mesh.triangles[t];
  const Vec3 &a = mesh.vertices[v[0]], &b = mesh.vertices[v[1]], &c = mesh.vertices[v[2]];
  return std::sqrt(std::max({dot(b - a, b - a), dot(c - b, c - b), dot(a - c, a - c)}));
}

double max_edge(const SurfaceMesh &mesh)
{
  double h = 0;
  for (int t = 0; t < mesh.num_triangles(); ++t) h = std::max(h, longest_edge(mesh, t));
  return h;
}

/// Whether y is at least `clearance` from the surface and inside the body. `joined`: y is known to
/// be reachable from an inside point without crossing the surface (see band_recipe), so no
/// winding number is needed.
bool clear_of_surface(const SurfaceLocator &locator, const Vec3 &y, double clearance, bool joined)
{
  return locator.nearest(y, clearance).triangle < 0 && (joined || locator.inside(y));
}

} // namespace

// The support points lie on the ray from x0 through x (inside, at distance d < δ from x0, the
// ball of radius d around it free of the surface). x1 = x0 + δ dir, clear by 0.9 δ: the segment
// from x to x1 lies in the two empty balls when 2 d > 0.1 δ, so x1 is inside without a winding
// number; x2 = x0 + 2 δ dir, clear by 1.8 δ, is likewise joined to x1 (0.9 + 1.8 > 1).
static_assert(3 * support_clearance > 1, "the second support point's ball must reach the first's");

InteriorPlan::Recipe InteriorPlan::band_recipe(const SurfaceLocator &locator, const SurfaceMesh &mesh, const Vec3 &x, const SurfaceLocator::Nearest &n,
                                               double delta, std::array<Vec3, 2> &support)
{
  Recipe r;
  r.kind = PointKind::Band;
  r.triangle = n.triangle;
  r.bary = n.bary;
  const double d = n.distance;
  const Vec3 dir = d > 0 ? (1.0 / d) * (x - n.point) : -1.0 * mesh.triangle_normal(n.triangle);
  for (int halve = 0; halve < 3 && d < delta; ++halve, delta *= 0.5) {
    const Vec3 x1 = n.point + delta * dir, x2 = n.point + (2 * delta) * dir;
    if (!clear_of_surface(locator, x1, support_clearance * delta, 2 * d > (1 - support_clearance) * delta)) continue;
    const double s = d / delta;
    support[0] = x1, r.eval[0] = 0;
    if (clear_of_surface(locator, x2, 2 * support_clearance * delta, true)) { // quadratic through 0, δ, 2δ
      support[1] = x2, r.eval[1] = 0;
      r.w_surface = 0.5 * (s - 1) * (s - 2);
      r.w[0] = s * (2 - s);
      r.w[1] = 0.5 * s * (s - 1);
    } else { // linear through 0, δ
      r.w_surface = 1 - s;
      r.w[0] = s;
    }
    return r;
  }
  return deep_recipe(x, support); // no clear line: integrate where the point is
}

InteriorPlan::Recipe InteriorPlan::deep_recipe(const Vec3 &x, std::array<Vec3, 2> &support)
{
  Recipe r;
  r.kind = PointKind::Deep, r.eval[0] = 0, r.w[0] = 1;
  support[0] = x;
  return r;
}

InteriorPlan::Recipe InteriorPlan::classify(const SurfaceLocator &locator, const SurfaceMesh &mesh, const Vec3 &x, signed char side, const Reach &reach,
                                            std::array<Vec3, 2> &support)
{
  Recipe r;
  // A point outside by the caller only needs to know whether it lies on the surface.
  const SurfaceLocator::Nearest n = locator.nearest(x, (side == 0 ? reach.on : reach.band) * (1 + 1e-12));
  if (n.triangle >= 0 && n.distance <= reach.on) {
    r.kind = PointKind::Surface, r.triangle = n.triangle, r.bary = n.bary, r.w_surface = 1;
    return r;
  }
  if (side == 0 || (side < 0 && !(n.triangle >= 0 ? locator.inside(x, n) : locator.inside(x)))) return r; // Outside
  const double delta = n.triangle >= 0 ? reach.band_depth * longest_edge(mesh, n.triangle) : 0.0;
  if (n.triangle >= 0 && n.distance < delta) return band_recipe(locator, mesh, x, n, delta, support);
  return deep_recipe(x, support);
}

InteriorPlan::InteriorPlan(const SurfaceLocator &locator, const SurfaceMesh &mesh, const std::vector<Vec3> &points, const InteriorPlanOptions &o,
                           const std::vector<signed char> *inside)
  : m_recipe(points.size())
{
  Reach reach;
  reach.on = o.on_surface * locator.size(), reach.band = std::max(reach.on, o.band * max_edge(mesh)), reach.band_depth = o.band;
  std::vector<std::array<Vec3, 2>> support(points.size());
  const long long np = static_cast<long long>(points.size());
#pragma omp parallel for schedule(dynamic, 256)
  for (long long p = 0; p < np; ++p) m_recipe[p] = classify(locator, mesh, points[p], inside ? (*inside)[p] : -1, reach, support[p]);
  // The evaluation points in the order of the points, each point's support points in turn.
  for (std::size_t p = 0; p < points.size(); ++p)
    for (int s = 0; s < 2; ++s)
      if (m_recipe[p].eval[s] >= 0) m_recipe[p].eval[s] = static_cast<int>(m_eval.size()), m_eval.push_back(support[p][s]);
}

namespace {

/// Union-find over grid points.
int find_root(std::vector<int> &parent, int i)
{
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

} // namespace

std::vector<signed char> grid_inside(const SurfaceLocator &locator, const Vec3 &origin, const Vec3 &spacing, const std::array<int, 3> &n)
{
  const long long total = 1LL * n[0] * n[1] * n[2];
  const double step = std::max({spacing[0], spacing[1], spacing[2]}) * (1 + 1e-9);
  auto point = [&](long long p) {
    const long long i = p % n[0], j = (p / n[0]) % n[1], k = p / (1LL * n[0] * n[1]);
    return Vec3{origin[0] + i * spacing[0], origin[1] + j * spacing[1], origin[2] + k * spacing[2]};
  };
  std::vector<signed char> side(static_cast<std::size_t>(total), -1);
  std::vector<char> clear(static_cast<std::size_t>(total));
#pragma omp parallel for schedule(dynamic, 256)
  for (long long p = 0; p < total; ++p) {
    const Vec3 x = point(p);
    const SurfaceLocator::Nearest near = locator.nearest(x, step);
    clear[p] = near.triangle < 0;
    if (!clear[p]) side[p] = locator.inside(x, near);
  }
  std::vector<int> parent(static_cast<std::size_t>(total));
  for (long long p = 0; p < total; ++p) parent[p] = static_cast<int>(p);
  const long long stride[3] = {1, n[0], 1LL * n[0] * n[1]};
  for (long long p = 0; p < total; ++p) {
    const long long idx[3] = {p % n[0], (p / n[0]) % n[1], p / stride[2]};
    for (int a = 0; a < 3; ++a)
      if (idx[a] + 1 < n[a] && (clear[p] || clear[p + stride[a]])) parent[find_root(parent, static_cast<int>(p))] = find_root(parent, static_cast<int>(p + stride[a]));
  }
  std::vector<signed char> root_side(static_cast<std::size_t>(total), -1);
  for (long long p = 0; p < total; ++p)
    if (side[p] >= 0) root_side[find_root(parent, static_cast<int>(p))] = side[p];
  for (long long p = 0; p < total; ++p) {
    if (side[p] >= 0) continue;
    signed char &r = root_side[find_root(parent, static_cast<int>(p))];
    if (r < 0) r = locator.inside(point(p)); // a component that never nears the surface
    side[p] = r;
  }
  return side;
}

std::vector<FieldValue> InteriorPlan::finish(const std::vector<double> &values, const std::vector<std::array<Vec3, 3>> &corner_u,
                                             const std::vector<std::array<Voigt, 3>> &corner_stress) const
{
  FieldValue none;
  none.fill(std::numeric_limits<double>::quiet_NaN());
  std::vector<FieldValue> out(m_recipe.size(), none);
  for (std::size_t p = 0; p < m_recipe.size(); ++p) {
    const Recipe &r = m_recipe[p];
    if (r.kind == PointKind::Outside) continue;
    FieldValue v{};
    if (r.w_surface != 0)
      for (int c = 0; c < 3; ++c) {
        const double w = r.w_surface * r.bary[c];
        for (int k = 0; k < 3; ++k) v[k] += w * corner_u[r.triangle][c][k];
        for (int k = 0; k < 6; ++k) v[3 + k] += w * corner_stress[r.triangle][c][k];
      }
    for (int s = 0; s < 2; ++s)
      if (r.eval[s] >= 0)
        for (int k = 0; k < field_outputs; ++k) v[k] += r.w[s] * values[static_cast<std::size_t>(r.eval[s]) * field_outputs + k];
    out[p] = v;
  }
  return out;
}

} // namespace hssbem
