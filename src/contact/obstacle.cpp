// Rigid obstacles and their gaps (obstacle.hpp).
#include "hssbem/contact/obstacle.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <unordered_map>

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

/// Undirected edge as one key: lower index in the high half.
std::uint64_t edge_key(int a, int b)
{
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(std::min(a, b))) << 32) | static_cast<std::uint32_t>(std::max(a, b));
}

/// The angle of triangle (a, b, c) at a.
double corner_angle(const Vec3 &a, const Vec3 &b, const Vec3 &c)
{
  const Vec3 u = b - a, v = c - a;
  return std::atan2(norm(cross(u, v)), dot(u, v));
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

ObstacleGeometry::ObstacleGeometry(Obstacle o, double depth) : m_o(std::move(o)), m_depth(depth)
{
  if (m_o.name.empty()) refuse(m_o, "an obstacle needs a name");
  if (!std::isnan(m_o.friction) && !(m_o.friction >= 0 && std::isfinite(m_o.friction))) refuse(m_o, "the friction coefficient must be finite and >= 0");
  if (!(depth > 0)) refuse(m_o, "the depth must be > 0");
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
    SurfaceMesh surface;
    surface.vertices = m_o.vertices, surface.triangles = m_o.triangles, surface.source = m_o.name;
    try {
      m_open = !validate_open_surface(surface);
    } catch (const MeshError &e) {
      refuse(m_o, e.what());
    }
    m_bvh = TriangleBvh(m_o.vertices, m_o.triangles);
    build_pseudo_normals();
    break;
  }
}

/// The triangles' normals and the pseudo-normals of their edges and vertices (Bærentzen and
/// Aanæs): an edge's is the sum of its (one or two) triangles' normals, a vertex's the sum of its
/// triangles' normals weighted by their angles at it; both normalised.
void ObstacleGeometry::build_pseudo_normals()
{
  const std::size_t nt = m_o.triangles.size();
  m_tri_normal.resize(nt);
  m_vertex_normal.assign(m_o.vertices.size(), Vec3{0, 0, 0});
  m_vertex_boundary.assign(m_o.vertices.size(), 0);
  std::unordered_map<std::uint64_t, std::pair<Vec3, int>> edges; // sum of normals, triangles
  for (std::size_t t = 0; t < nt; ++t) {
    const auto &tri = m_o.triangles[t];
    const Vec3 &a = m_o.vertices[tri[0]], &b = m_o.vertices[tri[1]], &c = m_o.vertices[tri[2]];
    const Vec3 n = normalized(cross(b - a, c - a));
    m_tri_normal[t] = n;
    for (int k = 0; k < 3; ++k) {
      const Vec3 &p = m_o.vertices[tri[k]], &q = m_o.vertices[tri[(k + 1) % 3]], &r = m_o.vertices[tri[(k + 2) % 3]];
      m_vertex_normal[tri[k]] = m_vertex_normal[tri[k]] + corner_angle(p, q, r) * n;
      auto &e = edges[edge_key(tri[k], tri[(k + 1) % 3])];
      e.first = e.first + n, ++e.second;
    }
  }
  m_edge_normal.resize(nt);
  m_edge_boundary.resize(nt);
  for (std::size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = m_o.triangles[t][k], b = m_o.triangles[t][(k + 1) % 3];
      const auto &e = edges.at(edge_key(a, b));
      m_edge_normal[t][k] = normalized(e.first);
      m_edge_boundary[t][k] = e.second == 1;
      if (e.second == 1) m_vertex_boundary[a] = m_vertex_boundary[b] = 1;
    }
  for (Vec3 &n : m_vertex_normal) n = normalized(n);
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

/// The closest point of the mesh within `bound` and the pseudo-normal of the feature it lies
/// on: the triangle's interior, an edge (one barycentric coordinate zero) or a vertex (two).
bool ObstacleGeometry::mesh_hit(const Vec3 &y, double bound, MeshHit &out) const
{
  out.hit = m_bvh.closest(y, bound);
  const int t = out.hit.triangle;
  if (t < 0) return false;
  const auto &bary = out.hit.bary;
  const int zeros = int(bary[0] == 0) + int(bary[1] == 0) + int(bary[2] == 0);
  if (out.hit.interior || zeros == 0) {
    out.pseudo_normal = m_tri_normal[t], out.boundary = false;
  } else if (zeros == 1) {
    const int k = bary[2] == 0 ? 0 : bary[0] == 0 ? 1 : 2; // the edge from corner k to k + 1
    out.pseudo_normal = m_edge_normal[t][k], out.boundary = m_edge_boundary[t][k] != 0;
  } else {
    const int v = m_o.triangles[t][bary[0] != 0 ? 0 : bary[1] != 0 ? 1 : 2];
    out.pseudo_normal = m_vertex_normal[v], out.boundary = m_vertex_boundary[v] != 0;
  }
  return true;
}

/// Searched within max(reach, depth) of y: farther points are neither within reach in front nor
/// within the depth behind.
bool ObstacleGeometry::mesh_gap(const Vec3 &y, double reach, ObstacleGap &out) const
{
  MeshHit m;
  if (!mesh_hit(y, std::max(reach, depth()), m)) return false;
  const Vec3 d = y - m.hit.point;
  const double dist = norm(d), along = dot(d, m.pseudo_normal), touching = 1e-12 * std::max(1.0, size());
  if (m.boundary && along < 0 && dist > touching) return false; // behind and past an open mesh's edge: beside it
  out.base_point = m.hit.point;
  if (m.hit.interior || dist <= touching) {
    out.normal = m.pseudo_normal;
    out.gap = along;
  } else {
    const double side = along >= 0 ? 1.0 : -1.0;
    out.normal = (side / dist) * d;
    out.gap = side * dist;
  }
  return out.gap <= reach && out.gap >= -depth();
}

bool ObstacleGeometry::side(const Vec3 &x, const Pose &pose, double bound, ObstacleSide &out) const
{
  const Vec3 y = pose.apply_inverse(x);
  out.on_boundary = false;
  if (m_o.shape != Obstacle::Shape::Mesh) {
    ObstacleGap g;
    if (!base_gap(y, std::numeric_limits<double>::infinity(), g) || std::abs(g.gap) > bound) return false;
    out.distance = g.gap;
    return true;
  }
  MeshHit m;
  if (!mesh_hit(y, bound, m)) return false;
  const Vec3 d = y - m.hit.point;
  out.distance = (dot(d, m.pseudo_normal) >= 0 ? 1.0 : -1.0) * norm(d);
  out.on_boundary = m.boundary;
  out.normal = pose.rotate(normalized(m.pseudo_normal));
  return true;
}

bool check_obstacle_faces(const ObstacleGeometry &o, const std::vector<Vec3> &x, const Pose &pose, double reach, const std::vector<Vec3> &normals)
{
  if (o.obstacle().shape != Obstacle::Shape::Mesh) return false;
  if (!normals.empty() && normals.size() != x.size()) throw std::invalid_argument("check_obstacle_faces: one normal per point expected");
  long long front = 0, behind = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    ObstacleSide s;
    if (!o.side(x[i], pose, reach, s) || s.on_boundary) continue;
    ++((normals.empty() ? s.distance >= 0 : dot(normals[i], s.normal) <= 0) ? front : behind);
  }
  if (behind > front)
    refuse(o.obstacle(), "its triangles face away from the bodies (" + std::to_string(behind) + " of the " + std::to_string(front + behind) + " body vertices within reach of its faces " +
                             (normals.empty() ? "lie behind them" : "face their back") +
                             "); an obstacle mesh's triangles must face the bodies (right-hand normals toward them): reverse the vertex order of its triangles");
  return front + behind > 0;
}

} // namespace hssbem
