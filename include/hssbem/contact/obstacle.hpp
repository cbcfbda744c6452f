/// \file obstacle.hpp
/// Rigid obstacles a body is pressed against: a plane, a sphere, or a rigid triangulated
/// surface (open or closed), each at a base position that frames move rigidly (a Pose: a turn
/// about a centre and a translation).
///
/// The gap of a body point x (linearised contact, small deformations): the signed distance from
/// the obstacle along its normal at the point of the obstacle closest to x, positive in front
/// (outside); the normal points from the obstacle toward x. Plane: g = (x − p)·n. Sphere:
/// g = |x − c| − R, n = (x − c)/|x − c|. Mesh: the closest point q of its triangles, and the
/// sign from the angle-weighted pseudo-normal N of the feature q lies on (Bærentzen and Aanæs,
/// 2005): the triangle's normal inside a triangle, the sum of its two triangles' normals on an
/// edge, the sum of its triangles' normals weighted by their angles at a vertex. Inside a
/// triangle n = N and g = (x − q)·N; on an edge or a vertex n = ±(x − q)/|x − q| and g = ±|x − q|,
/// the sign that of (x − q)·N. So the sign at edges and corners does not depend on which of the
/// triangles there is found first, and a closed mesh's inside is negative, its outside positive.
///
/// An open mesh (a plate, a retractor) has a boundary: its edges of one triangle and their
/// vertices. A point whose closest point lies on the boundary and that lies behind it
/// ((x − q)·N < 0: behind the plate's plane and past its edge) is beside the obstacle, not in it:
/// no contact. And a point deeper behind an open mesh than its `depth` (ObstacleGeometry) lies on
/// the far side of the sheet, not in it: no contact either. Closed meshes, planes and spheres are
/// solids: every point behind them is in them.
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

/// Where a point lies against an obstacle, with no reach or depth: the signed distance (positive
/// in front), and whether the closest point lies on an open mesh's boundary.
struct ObstacleSide {
  double distance = 0;
  bool on_boundary = false;
  Vec3 normal{}; ///< a mesh obstacle's unit pseudo-normal at the closest point, posed (planes and spheres: zero)
};

/// An obstacle ready for gap queries (a mesh obstacle's hierarchy and pseudo-normals are built once).
class ObstacleGeometry {
public:
  /// Checks the description: throws std::invalid_argument naming the obstacle for a zero normal,
  /// a radius ≤ 0, a non-finite coordinate, an empty mesh, a negative friction coefficient, or a
  /// mesh that validate_open_surface() refuses (a degenerate or duplicate triangle, an edge of
  /// more than two triangles, an inconsistent orientation, a surface through itself). `depth`:
  /// a point deeper than this behind an open mesh obstacle is not in contact with it (ignored by
  /// the solids: closed meshes, planes and spheres); it must be > 0.
  explicit ObstacleGeometry(Obstacle o, double depth = std::numeric_limits<double>::infinity());

  /// The gap of x to the obstacle at `pose`, when it is at most `reach`; false when the obstacle
  /// is farther, when x sits on a sphere's centre, lies behind an open mesh's boundary, or deeper
  /// behind an open mesh than its depth.
  bool gap(const Vec3 &x, const Pose &pose, double reach, ObstacleGap &out) const;
  /// The same for the obstacle translated by `offset`.
  bool gap(const Vec3 &x, const Vec3 &offset, double reach, ObstacleGap &out) const { return gap(x, Pose::translation(offset), reach, out); }
  /// Where x lies against the obstacle at `pose` (no reach, no depth: the orientation checks
  /// and the driver's notes); false when the obstacle is farther than `bound` (or x sits on a
  /// sphere's centre).
  bool side(const Vec3 &x, const Pose &pose, double bound, ObstacleSide &out) const;
  /// The default centre of a turn: the plane's point, the sphere's centre, the mesh's centroid
  /// (the mean of its vertices).
  Vec3 default_centre() const;
  const Obstacle &obstacle() const { return m_o; }
  const std::string &name() const { return m_o.name; }
  /// A length of the obstacle's own (radius, mesh bounding-box diagonal; 0 for a plane).
  double size() const;
  /// An open mesh: a sheet with a boundary, the one shape with a depth.
  bool open() const { return m_open; }
  /// The depth behind an open mesh beyond which a point is not in contact with it (infinite for
  /// the solids).
  double depth() const { return m_open ? m_depth : std::numeric_limits<double>::infinity(); }

private:
  /// The closest point of a mesh obstacle and its feature, in the base position.
  struct MeshHit {
    TriangleHit hit;
    Vec3 pseudo_normal{};
    bool boundary = false;
  };
  /// The gap in the base position (y = the point taken back by the pose).
  bool base_gap(const Vec3 &y, double reach, ObstacleGap &out) const;
  bool mesh_gap(const Vec3 &y, double reach, ObstacleGap &out) const;
  bool mesh_hit(const Vec3 &y, double bound, MeshHit &out) const;
  void build_pseudo_normals();

  Obstacle m_o;
  TriangleBvh m_bvh;
  std::vector<Vec3> m_tri_normal;
  std::vector<std::array<Vec3, 3>> m_edge_normal; ///< per triangle, its edge k (corner k to k + 1): the edge's pseudo-normal
  std::vector<std::array<char, 3>> m_edge_boundary; ///< the same edge lies on the boundary (one triangle)
  std::vector<Vec3> m_vertex_normal;              ///< per vertex: the angle-weighted pseudo-normal
  std::vector<char> m_vertex_boundary;            ///< per vertex: on a boundary edge
  bool m_open = false;
  double m_depth = std::numeric_limits<double>::infinity();
};

/// Throws std::invalid_argument naming the obstacle when a mesh obstacle faces away from the
/// bodies: among the body points `x` (the candidate vertices) within `reach` of it at `pose`
/// whose closest point is not on its boundary, more face its back than its front. With the
/// bodies' outward unit normals at the points (`normals`, one per point), a point faces the
/// obstacle's front when its normal points against the obstacle's there (so an interference,
/// a point pressed a little behind a surface that faces it, is no evidence against it);
/// without, when it lies in front. Returns whether any such point was found (no verdict
/// otherwise). Planes and spheres pass.
bool check_obstacle_faces(const ObstacleGeometry &o, const std::vector<Vec3> &x, const Pose &pose, double reach, const std::vector<Vec3> &normals = {});

/// The surface that shows an obstacle at its base position: a mesh obstacle's own triangles; a
/// sphere as an icosahedron refined twice (162 vertices) on it; a plane as a square patch of
/// 16 × 16 squares, its centre the projection onto the plane of the centre of the box [lo, hi]
/// (the bodies'), its side 1.5 × the box's diagonal. Triangles face the bodies.
SurfaceMesh obstacle_surface(const Obstacle &o, const Vec3 &lo, const Vec3 &hi);

} // namespace hssbem
