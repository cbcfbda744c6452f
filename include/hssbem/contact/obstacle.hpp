/// \file obstacle.hpp
/// Rigid obstacles a body is pressed against: a plane, a sphere, or a rigid triangulated
/// surface (open or closed), each at a base position that frames translate.
///
/// The gap of a body point x (linearised contact, small deformations): the signed distance from
/// the obstacle along its normal at the point of the obstacle closest to x, positive outside;
/// the normal points from the obstacle toward x. Plane: g = (x − p)·n. Sphere: g = |x − c| − R,
/// n = (x − c)/|x − c|. Mesh: the closest point q of its triangles; inside a triangle n is the
/// triangle's right-hand normal (the side facing the bodies) and g = (x − q)·n; on an edge or a
/// corner n = ±(x − q)/|x − q|, the sign that of (x − q)·n_t for the closest triangle t.
#pragma once

#include "hssbem/bem/mesh.hpp"
#include "hssbem/contact/triangle_bvh.hpp"

#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace hssbem {

struct Obstacle {
  enum class Shape { Plane, Sphere, Mesh };
  std::string name;
  Shape shape = Shape::Plane;
  Vec3 point{}, normal{};                  ///< plane: a point on it, its normal toward the bodies (any length but 0)
  Vec3 center{};                           ///< sphere: centre and radius (the bodies are outside)
  double radius = 0;
  std::vector<Vec3> vertices;              ///< mesh: the triangles' right-hand normals face the bodies
  std::vector<std::array<int, 3>> triangles;
  double friction = std::numeric_limits<double>::quiet_NaN(); ///< Coulomb coefficient of this obstacle (NaN: the global one)

  static Obstacle plane(std::string name, const Vec3 &point, const Vec3 &normal);
  static Obstacle sphere(std::string name, const Vec3 &center, double radius);
  /// A rigid mesh obstacle from a surface mesh (e.g. read_mesh()); it need not be closed.
  static Obstacle mesh(std::string name, const SurfaceMesh &mesh);
};

/// Where an obstacle meets a point: the signed gap along the normal, and the unit normal from
/// the obstacle toward the point.
struct ObstacleGap {
  double gap = 0;
  Vec3 normal{};
};

/// An obstacle ready for gap queries (a mesh obstacle's hierarchy is built once).
class ObstacleGeometry {
public:
  /// Checks the description: throws std::invalid_argument naming the obstacle for a zero normal,
  /// a radius ≤ 0, a non-finite coordinate, an empty mesh, a degenerate triangle or a negative
  /// friction coefficient.
  explicit ObstacleGeometry(Obstacle o);

  /// The gap of x to the obstacle translated by `offset`, when it is at most `reach`; false when
  /// the obstacle is farther (or x sits on a sphere's centre).
  bool gap(const Vec3 &x, const Vec3 &offset, double reach, ObstacleGap &out) const;
  const Obstacle &obstacle() const { return m_o; }
  const std::string &name() const { return m_o.name; }
  /// A length of the obstacle's own (radius, mesh bounding-box diagonal; 0 for a plane).
  double size() const;

private:
  bool mesh_gap(const Vec3 &x, double reach, ObstacleGap &out) const;

  Obstacle m_o;
  TriangleBvh m_bvh;
  std::vector<Vec3> m_tri_normal;
};

} // namespace hssbem
