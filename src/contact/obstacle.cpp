// Rigid obstacles and their gaps (obstacle.hpp).
#include "hssbem/contact/obstacle.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hssbem {

namespace {

bool finite(const Vec3 &v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

[[noreturn]] void refuse(const Obstacle &o, const std::string &what) { throw std::invalid_argument("obstacle '" + o.name + "': " + what); }

void check_mesh(const Obstacle &o)
{
  if (o.triangles.empty()) refuse(o, "the mesh has no triangles");
  const int nv = static_cast<int>(o.vertices.size());
  for (const Vec3 &v : o.vertices)
    if (!finite(v)) refuse(o, "a mesh vertex is not finite");
  for (std::size_t t = 0; t < o.triangles.size(); ++t) {
    const auto &tri = o.triangles[t];
    for (int v : tri)
      if (v < 0 || v >= nv) refuse(o, "triangle " + std::to_string(t) + " refers to vertex " + std::to_string(v) + " of " + std::to_string(nv));
    if (norm(cross(o.vertices[tri[1]] - o.vertices[tri[0]], o.vertices[tri[2]] - o.vertices[tri[0]])) == 0)
      refuse(o, "triangle " + std::to_string(t) + " is degenerate (zero area)");
  }
}

} // namespace

Obstacle Obstacle::plane(std::string name, const Vec3 &point, const Vec3 &normal)
{
  Obstacle o;
  o.name = std::move(name), o.shape = Shape::Plane, o.point = point, o.normal = normal;
  return o;
}

Obstacle Obstacle::sphere(std::string name, const Vec3 &center, double radius)
{
  Obstacle o;
  o.name = std::move(name), o.shape = Shape::Sphere, o.center = center, o.radius = radius;
  return o;
}

Obstacle Obstacle::mesh(std::string name, const SurfaceMesh &mesh)
{
  Obstacle o;
  o.name = std::move(name), o.shape = Shape::Mesh, o.vertices = mesh.vertices, o.triangles = mesh.triangles;
  return o;
}

ObstacleGeometry::ObstacleGeometry(Obstacle o) : m_o(std::move(o))
{
  if (m_o.name.empty()) refuse(m_o, "an obstacle needs a name");
  if (!std::isnan(m_o.friction) && !(m_o.friction >= 0 && std::isfinite(m_o.friction))) refuse(m_o, "the friction coefficient must be finite and >= 0");
  switch (m_o.shape) {
  case Obstacle::Shape::Plane:
    if (!finite(m_o.point) || !finite(m_o.normal)) refuse(m_o, "the plane's point and normal must be finite");
    if (norm(m_o.normal) == 0) refuse(m_o, "the plane's normal is zero");
    m_o.normal = normalized(m_o.normal);
    break;
  case Obstacle::Shape::Sphere:
    if (!finite(m_o.center) || !std::isfinite(m_o.radius)) refuse(m_o, "the sphere's centre and radius must be finite");
    if (!(m_o.radius > 0)) refuse(m_o, "the sphere's radius must be > 0");
    break;
  case Obstacle::Shape::Mesh:
    check_mesh(m_o);
    m_bvh = TriangleBvh(m_o.vertices, m_o.triangles);
    m_tri_normal.resize(m_o.triangles.size());
    for (std::size_t t = 0; t < m_o.triangles.size(); ++t) {
      const auto &tri = m_o.triangles[t];
      m_tri_normal[t] = normalized(cross(m_o.vertices[tri[1]] - m_o.vertices[tri[0]], m_o.vertices[tri[2]] - m_o.vertices[tri[0]]));
    }
    break;
  }
}

double ObstacleGeometry::size() const
{
  if (m_o.shape == Obstacle::Shape::Sphere) return m_o.radius;
  if (m_o.shape == Obstacle::Shape::Plane) return 0;
  Vec3 lo = m_o.vertices[0], hi = lo;
  for (const Vec3 &v : m_o.vertices)
    for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], v[d]), hi[d] = std::max(hi[d], v[d]);
  return norm(hi - lo);
}

Pose Pose::translation(const Vec3 &t)
{
  Pose p;
  p.translate = t;
  return p;
}

Pose Pose::turn(const Vec3 &axis, double angle_deg, const Vec3 &about, const Vec3 &t)
{
  if (!finite(axis) || norm(axis) == 0) throw std::invalid_argument("a turn needs a finite, non-zero axis");
  if (!std::isfinite(angle_deg)) throw std::invalid_argument("a turn needs a finite angle");
  if (!finite(about) || !finite(t)) throw std::invalid_argument("a turn needs a finite centre and translation");
  const Vec3 k = normalized(axis);
  const double a = angle_deg * M_PI / 180.0, c = std::cos(a), s = std::sin(a), v = 1 - c;
  Pose p; // Rodrigues: R = c I + s [k]x + (1 − c) k kᵀ
  p.rotation = {c + v * k[0] * k[0],        v * k[0] * k[1] - s * k[2], v * k[0] * k[2] + s * k[1],
                v * k[1] * k[0] + s * k[2], c + v * k[1] * k[1],        v * k[1] * k[2] - s * k[0],
                v * k[2] * k[0] - s * k[1], v * k[2] * k[1] + s * k[0], c + v * k[2] * k[2]};
  p.about = about;
  p.translate = t;
  return p;
}

Vec3 Pose::rotate(const Vec3 &v) const
{
  const Mat3 &R = rotation;
  return {R[0] * v[0] + R[1] * v[1] + R[2] * v[2], R[3] * v[0] + R[4] * v[1] + R[5] * v[2], R[6] * v[0] + R[7] * v[1] + R[8] * v[2]};
}

Vec3 Pose::rotate_back(const Vec3 &v) const
{
  const Mat3 &R = rotation;
  return {R[0] * v[0] + R[3] * v[1] + R[6] * v[2], R[1] * v[0] + R[4] * v[1] + R[7] * v[2], R[2] * v[0] + R[5] * v[1] + R[8] * v[2]};
}

Vec3 Pose::apply(const Vec3 &x) const { return rotate(x - about) + about + translate; }
Vec3 Pose::apply_inverse(const Vec3 &y) const { return rotate_back(y - translate - about) + about; }

bool Pose::is_translation() const { return rotation == Mat3{1, 0, 0, 0, 1, 0, 0, 0, 1}; }

Vec3 ObstacleGeometry::default_centre() const
{
  switch (m_o.shape) {
  case Obstacle::Shape::Plane: return m_o.point;
  case Obstacle::Shape::Sphere: return m_o.center;
  case Obstacle::Shape::Mesh: break;
  }
  Vec3 c{0, 0, 0};
  for (const Vec3 &v : m_o.vertices) c = c + v;
  return (1.0 / static_cast<double>(m_o.vertices.size())) * c;
}

bool ObstacleGeometry::gap(const Vec3 &x, const Pose &pose, double reach, ObstacleGap &out) const
{
  if (pose.is_translation()) { // the common case: no rotation to apply
    if (!base_gap(x - pose.translate, reach, out)) return false;
    out.point = out.base_point + pose.translate;
    return true;
  }
  if (!base_gap(pose.apply_inverse(x), reach, out)) return false;
  out.normal = pose.rotate(out.normal);
  out.point = pose.apply(out.base_point);
  return true;
}

bool ObstacleGeometry::base_gap(const Vec3 &y, double reach, ObstacleGap &out) const
{
  switch (m_o.shape) {
  case Obstacle::Shape::Plane:
    out.normal = m_o.normal;
    out.gap = dot(y - m_o.point, m_o.normal);
    out.base_point = y - out.gap * m_o.normal;
    return out.gap <= reach;
  case Obstacle::Shape::Sphere: {
    const Vec3 d = y - m_o.center;
    const double r = norm(d);
    if (r == 0) return false;
    out.gap = r - m_o.radius;
    out.normal = (1.0 / r) * d;
    out.base_point = m_o.center + m_o.radius * out.normal;
    return out.gap <= reach;
  }
  case Obstacle::Shape::Mesh: return mesh_gap(y, reach, out);
  }
  return false;
}

/// A point behind the mesh (a negative gap) is as far from it as one in front: the search
/// bound is |reach| either way, and the gap's sign comes from the closest triangle's side.
bool ObstacleGeometry::mesh_gap(const Vec3 &y, double reach, ObstacleGap &out) const
{
  const TriangleHit h = m_bvh.closest(y);
  if (h.triangle < 0) return false;
  const Vec3 &nt = m_tri_normal[h.triangle];
  const Vec3 d = y - h.point;
  const double dist = norm(d);
  out.base_point = h.point;
  if (h.interior || dist <= 1e-12 * std::max(1.0, size())) {
    out.normal = nt;
    out.gap = dot(d, nt);
  } else {
    const double side = dot(d, nt) >= 0 ? 1.0 : -1.0;
    out.normal = (side / dist) * d;
    out.gap = side * dist;
  }
  return out.gap <= reach;
}

} // namespace hssbem
