/// \file surface_nesting.cpp
/// How the closed surfaces of a mesh lie in one another (surface_intersection.hpp): each surface's
/// samples (vertices and triangle centroids) placed against every other surface by its nearest
/// point (on it, within the tolerance) or its winding number (inside or outside).
#include "hssbem/mesh/surface_intersection.hpp"
#include "hssbem/mesh/surface_locator.hpp"


#include <algorithm>
#include <cmath>
#include <memory>

namespace hssbem {

namespace {


/// One surface: its triangles, vertices, box, and (built when another surface's box meets it)
/// its locator over its own sub-mesh.
struct Surface {
  std::vector<int> triangles, vertices;
  Box box;
  SurfaceMesh own;
  std::unique_ptr<SurfaceLocator> locator;

  const SurfaceLocator &located(const SurfaceMesh &mesh)
  {
    if (!locator) own = sub_mesh(mesh, triangles), locator = std::make_unique<SurfaceLocator>(own);
    return *locator;
  }
};

std::vector<Surface> surfaces_of(const SurfaceMesh &mesh, const std::vector<int> &surface_of, int count)
{
  std::vector<Surface> s(count);
  std::vector<int> seen(mesh.vertices.size(), -1);
  for (int t = 0; t < mesh.num_triangles(); ++t) {
    Surface &f = s[surface_of[t]];
    f.triangles.push_back(t);
    for (int v : mesh.triangles[t]) {
      f.box.add(mesh.vertices[v]);
      if (seen[v] != surface_of[t]) seen[v] = surface_of[t], f.vertices.push_back(v);
    }
  }
  return s;
}

enum class Side { on, inside, outside };

Side side_of(const Vec3 &x, const SurfaceLocator &other, const Box &box, double eps)
{
  if (!box.contains(x, eps)) return Side::outside;
  if (other.nearest(x, eps).triangle >= 0) return Side::on;
  return std::abs(other.winding_number(x)) > 0.5 ? Side::inside : Side::outside; // either orientation
}

/// What surface a's samples say about surface b: every sample is looked at until both an inside
/// and an outside one are known.
struct Placement {
  SurfaceSample inside, outside;
  bool any_inside() const { return inside.vertex >= 0 || inside.triangle >= 0; }
  bool any_outside() const { return outside.vertex >= 0 || outside.triangle >= 0; }
};

Placement place(const SurfaceMesh &mesh, const Surface &a, Surface &b, double eps)
{
  Placement p;
  const SurfaceLocator &other = b.located(mesh);
  auto take = [&](const Vec3 &x, SurfaceSample s) {
    const Side side = side_of(x, other, b.box, eps);
    if (side == Side::inside && !p.any_inside()) p.inside = s;
    if (side == Side::outside && !p.any_outside()) p.outside = s;
    return p.any_inside() && p.any_outside();
  };
  for (int v : a.vertices)
    if (take(mesh.vertices[v], {v, -1})) return p;
  for (int t : a.triangles) {
    const auto &tri = mesh.triangles[t];
    if (take((1.0 / 3.0) * (mesh.vertices[tri[0]] + mesh.vertices[tri[1]] + mesh.vertices[tri[2]]), {-1, t})) return p;
  }
  return p;
}

} // namespace

SurfaceNesting nest_surfaces(const SurfaceMesh &mesh, const std::vector<int> &surface_of, int count, const IntersectionOptions &o)
{
  std::vector<Surface> s = surfaces_of(mesh, surface_of, count);
  Box all;
  for (const Surface &f : s) all.add(f.box);
  const double eps = o.tolerance * all.diagonal();
  SurfaceNesting out;
  out.inside.assign(count, std::vector<char>(count, 0));
  for (int a = 0; a < count; ++a)
    for (int b = 0; b < count; ++b) {
      if (a == b || !s[a].box.overlaps(s[b].box, eps)) continue;
      const Placement p = place(mesh, s[a], s[b], eps);
      out.inside[a][b] = p.any_inside() && !p.any_outside();
      if (out.crossing) continue;
      if (p.any_inside() && p.any_outside()) out.crossing = SurfaceCrossing{a, b, p.inside, p.outside, false};
      else if (!p.any_inside() && !p.any_outside()) out.crossing = SurfaceCrossing{a, b, {}, {}, true}; // every sample on b
    }
  return out;
}

} // namespace hssbem
