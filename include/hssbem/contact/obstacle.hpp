/// \file obstacle.hpp
/// Rigid obstacles a body is pressed against: a plane, a sphere, or a rigid triangulated
/// surface (open or closed), each at a base position that frames move rigidly (a Pose: a turn
/// about a centre and a translation).
///
/// The gap of a body point x (linearised contact, small deformations): the signed distance from
/// the obstacle along its normal at the point of the obstacle closest to x, positive outside;
/// the normal points from the obstacle toward x. Plane: g = (x − p)·n. Sphere: g = |x − c| − R,
/// n = (x − c)/|x − c|. Mesh: the closest point q of its triangles; inside a triangle n is the
/// triangle's right-hand normal (the side facing the bodies) and g = (x − q)·n; on an edge or a
/// corner n = ±(x − q)/|x − q|, the sign that of (x − q)·n_t for the closest triangle t.
#pragma once

#include "hssbem/mesh/mesh.hpp"
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

/// A rigid placement of an obstacle relative to its base position: x ↦ R (x − c) + c + t, R a
/// rotation (row-major), c the centre of the turn, t the translation. Absolute, not cumulative.
struct Pose {
  Pose() noexcept {} // user-provided: not an aggregate, so a braced {x, y, z} is an offset, never a Pose
  Mat3 rotation{1, 0, 0, 0, 1, 0, 0, 0, 1};
  Vec3 about{};
  Vec3 translate{};

  /// A translation alone.
  static Pose translation(const Vec3 &t);
  /// The turn by `angle_deg` degrees about `axis` (right-hand rule) through `about`, then the
  /// translation t. Throws std::invalid_argument for a zero or non-finite axis or a non-finite angle.
  static Pose turn(const Vec3 &axis, double angle_deg, const Vec3 &about, const Vec3 &t = {0, 0, 0});
  /// The image of a point of the obstacle's base position.
  Vec3 apply(const Vec3 &x) const;
  /// The base-position point whose image is y.
  Vec3 apply_inverse(const Vec3 &y) const;
  /// The image of a direction (R v).
  Vec3 rotate(const Vec3 &v) const;
  /// Rᵀ v.
  Vec3 rotate_back(const Vec3 &v) const;
  bool is_translation() const;
};

/// Where an obstacle meets a point: the signed gap along the normal, the unit normal from the
/// obstacle toward the point, and the obstacle's closest point (in the posed obstacle, and in its
/// base position: the material point, which moves with the obstacle's pose).
struct ObstacleGap {
  double gap = 0;
  Vec3 normal{};
  Vec3 point{};       ///< the obstacle's point closest to x (posed)
  Vec3 base_point{};  ///< the same point in the obstacle's base position
};

/// An obstacle ready for gap queries (a mesh obstacle's hierarchy is built once).
class ObstacleGeometry {
public:
  /// Checks the description: throws std::invalid_argument naming the obstacle for a zero normal,
  /// a radius ≤ 0, a non-finite coordinate, an empty mesh, a degenerate triangle or a negative
  /// friction coefficient.
  explicit ObstacleGeometry(Obstacle o);

  /// The gap of x to the obstacle at `pose`, when it is at most `reach`; false when the obstacle
  /// is farther (or x sits on a sphere's centre).
  bool gap(const Vec3 &x, const Pose &pose, double reach, ObstacleGap &out) const;
  /// The same for the obstacle translated by `offset`.
  bool gap(const Vec3 &x, const Vec3 &offset, double reach, ObstacleGap &out) const { return gap(x, Pose::translation(offset), reach, out); }
  /// The default centre of a turn: the plane's point, the sphere's centre, the mesh's centroid
  /// (the mean of its vertices).
  Vec3 default_centre() const;
  const Obstacle &obstacle() const { return m_o; }
  const std::string &name() const { return m_o.name; }
  /// A length of the obstacle's own (radius, mesh bounding-box diagonal; 0 for a plane).
  double size() const;

private:
  /// The gap in the base position (y = the point taken back by the pose).
  bool base_gap(const Vec3 &y, double reach, ObstacleGap &out) const;
  bool mesh_gap(const Vec3 &y, double reach, ObstacleGap &out) const;

  Obstacle m_o;
  TriangleBvh m_bvh;
  std::vector<Vec3> m_tri_normal;
};

} // namespace hssbem
