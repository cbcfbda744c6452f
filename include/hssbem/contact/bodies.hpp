/// \file bodies.hpp
/// The deformable bodies of one mesh: its separate closed surfaces, a surface nested inside
/// another bounding a cavity of that body rather than a body of its own.
#pragma once

#include "hssbem/bem/discretization.hpp"
#include "hssbem/mesh/mesh.hpp"

#include <vector>

namespace hssbem {

struct Bodies {
  int count = 0;
  std::vector<int> of_vertex;   ///< body of each vertex (-1: used by no triangle)
  std::vector<int> of_triangle; ///< body of each triangle
};

/// The bodies of a validated (closed, oriented) mesh, numbered in the order of their lowest
/// vertex index. A connected surface inside an odd number of others (all of it: nest_surfaces)
/// is a cavity: it belongs to the body whose outer surface immediately contains it.
Bodies find_bodies(const SurfaceMesh &mesh);

/// The body of every dof node, or empty when the mesh is one body: what a reference
/// factorization takes to keep separate bodies separate (DenseReferenceOptions::node_body).
std::vector<int> node_bodies(const Discretization &disc);

} // namespace hssbem
