// The surfaces that show the obstacles in a result file (obstacle.hpp: obstacle_surface): a plane's
// patch around the bodies, a sphere triangulated, a mesh obstacle's own triangles.
#include "hssbem/contact/obstacle.hpp"

#include <cmath>
#include <cstdint>
#include <map>

namespace hssbem {

namespace {

constexpr int k_patch_squares = 16; ///< a plane's patch: squares per side (a finer patch sorts better in a painter's algorithm)
constexpr int k_sphere_refinements = 2;

/// The icosahedron on the unit sphere, its triangles facing out.
SurfaceMesh icosahedron()
{
  const double p = (1 + std::sqrt(5.0)) / 2;
  SurfaceMesh m;
  m.vertices = {{-1, p, 0}, {1, p, 0}, {-1, -p, 0}, {1, -p, 0}, {0, -1, p}, {0, 1, p}, {0, -1, -p}, {0, 1, -p}, {p, 0, -1}, {p, 0, 1}, {-p, 0, -1}, {-p, 0, 1}};
  for (Vec3 &v : m.vertices) v = normalized(v);
  m.triangles = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                 {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8}, {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  return m;
}

/// Each triangle split in four at its edges' midpoints, pushed onto the unit sphere.
SurfaceMesh refine_on_sphere(const SurfaceMesh &m)
{
  SurfaceMesh out;
  out.vertices = m.vertices;
  std::map<std::pair<int, int>, int> middle;
  auto mid = [&](int a, int b) {
    const auto key = std::make_pair(std::min(a, b), std::max(a, b));
    const auto it = middle.find(key);
    if (it != middle.end()) return it->second;
    out.vertices.push_back(normalized(out.vertices[a] + out.vertices[b]));
    return middle[key] = static_cast<int>(out.vertices.size()) - 1;
  };
  for (const auto &t : m.triangles) {
    const int ab = mid(t[0], t[1]), bc = mid(t[1], t[2]), ca = mid(t[2], t[0]);
    out.triangles.insert(out.triangles.end(), {{t[0], ab, ca}, {t[1], bc, ab}, {t[2], ca, bc}, {ab, bc, ca}});
  }
  return out;
}

SurfaceMesh sphere_surface(const Vec3 &centre, double radius)
{
  SurfaceMesh m = icosahedron();
  for (int r = 0; r < k_sphere_refinements; ++r) m = refine_on_sphere(m);
  for (Vec3 &v : m.vertices) v = centre + radius * v;
  return m;
}

/// A square patch of the plane (point p, unit normal n) centred at the projection of c, of side
/// `side`, its triangles facing along n.
SurfaceMesh plane_patch(const Vec3 &p, const Vec3 &n, const Vec3 &c, double side)
{
  int axis = 0; // the axis least along n gives the first tangent
  for (int d = 1; d < 3; ++d)
    if (std::abs(n[d]) < std::abs(n[axis])) axis = d;
  Vec3 e{0, 0, 0};
  e[axis] = 1;
  const Vec3 t1 = normalized(e - dot(e, n) * n), t2 = cross(n, t1); // t1 × t2 = n
  const Vec3 origin = c - dot(c - p, n) * n - 0.5 * side * (t1 + t2);
  const int k = k_patch_squares;
  SurfaceMesh m;
  for (int j = 0; j <= k; ++j)
    for (int i = 0; i <= k; ++i) m.vertices.push_back(origin + (side * i / k) * t1 + (side * j / k) * t2);
  for (int j = 0; j < k; ++j)
    for (int i = 0; i < k; ++i) {
      const int a = j * (k + 1) + i, b = a + 1, d = a + k + 1, c2 = d + 1;
      m.triangles.push_back({a, b, c2});
      m.triangles.push_back({a, c2, d});
    }
  return m;
}

} // namespace

SurfaceMesh obstacle_surface(const Obstacle &o, const Vec3 &lo, const Vec3 &hi)
{
  SurfaceMesh m;
  switch (o.shape) {
  case Obstacle::Shape::Mesh: m.vertices = o.vertices, m.triangles = o.triangles; break;
  case Obstacle::Shape::Sphere: m = sphere_surface(o.center, o.radius); break;
  case Obstacle::Shape::Plane: {
    const double diagonal = norm(hi - lo);
    m = plane_patch(o.point, normalized(o.normal), 0.5 * (lo + hi), diagonal > 0 ? 1.5 * diagonal : 1.0);
    break;
  }
  }
  m.triangle_region.assign(m.triangles.size(), -1);
  m.source = o.name;
  return m;
}

} // namespace hssbem
