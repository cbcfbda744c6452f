// The obstacle as a problem describes it (obstacle_shape.hpp).
#include "hssbem/mesh/obstacle_shape.hpp"

#include <utility>

namespace hssbem {

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

} // namespace hssbem
