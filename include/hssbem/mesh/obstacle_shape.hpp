/// \file obstacle_shape.hpp
/// A rigid obstacle as a problem describes it: a name, a shape (a plane, a sphere, or a rigid
/// triangulated surface, open or closed), its friction. One type from the problem file to the
/// contact solver: the problem file's parser fills it (a mesh obstacle's file path, its triangles
/// once the set-up has read them), the library's users make it with the factories below, and
/// the contact engine places and queries it (contact/obstacle.hpp: ObstacleGeometry). A new
/// shape is a case here, its reading in problem/problem_file.cpp and its geometry in
/// contact/obstacle.cpp (CONTRIBUTING.md, "A new obstacle shape").
#pragma once

#include "hssbem/mesh/mesh.hpp"

#include <array>
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
  std::string mesh_path;                   ///< mesh: the file it is read from (a problem file's; empty when made in memory)
  double friction = std::numeric_limits<double>::quiet_NaN(); ///< Coulomb coefficient of this obstacle (NaN: the global one)

  static Obstacle plane(std::string name, const Vec3 &point, const Vec3 &normal);
  static Obstacle sphere(std::string name, const Vec3 &center, double radius);
  /// A rigid mesh obstacle from a surface mesh (e.g. read_mesh()); it need not be closed.
  static Obstacle mesh(std::string name, const SurfaceMesh &mesh);
};

} // namespace hssbem
