/// \file mesh.hpp
/// Closed triangulated surfaces: reading (.msh 2.2/4.1, .stl, .off, .obj) and validation.
#pragma once

#include "hssbem/core/geometry.hpp"

#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
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

/// The triangles `triangles` of `mesh` (in that order) over their own vertices, numbered in the
/// order of first use; `vertex_of`, if given, receives each one's index in `mesh`. Regions and
/// the source are kept.
SurfaceMesh sub_mesh(const SurfaceMesh &mesh, const std::vector<int> &triangles, std::vector<int> *vertex_of = nullptr);

/// Read a surface mesh; the format is chosen by extension (.msh, .stl, .off, .obj).
/// Throws MeshError naming the file (and line) for a missing, unreadable or malformed file.
SurfaceMesh read_mesh(const std::string &path);

/// The same from the file's bytes (`name` chooses the format by its extension and names the
/// file in messages): what the fuzzers (tests/fuzz/) drive.
SurfaceMesh parse_mesh(const std::string &bytes, const std::string &name);

/// Validate topology and fix orientation: closed (every edge in exactly two triangles),
/// manifold (edges and vertex fans), no degenerate or duplicate triangles, consistent orientation
/// in each connected component, no surface passing through itself or another (find_intersection()
/// of mesh/surface_intersection.hpp: the two triangles are named; nest_surfaces(): surfaces that
/// cross along edges or at vertices, or coincide), outward normals (a component wholly inside another is a cavity and
/// gets normals pointing into it, i.e. out of the solid). Components oriented inward are flipped
/// and a notice is appended to `notices`. Vertices used by no triangle are allowed and reported.
/// Throws MeshError naming the edge, vertex or triangle at fault.
void validate_and_orient(SurfaceMesh &mesh, std::vector<std::string> &notices);

/// The checks of a surface that need not be closed (a rigid contact obstacle): those of
/// validate_and_orient() but closedness, vertex fans, nesting and orientation outward — vertex
/// indices, scale, degenerate and duplicate triangles, no edge shared by more than two
/// triangles, a consistent orientation (every edge two triangles share used once in each
/// direction), no surface passing through itself or another (find_intersection()). Nothing is
/// changed. Returns whether the surface is closed (every edge in two triangles). Throws MeshError
/// naming the edge, vertex or triangle at fault.
bool validate_open_surface(const SurfaceMesh &mesh);

/// Internals shared by the mesh readers (src/bem/mesh*.cpp); not part of the public interface.
namespace detail {

/// Whole file as bytes. Throws MeshError "cannot open mesh file '<path>'".
std::string read_file_bytes(const std::string &path);

/// Walks a text buffer line by line, splitting each line into whitespace-separated tokens, and
/// turns parse failures into MeshError "<path>:<line>: <what>".
class LineReader {
public:
  /// `comment` starts a comment running to the end of the line ('\0': no comments).
  LineReader(const std::string &text, const std::string &path, char comment = '\0');
  /// Advance to the next line; false at the end of the text (tokens() is then empty).
  bool next();
  /// Advance to the next line that has tokens; false at the end of the text.
  bool next_nonblank();
  const std::vector<std::string_view> &tokens() const { return m_tokens; }
  std::string_view token(std::size_t i) const;   ///< fails when the line is shorter
  std::string_view line() const { return m_line; } ///< current line without its comment
  int line_number() const { return m_line_number; }
  const std::string &path() const { return m_path; }
  double real(std::size_t i) const;               ///< token i as a floating-point number
  long long integer(std::size_t i) const;          ///< token i as an integer
  /// Fail unless the line has between `lo` and `hi` tokens; `what` names the record.
  void expect_tokens(std::size_t lo, std::size_t hi, const char *what) const;
  [[noreturn]] void fail(const std::string &what) const;

private:
  std::string_view m_text;
  std::string m_path;
  char m_comment;
  std::size_t m_pos = 0;
  int m_line_number = 0;
  std::string_view m_line;
  std::vector<std::string_view> m_tokens;
};

/// The readers parse the file's bytes; `path` names it in messages.
SurfaceMesh parse_msh(const std::string &text, const std::string &path);  ///< Gmsh ASCII 2.2 / 4.1
SurfaceMesh parse_stl(const std::string &bytes, const std::string &path); ///< ASCII or binary STL
SurfaceMesh parse_off(const std::string &text, const std::string &path);  ///< OFF (polygons fan-triangulated)
SurfaceMesh parse_obj(const std::string &text, const std::string &path);  ///< Wavefront OBJ (v and f records)

} // namespace detail

} // namespace hssbem
