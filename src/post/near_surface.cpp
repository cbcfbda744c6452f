// Interior points: outside, on the surface, in the band along it, or deep (see near_surface.hpp).
#include "hssbem/post/near_surface.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

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

/// What classify needs of the surface near a point: its nearest point within `reach` (the band's
/// search reach), or none, when the plan's decision does not depend on it. A point whose nearest
/// triangle T lies at d is in the band when d < band · longest_edge(T), so beyond band · ℓ (ℓ: a
/// percentile of the longest edges) only the triangles longer than ℓ can make it so. Staged:
/// first the nearest point within band · ℓ; if there is none, the nearest among the longer
/// triangles within the reach (their own tree); if that one puts the point in the band, the
/// nearest point overall is either it or a shorter triangle closer still (which leaves the point
/// deep). The decisions are those of one search within the reach.
class InteriorPlan::Search {
public:
  Search(const SurfaceLocator &locator, double band, double reach, bool staged) : m_all(locator), m_band(band), m_reach(reach)
  {
    const SurfaceMesh &mesh = locator.mesh();
    if (!staged || band <= 0 || mesh.num_triangles() == 0) return;
    std::vector<double> edge(mesh.num_triangles());
    for (int t = 0; t < mesh.num_triangles(); ++t) edge[t] = longest_edge(mesh, t);
    std::vector<double> sorted = edge;
    const std::size_t at = (sorted.size() * 9) / 10;
    std::nth_element(sorted.begin(), sorted.begin() + at, sorted.end());
    const double first = band * sorted[at] * (1 + 1e-12);
    if (!(first < reach)) return;
    m_first = first;
    m_long_mesh.vertices = mesh.vertices;
    for (int t = 0; t < mesh.num_triangles(); ++t)
      if (band * edge[t] * (1 + 1e-12) > first) m_long_mesh.triangles.push_back(mesh.triangles[t]), m_long_id.push_back(t);
    if (!m_long_id.empty()) m_long.emplace(m_long_mesh);
  }
  const SurfaceLocator &locator() const { return m_all; }
  SurfaceLocator::Nearest nearest(const Vec3 &x) const
  {
    if (m_first <= 0) return m_all.nearest(x, m_reach);
    SurfaceLocator::Nearest n = m_all.nearest(x, m_first);
    if (n.triangle >= 0 || !m_long) return n;
    SurfaceLocator::Nearest l = m_long->nearest(x, m_reach);
    if (l.triangle < 0) return l;
    l.triangle = m_long_id[l.triangle];
    if (!(l.distance < m_band * longest_edge(m_all.mesh(), l.triangle))) return {}; // deep: its nearest triangle is this one or a closer short one
    const SurfaceLocator::Nearest closer = m_all.nearest(x, l.distance);
    return closer.triangle >= 0 && closer.distance < l.distance ? SurfaceLocator::Nearest{} : l; // a closer short triangle: deep
  }

private:
  const SurfaceLocator &m_all;
  double m_band, m_reach, m_first = 0;
  SurfaceMesh m_long_mesh;
  std::vector<int> m_long_id;
  std::optional<SurfaceLocator> m_long;
};

InteriorPlan::Recipe InteriorPlan::classify(const Search &search, const SurfaceMesh &mesh, const Vec3 &x, signed char side, const Reach &reach,
                                            std::array<Vec3, 2> &support)
{
  Recipe r;
  if (side == 2) return deep_recipe(x, support); // no surface within reach.band (grid_inside)
  const SurfaceLocator &locator = search.locator();
  // A point outside by the caller only needs to know whether it lies on the surface.
  const SurfaceLocator::Nearest n = side == 0 ? locator.nearest(x, reach.on * (1 + 1e-12)) : search.nearest(x);
  if (n.triangle >= 0 && n.distance <= reach.on) {
    r.kind = PointKind::Surface, r.triangle = n.triangle, r.bary = n.bary, r.w_surface = 1;
    return r;
  }
  if (side == 0 || (side < 0 && !(n.triangle >= 0 ? locator.inside(x, n) : locator.inside(x)))) return r; // Outside
  const double delta = n.triangle >= 0 ? reach.band_depth * longest_edge(mesh, n.triangle) : 0.0;
  if (n.triangle >= 0 && n.distance < delta) return band_recipe(locator, mesh, x, n, delta, support);
  return deep_recipe(x, support);
}

double InteriorPlan::search_reach(const SurfaceLocator &locator, const SurfaceMesh &mesh, const InteriorPlanOptions &o)
{
  return std::max(o.on_surface * locator.size(), o.band * max_edge(mesh));
}

InteriorPlan::InteriorPlan(const SurfaceLocator &locator, const SurfaceMesh &mesh, const std::vector<Vec3> &points, const InteriorPlanOptions &o,
                           const std::vector<signed char> *inside)
  : m_recipe(points.size())
{
  Reach reach;
  reach.on = o.on_surface * locator.size(), reach.band = search_reach(locator, mesh, o), reach.band_depth = o.band;
  const Search search(locator, o.band, reach.band * (1 + 1e-12), o.staged_search);
  std::vector<std::array<Vec3, 2>> support(points.size());
  const long long np = static_cast<long long>(points.size());
#pragma omp parallel for schedule(dynamic, 256)
  for (long long p = 0; p < np; ++p) m_recipe[p] = classify(search, mesh, points[p], inside ? (*inside)[p] : -1, reach, support[p]);
  // The evaluation points in the order of the points, each point's support points in turn.
  for (std::size_t p = 0; p < points.size(); ++p)
    for (int s = 0; s < 2; ++s)
      if (m_recipe[p].eval[s] >= 0) m_recipe[p].eval[s] = static_cast<int>(m_eval.size()), m_eval.push_back(support[p][s]);
}

namespace {

/// The indices (i, j, k) of grid point p, numbered x fastest.
std::array<long long, 3> grid_index(long long p, const std::array<int, 3> &n) { return {p % n[0], (p / n[0]) % n[1], p / (1LL * n[0] * n[1])}; }

/// Dilates the set `near` (one flag per grid point) by r points along axis a: afterwards a point
/// is set when some point of the set lies at most r points from it along that axis.
void dilate(const std::array<int, 3> &n, int a, int r, std::vector<char> &near)
{
  const long long stride[3] = {1, n[0], 1LL * n[0] * n[1]}, total = stride[2] * n[2];
  const long long lines = total / n[a];
#pragma omp parallel for schedule(static)
  for (long long l = 0; l < lines; ++l) {
    // the first point of line l: its index along a is 0, the others run over the other two axes
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    const long long first = (l % n[b]) * stride[b] + (l / n[b]) * stride[c];
    std::vector<char> was(static_cast<std::size_t>(n[a]));
    for (int i = 0; i < n[a]; ++i) was[i] = near[first + i * stride[a]];
    int last = -r - 1; // the last set point seen, forward then backward
    for (int i = 0; i < n[a]; ++i) {
      if (was[i]) last = i;
      if (i - last <= r) near[first + i * stride[a]] = 1;
    }
    last = n[a] + r;
    for (int i = n[a] - 1; i >= 0; --i) {
      if (was[i]) last = i;
      if (last - i <= r) near[first + i * stride[a]] = 1;
    }
  }
}

/// Inside points (side 1) at least `beyond` from the surface become 2 (grid_inside). The points
/// within a step of the surface (not clear) and the grid's boundary (the surface may leave the
/// grid) are dilated by a cube of r points each way: a point left out has none of them within r
/// points along every axis, so the grid point nearest to its nearest surface point q (within a
/// step of the surface, or on the boundary if q lies outside the grid) is more than r points away
/// along some axis: |x − q| ≥ (r + 1 − ½) h, h the smallest spacing.
void mark_deep(const std::array<int, 3> &n, const Vec3 &spacing, const std::vector<char> &clear, double beyond, std::vector<signed char> &side)
{
  const long long total = 1LL * n[0] * n[1] * n[2];
  const double h = std::min({spacing[0], spacing[1], spacing[2]});
  const double r = std::ceil(beyond / h - 0.5); // (r + ½) h ≥ beyond
  if (!(r < std::max({n[0], n[1], n[2]}))) return;
  std::vector<char> near(static_cast<std::size_t>(total));
  for (long long p = 0; p < total; ++p) {
    const std::array<long long, 3> idx = grid_index(p, n);
    bool boundary = false;
    for (int a = 0; a < 3; ++a) boundary = boundary || idx[a] == 0 || idx[a] == n[a] - 1;
    near[p] = !clear[p] || boundary;
  }
  for (int a = 0; a < 3; ++a) dilate(n, a, static_cast<int>(r), near);
  for (long long p = 0; p < total; ++p)
    if (side[p] == 1 && !near[p]) side[p] = 2;
}

/// Union-find over grid points.
int find_root(std::vector<int> &parent, int i)
{
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

} // namespace

std::vector<signed char> grid_inside(const SurfaceLocator &locator, const Vec3 &origin, const Vec3 &spacing, const std::array<int, 3> &n, double deep_beyond)
{
  const long long total = 1LL * n[0] * n[1] * n[2];
  const double step = std::max({spacing[0], spacing[1], spacing[2]}) * (1 + 1e-9);
  const long long stride[3] = {1, n[0], 1LL * n[0] * n[1]};
  auto point = [&](long long p) {
    const std::array<long long, 3> idx = grid_index(p, n);
    return Vec3{origin[0] + idx[0] * spacing[0], origin[1] + idx[1] * spacing[1], origin[2] + idx[2] * spacing[2]};
  };
  // The points within a step of some triangle's bounding box: only they can lie within a step of the surface.
  std::vector<char> candidate(static_cast<std::size_t>(total), 0);
  const SurfaceMesh &mesh = locator.mesh();
  for (const auto &t : mesh.triangles) {
    long long lo[3], hi[3];
    bool empty = false;
    for (int a = 0; a < 3; ++a) {
      const double x0 = std::min({mesh.vertices[t[0]][a], mesh.vertices[t[1]][a], mesh.vertices[t[2]][a]}) - 1.01 * step;
      const double x1 = std::max({mesh.vertices[t[0]][a], mesh.vertices[t[1]][a], mesh.vertices[t[2]][a]}) + 1.01 * step;
      lo[a] = std::max(0LL, static_cast<long long>(std::ceil((x0 - origin[a]) / spacing[a])));
      hi[a] = std::min(n[a] - 1LL, static_cast<long long>(std::floor((x1 - origin[a]) / spacing[a])));
      empty = empty || lo[a] > hi[a];
    }
    if (empty) continue;
    for (long long k = lo[2]; k <= hi[2]; ++k)
      for (long long j = lo[1]; j <= hi[1]; ++j)
        std::fill(candidate.begin() + (k * stride[2] + j * stride[1] + lo[0]), candidate.begin() + (k * stride[2] + j * stride[1] + hi[0] + 1), 1);
  }
  std::vector<signed char> side(static_cast<std::size_t>(total), -1);
  std::vector<char> clear(static_cast<std::size_t>(total), 1);
#pragma omp parallel for schedule(dynamic, 256)
  for (long long p = 0; p < total; ++p) {
    if (!candidate[p]) continue;
    const Vec3 x = point(p);
    const SurfaceLocator::Nearest near = locator.nearest(x, step);
    clear[p] = near.triangle < 0;
    if (!clear[p]) side[p] = locator.inside(x, near);
  }
  std::vector<int> parent(static_cast<std::size_t>(total));
  for (long long p = 0; p < total; ++p) parent[p] = static_cast<int>(p);
  for (long long p = 0; p < total; ++p) {
    const std::array<long long, 3> idx = grid_index(p, n);
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
  if (deep_beyond > 0) mark_deep(n, spacing, clear, deep_beyond, side);
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
