// Nearest surface points and winding numbers through a bounding-ball tree (see surface_locator.hpp).
#include "hssbem/mesh/surface_locator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hssbem {

namespace {

/// Clusters beyond this many radii count through their dipole.
constexpr double far_ratio = 4.0;

std::vector<Vec3> centroids(const SurfaceMesh &mesh)
{
  std::vector<Vec3> c(mesh.triangles.size());
  for (int t = 0; t < mesh.num_triangles(); ++t) {
    const auto &v = mesh.triangles[t];
    c[t] = (1.0 / 3) * (mesh.vertices[v[0]] + mesh.vertices[v[1]] + mesh.vertices[v[2]]);
  }
  return c;
}

/// Solid angle of triangle (a, b, c) seen from x, positive when x lies behind its normal.
double solid_angle(const Vec3 &x, const Vec3 &pa, const Vec3 &pb, const Vec3 &pc)
{
  const Vec3 a = pa - x, b = pb - x, c = pc - x;
  const double la = norm(a), lb = norm(b), lc = norm(c);
  const double num = dot(a, cross(b, c));
  const double den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
  return 2.0 * std::atan2(num, den);
}

ClusterTreeOptions small_leaves()
{
  ClusterTreeOptions o;
  o.leaf_size = 8;
  o.refine_splits = false;
  return o;
}

} // namespace

SurfaceLocator::SurfaceLocator(const SurfaceMesh &mesh) : m_mesh(&mesh), m_tree(centroids(mesh), small_leaves())
{
  m_size = Box::of(mesh.vertices).diagonal();
  m_ball.resize(m_tree.num_clusters());
  const std::vector<int> &perm = m_tree.perm();
  for (int k = 0; k < m_tree.num_clusters(); ++k) {
    const Cluster &cl = m_tree.cluster(k);
    Ball &b = m_ball[k];
    double area = 0;
    for (int p = cl.begin; p < cl.end; ++p) {
      const int t = perm[p];
      const auto &v = mesh.triangles[t];
      const double A = mesh.triangle_area(t);
      b.centre = b.centre + (A / 3) * (mesh.vertices[v[0]] + mesh.vertices[v[1]] + mesh.vertices[v[2]]);
      b.dipole = b.dipole + A * mesh.triangle_normal(t);
      area += A;
    }
    b.centre = (1.0 / area) * b.centre;
    b.lo = b.hi = mesh.vertices[mesh.triangles[perm[cl.begin]][0]];
    for (int p = cl.begin; p < cl.end; ++p)
      for (int v : mesh.triangles[perm[p]]) {
        b.radius = std::max(b.radius, norm(mesh.vertices[v] - b.centre));
        for (int a = 0; a < 3; ++a) b.lo[a] = std::min(b.lo[a], mesh.vertices[v][a]), b.hi[a] = std::max(b.hi[a], mesh.vertices[v][a]);
      }
  }
}

double SurfaceLocator::distance_to(int c, const Vec3 &x) const
{
  const Ball &b = m_ball[c];
  double box = 0;
  for (int a = 0; a < 3; ++a) {
    const double out = std::max({b.lo[a] - x[a], 0.0, x[a] - b.hi[a]});
    box += out * out;
  }
  return std::max(norm(x - b.centre) - b.radius, std::sqrt(box));
}

void SurfaceLocator::nearest_in(int c, const Vec3 &x, Nearest &best) const
{
  if (distance_to(c, x) >= best.distance) return;
  const Cluster &cl = m_tree.cluster(c);
  if (cl.left < 0) {
    for (int p = cl.begin; p < cl.end; ++p) {
      const int t = m_tree.perm()[p];
      const auto &v = m_mesh->triangles[t];
      const TrianglePoint q = closest_point_on_triangle(x, m_mesh->vertices[v[0]], m_mesh->vertices[v[1]], m_mesh->vertices[v[2]]);
      const double d = norm(x - q.point);
      if (d < best.distance) best = {t, q.point, q.bary, d};
    }
    return;
  }
  const double dl = norm(x - m_ball[cl.left].centre), dr = norm(x - m_ball[cl.right].centre);
  nearest_in(dl <= dr ? cl.left : cl.right, x, best);
  nearest_in(dl <= dr ? cl.right : cl.left, x, best);
}

SurfaceLocator::Nearest SurfaceLocator::nearest(const Vec3 &x, double limit) const
{
  Nearest best;
  best.distance = limit;
  nearest_in(0, x, best);
  return best;
}

double SurfaceLocator::winding_in(int c, const Vec3 &x) const
{
  const Ball &b = m_ball[c];
  const Vec3 d = b.centre - x;
  const double r = norm(d);
  if (r > far_ratio * b.radius) return dot(b.dipole, d) / (r * r * r);
  const Cluster &cl = m_tree.cluster(c);
  if (cl.left >= 0) return winding_in(cl.left, x) + winding_in(cl.right, x);
  double sum = 0;
  for (int p = cl.begin; p < cl.end; ++p) {
    const auto &v = m_mesh->triangles[m_tree.perm()[p]];
    sum += solid_angle(x, m_mesh->vertices[v[0]], m_mesh->vertices[v[1]], m_mesh->vertices[v[2]]);
  }
  return sum;
}

double SurfaceLocator::winding_number(const Vec3 &x) const { return winding_in(0, x) / (4.0 * M_PI); }

bool SurfaceLocator::inside(const Vec3 &x, const Nearest &n) const
{
  constexpr double interior = 1e-6, off_plane = 1e-9; // barycentric margin; distance from the plane relative to the surface's size
  if (n.triangle >= 0 && std::min({n.bary[0], n.bary[1], n.bary[2]}) > interior) {
    const double side = dot(x - n.point, m_mesh->triangle_normal(n.triangle));
    if (std::abs(side) > off_plane * m_size) return side < 0;
  }
  return inside(x);
}

} // namespace hssbem
