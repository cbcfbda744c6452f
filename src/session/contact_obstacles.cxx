// A contact session's obstacles besides solving (contact_obstacles.hpp).
#include "hssbem/session/contact_obstacles.hpp"

#include "hssbem/session/petsc_call.hpp"
#include "hssbem/problem/problem.hpp"

#include <limits>

#include <petscsys.h>

#include <algorithm>

namespace hssbem {

namespace {

const char *shape_name(Obstacle::Shape s)
{
  switch (s) {
  case Obstacle::Shape::Plane: return "plane";
  case Obstacle::Shape::Sphere: return "sphere";
  case Obstacle::Shape::Mesh: break;
  }
  return "mesh";
}

/// The vertices `where` selects (`where` empty: all) whose displacement is not prescribed in all
/// three components.
std::vector<int> candidate_vertices(const ProblemSetup &s, const std::vector<std::array<bool, 3>> &held, const std::vector<char> &where)
{
  std::vector<int> out;
  for (std::size_t v = 0; v < s.mesh->vertices.size(); ++v)
    if ((where.empty() || where[v]) && !(held[v][0] && held[v][1] && held[v][2])) out.push_back(static_cast<int>(v));
  return out;
}

/// Each vertex's outward unit normal: the area-weighted mean of its triangles' (the mesh is
/// oriented outward).
std::vector<Vec3> vertex_normals(const SurfaceMesh &mesh)
{
  std::vector<Vec3> n(mesh.vertices.size(), Vec3{0, 0, 0});
  for (const auto &tri : mesh.triangles) {
    const Vec3 a = cross(mesh.vertices[tri[1]] - mesh.vertices[tri[0]], mesh.vertices[tri[2]] - mesh.vertices[tri[0]]);
    for (int k = 0; k < 3; ++k) n[tri[k]] = n[tri[k]] + a;
  }
  for (Vec3 &v : n) v = normalized(v);
  return n;
}

} // namespace

ContactObstacles::ContactObstacles(const ProblemSetup &s, const std::vector<Obstacle> &obstacles, const std::vector<std::array<bool, 3>> &held, const std::vector<char> &where,
                                   double reach, double depth)
    : m_s(s), m_noted(obstacles.size(), 0)
{
  const std::vector<Vec3> normals = vertex_normals(*s.mesh);
  for (int v : candidate_vertices(s, held, where)) {
    m_candidates.push_back(s.mesh->vertices[v]);
    m_candidate_normals.push_back(normals[v]);
  }
  Vec3 lo = s.mesh->vertices.empty() ? Vec3{} : s.mesh->vertices[0], hi = lo;
  for (const Vec3 &p : s.mesh->vertices)
    for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], p[d]), hi[d] = std::max(hi[d], p[d]);
  m_reach = reach > 0 ? reach : 0.05 * norm(hi - lo); // the engine's default (ContactOptions::reach)
  m_depth = depth > 0 ? depth : m_reach;
  for (const Obstacle &o : obstacles) {
    m_geometry.emplace_back(o, m_depth);
    m_surface.push_back(obstacle_surface(o, lo, hi));
  }
}

void ContactObstacles::check_facing(const std::vector<std::vector<Pose>> &poses) const
{
  for (std::size_t k = 0; k < m_geometry.size(); ++k) {
    if (m_geometry[k].obstacle().shape != Obstacle::Shape::Mesh) continue;
    try {
      for (const std::vector<Pose> &frame : poses)
        if (check_obstacle_faces(m_geometry[k], m_candidates, frame[k], m_reach, m_candidate_normals)) break;
    } catch (const std::invalid_argument &e) {
      if (k >= m_s.spec.contact.obstacles.size()) throw ProblemError("contact obstacle '" + m_geometry[k].name() + "': " + e.what()); // made in memory
      throw ProblemError(m_s.spec.file + ": contact.obstacles[" + std::to_string(k) + "] (" + m_s.spec.contact.obstacles[k].mesh_path + "): " + e.what());
    }
  }
}

void ContactObstacles::note_depth(long long frame, const std::vector<Pose> &poses)
{
  for (std::size_t k = 0; k < m_geometry.size(); ++k) {
    if (m_noted[k] || !m_geometry[k].open()) continue;
    long long deep = 0;
    for (const Vec3 &x : m_candidates) {
      ObstacleSide side;
      if (m_geometry[k].side(x, poses[k], std::numeric_limits<double>::infinity(), side) && !side.on_boundary && side.distance < -m_depth) ++deep;
    }
    if (deep == 0) continue;
    m_noted[k] = 1;
    HssbemCallThrow(PetscPrintf(PETSC_COMM_SELF, "hssbem: contact: note: frame %lld starts with %lld vertices deeper than %.3g (-contact_depth) behind obstacle '%s': not in contact with it\n",
                                frame, deep, m_depth, m_geometry[k].name().c_str()));
  }
}

std::vector<ObstacleSurface> ContactObstacles::surfaces(const std::vector<Pose> &poses) const
{
  const std::vector<std::vector<Vec3>> at = placed(poses);
  std::vector<ObstacleSurface> out;
  for (std::size_t k = 0; k < m_geometry.size(); ++k)
    out.push_back({m_geometry[k].name(), shape_name(m_geometry[k].obstacle().shape), at[k], m_surface[k].triangles});
  return out;
}

std::vector<std::vector<Vec3>> ContactObstacles::placed(const std::vector<Pose> &poses) const
{
  std::vector<std::vector<Vec3>> out(m_surface.size());
  for (std::size_t k = 0; k < m_surface.size(); ++k)
    for (const Vec3 &v : m_surface[k].vertices) out[k].push_back(poses[k].apply(v));
  return out;
}

} // namespace hssbem
