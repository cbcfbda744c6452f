/// \file mesh_read_simple.cpp
/// Readers for the region-less formats: STL (ASCII and binary), OFF and Wavefront OBJ.

#include "hssbem/mesh/mesh.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <unordered_map>

namespace hssbem::detail {
namespace {

/// STL stores every facet with its own copies of the corners: give equal points one index,
/// numbered in order of first appearance.
class VertexMerger {
public:
  explicit VertexMerger(SurfaceMesh &mesh) : m_mesh(mesh) {}

  int index_of(const Vec3 &x)
  {
    Key key;
    for (std::size_t i = 0; i < 3; ++i) {
      const double c = x[i] + 0.0; // -0.0 becomes +0.0: the two are equal coordinates
      std::memcpy(&key[i], &c, sizeof c);
    }
    const auto [it, inserted] = m_index.emplace(key, m_mesh.num_vertices());
    if (inserted)
      m_mesh.vertices.push_back(x);
    return it->second;
  }

private:
  using Key = std::array<std::uint64_t, 3>;
  struct KeyHash {
    std::size_t operator()(const Key &k) const
    {
      std::uint64_t h = k[0];
      h = (h ^ (h >> 29)) * 0xbf58476d1ce4e5b9ULL + k[1];
      h = (h ^ (h >> 31)) * 0x94d049bb133111ebULL + k[2];
      return static_cast<std::size_t>(h ^ (h >> 32));
    }
  };
  std::unordered_map<Key, int, KeyHash> m_index;
  SurfaceMesh &m_mesh;
};

void add_triangle(SurfaceMesh &mesh, int a, int b, int c)
{
  mesh.triangles.push_back({a, b, c});
  mesh.triangle_region.push_back(-1);
}

/// Polygons become fans around their first corner, which keeps the polygon's orientation.
void add_polygon(SurfaceMesh &mesh, const std::vector<int> &corners)
{
  for (std::size_t k = 1; k + 1 < corners.size(); ++k)
    add_triangle(mesh, corners[0], corners[k], corners[k + 1]);
}

std::string lower(std::string_view s)
{
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

// ---------------------------------------------------------------------------------------- STL

constexpr std::size_t k_stl_header = 84; ///< 80-byte comment plus the 32-bit facet count
constexpr std::size_t k_stl_facet = 50;  ///< normal, 3 corners (12 floats) and a 16-bit attribute

std::uint32_t little_u32(const char *p)
{
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i)
    v = (v << 8) | static_cast<unsigned char>(p[i]);
  return v;
}

float little_float(const char *p)
{
  const std::uint32_t bits = little_u32(p);
  float f = 0.0f;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}

bool sized_as_binary_stl(const std::string &bytes)
{
  if (bytes.size() < k_stl_header)
    return false;
  const std::uint64_t count = little_u32(bytes.data() + 80);
  return bytes.size() == k_stl_header + k_stl_facet * count;
}

bool starts_with_solid(const std::string &bytes)
{
  const std::size_t first = bytes.find_first_not_of(" \t\r\n");
  return first != std::string::npos && lower(bytes.substr(first, 5)) == "solid";
}

SurfaceMesh read_binary_stl(const std::string &bytes, const std::string &path)
{
  SurfaceMesh mesh;
  mesh.source = path;
  VertexMerger merger(mesh);
  const std::uint32_t count = little_u32(bytes.data() + 80);
  for (std::uint32_t f = 0; f < count; ++f) {
    const char *facet = bytes.data() + k_stl_header + k_stl_facet * f;
    int corner[3];
    for (int k = 0; k < 3; ++k) {
      const char *p = facet + 12 * (k + 1); // skip the stored normal
      const Vec3 x{little_float(p), little_float(p + 4), little_float(p + 8)};
      if (!std::isfinite(x[0]) || !std::isfinite(x[1]) || !std::isfinite(x[2]))
        throw MeshError(path + ": binary STL facet " + std::to_string(f) +
                        " has a non-finite coordinate");
      corner[k] = merger.index_of(x);
    }
    add_triangle(mesh, corner[0], corner[1], corner[2]);
  }
  return mesh;
}

/// Where an ASCII STL parser stands between keywords.
enum class StlState { outside, solid, facet, loop };

/// Parses ASCII STL keyword by keyword; facets must hold exactly three vertices.
class AsciiStlReader {
public:
  AsciiStlReader(const std::string &text, const std::string &path) : m_in(text, path), m_merger(m_mesh)
  {
    m_mesh.source = path;
  }

  SurfaceMesh read()
  {
    while (m_in.next_nonblank())
      keyword(lower(m_in.token(0)));
    if (m_state != StlState::outside)
      m_in.fail("file truncated: missing endsolid");
    return std::move(m_mesh);
  }

private:
  void keyword(const std::string &kw)
  {
    if (kw == "solid")
      enter(StlState::outside, StlState::solid, "solid");
    else if (kw == "facet")
      facet();
    else if (kw == "outer")
      enter(StlState::facet, StlState::loop, "outer loop");
    else if (kw == "vertex")
      vertex();
    else if (kw == "endloop")
      enter(StlState::loop, StlState::facet, "endloop");
    else if (kw == "endfacet")
      end_facet();
    else if (kw == "endsolid")
      enter(StlState::solid, StlState::outside, "endsolid");
    else
      m_in.fail("unexpected '" + std::string(m_in.token(0)) + "' in ASCII STL");
  }

  void enter(StlState from, StlState to, const char *what)
  {
    if (m_state != from)
      m_in.fail(std::string("misplaced '") + what + "' in ASCII STL");
    m_state = to;
  }

  void facet()
  {
    enter(StlState::solid, StlState::facet, "facet");
    // The stored normal is not read: orientation comes from the corner order, and exporters
    // write "nan" normals for slivers, which would otherwise reject a usable file.
    m_count = 0;
  }

  void vertex()
  {
    if (m_state != StlState::loop)
      m_in.fail("'vertex' outside 'outer loop' in ASCII STL");
    m_in.expect_tokens(4, 4, "vertex");
    if (m_count == 3)
      m_in.fail("facet with more than 3 vertices");
    m_corner[m_count++] = m_merger.index_of({m_in.real(1), m_in.real(2), m_in.real(3)});
  }

  void end_facet()
  {
    enter(StlState::facet, StlState::solid, "endfacet");
    if (m_count != 3)
      m_in.fail("facet with " + std::to_string(m_count) + " vertices (expected 3)");
    add_triangle(m_mesh, m_corner[0], m_corner[1], m_corner[2]);
  }

  SurfaceMesh m_mesh;
  LineReader m_in;
  VertexMerger m_merger;
  StlState m_state = StlState::outside;
  int m_corner[3] = {0, 0, 0};
  int m_count = 0;
};

// ---------------------------------------------------------------------------------------- OFF

/// Reads the header line ("OFF", optionally followed by the counts) and the counts.
std::array<long long, 2> read_off_counts(LineReader &in)
{
  if (!in.next_nonblank())
    in.fail("empty file (expected the OFF header)");
  const std::string header(in.token(0));
  if (header != "OFF" && header != "COFF" && header != "NOFF" && header != "CNOFF")
    in.fail("expected the header OFF, found '" + header + "'");
  std::size_t first = 1;
  if (in.tokens().size() == 1) {
    if (!in.next_nonblank())
      in.fail("file truncated: missing vertex and face counts");
    first = 0;
  }
  in.expect_tokens(first + 2, first + 3, "OFF counts (vertices faces [edges])");
  const std::array<long long, 2> counts{in.integer(first), in.integer(first + 1)};
  if (counts[0] < 0 || counts[1] < 0)
    in.fail("negative vertex or face count");
  return counts;
}

void read_off_face(LineReader &in, SurfaceMesh &mesh, std::vector<int> &corners)
{
  const long long n = in.integer(0);
  if (n < 3)
    in.fail("face with " + std::to_string(n) + " vertices (at least 3 needed)");
  in.token(static_cast<std::size_t>(n)); // all indices present; more tokens are a colour
  corners.clear();
  for (std::size_t k = 1; k <= static_cast<std::size_t>(n); ++k) {
    const long long v = in.integer(k);
    if (v < 0 || v >= mesh.num_vertices())
      in.fail("face refers to vertex " + std::to_string(v) + ", but the file has " +
              std::to_string(mesh.num_vertices()) + " vertices");
    corners.push_back(static_cast<int>(v));
  }
  add_polygon(mesh, corners);
}

// ---------------------------------------------------------------------------------------- OBJ

/// One corner of an OBJ face ("a", "a/b", "a//c", "a/b/c"), as a 0-based vertex index.
int obj_corner(LineReader &in, std::size_t i, int num_vertices)
{
  const std::string_view tok = in.token(i);
  const std::string_view index_text = tok.substr(0, tok.find('/'));
  long long v = 0;
  const auto res = std::from_chars(index_text.data(), index_text.data() + index_text.size(), v);
  if (index_text.empty() || res.ec != std::errc() || res.ptr != index_text.data() + index_text.size())
    in.fail("bad face vertex '" + std::string(tok) + "'");
  if (v == 0)
    in.fail("face vertex index 0 (OBJ indices start at 1)");
  // Negative indices count back from the last vertex defined so far.
  const long long index = v > 0 ? v - 1 : num_vertices + v;
  if (index < 0 || index >= num_vertices)
    in.fail("face refers to vertex " + std::to_string(v) + ", but only " +
            std::to_string(num_vertices) + " vertices are defined so far");
  return static_cast<int>(index);
}

} // namespace

SurfaceMesh parse_stl(const std::string &bytes, const std::string &path)
{
  // Binary files may also begin with "solid", so the exact binary size decides first.
  if (sized_as_binary_stl(bytes))
    return read_binary_stl(bytes, path);
  if (starts_with_solid(bytes))
    return AsciiStlReader(bytes, path).read();
  if (bytes.size() < k_stl_header)
    throw MeshError(path + ": not an STL file (no 'solid' header and shorter than a binary STL header)");
  const std::uint64_t count = little_u32(bytes.data() + 80);
  throw MeshError(path + ": binary STL header declares " + std::to_string(count) + " triangles (" +
                  std::to_string(k_stl_header + k_stl_facet * count) + " bytes) but the file has " +
                  std::to_string(bytes.size()) + " bytes (truncated or not an STL file)");
}

SurfaceMesh parse_off(const std::string &text, const std::string &path)
{
  LineReader in(text, path, '#');
  SurfaceMesh mesh;
  mesh.source = path;
  const auto [num_vertices, num_faces] = read_off_counts(in);
  for (long long i = 0; i < num_vertices; ++i) {
    if (!in.next_nonblank())
      in.fail("file truncated: " + std::to_string(i) + " of " + std::to_string(num_vertices) +
              " vertices read");
    in.expect_tokens(3, static_cast<std::size_t>(-1), "vertex");
    mesh.vertices.push_back({in.real(0), in.real(1), in.real(2)});
  }
  std::vector<int> corners;
  for (long long i = 0; i < num_faces; ++i) {
    if (!in.next_nonblank())
      in.fail("file truncated: " + std::to_string(i) + " of " + std::to_string(num_faces) +
              " faces read");
    read_off_face(in, mesh, corners);
  }
  return mesh;
}

SurfaceMesh parse_obj(const std::string &text, const std::string &path)
{
  LineReader in(text, path, '#');
  SurfaceMesh mesh;
  mesh.source = path;
  std::vector<int> corners;
  while (in.next_nonblank()) {
    const std::string_view kw = in.token(0);
    if (kw == "v") {
      in.expect_tokens(4, static_cast<std::size_t>(-1), "vertex");
      mesh.vertices.push_back({in.real(1), in.real(2), in.real(3)});
    } else if (kw == "f") {
      in.expect_tokens(4, static_cast<std::size_t>(-1), "face (at least 3 vertices)");
      corners.clear();
      for (std::size_t i = 1; i < in.tokens().size(); ++i)
        corners.push_back(obj_corner(in, i, mesh.num_vertices()));
      add_polygon(mesh, corners);
    }
  }
  return mesh;
}

} // namespace hssbem::detail
