/// \file mesh.hpp
/// Closed triangulated surfaces: reading (.msh 2.2/4.1, .stl, .off, .obj) and validation.
#pragma once

#include "hssbem/bem/geometry.hpp"

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace hssbem {

/// Any problem with a mesh file or its topology. The message names the file and, where it
/// applies, the line, triangle or vertex at fault.
class MeshError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

/// A triangulated surface in file order. Vertex indices are 0-based in file order (for .msh: by
/// ascending node tag). Regions are Gmsh physical groups of the triangles.
struct SurfaceMesh {
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> triangles;
  std::vector<int> triangle_region;         ///< physical tag per triangle, -1 when none
  std::map<std::string, int> region_tags;   ///< physical name -> tag (names known to the file)
  std::string source;                       ///< file the mesh came from (for messages)

  int num_vertices() const { return static_cast<int>(vertices.size()); }
  int num_triangles() const { return static_cast<int>(triangles.size()); }
  Vec3 triangle_normal(int t) const;        ///< unit normal from the vertex order (right hand)
  double triangle_area(int t) const;
};

/// Read a surface mesh; the format is chosen by extension (.msh, .stl, .off, .obj).
/// Throws MeshError naming the file (and line) for a missing, unreadable or malformed file.
SurfaceMesh read_mesh(const std::string &path);

/// Validate topology and fix orientation: closed (every edge in exactly two triangles),
/// manifold (edges and vertex fans), no degenerate or duplicate triangles, consistent orientation
/// in each connected component, outward normals (a component nested inside another is a cavity and
/// gets normals pointing into it, i.e. out of the solid). Components oriented inward are flipped
/// and a notice is appended to `notices`. Vertices used by no triangle are allowed and reported.
/// Throws MeshError naming the edge, vertex or triangle at fault.
void validate_and_orient(SurfaceMesh &mesh, std::vector<std::string> &notices);

} // namespace hssbem
