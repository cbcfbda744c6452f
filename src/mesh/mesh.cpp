/// \file mesh.cpp
/// SurfaceMesh geometry, format dispatch and the line reader shared by the text formats.

#include "hssbem/mesh/mesh.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace hssbem {

Vec3 SurfaceMesh::triangle_normal(int t) const
{
  const auto &tri = triangles.at(static_cast<std::size_t>(t));
  const Vec3 &a = vertices[tri[0]];
  return normalized(cross(vertices[tri[1]] - a, vertices[tri[2]] - a));
}

double SurfaceMesh::triangle_area(int t) const
{
  const auto &tri = triangles.at(static_cast<std::size_t>(t));
  const Vec3 &a = vertices[tri[0]];
  return 0.5 * norm(cross(vertices[tri[1]] - a, vertices[tri[2]] - a));
}

SurfaceMesh sub_mesh(const SurfaceMesh &mesh, const std::vector<int> &triangles, std::vector<int> *vertex_of)
{
  SurfaceMesh out;
  out.source = mesh.source, out.region_tags = mesh.region_tags;
  std::vector<int> local(mesh.vertices.size(), -1), used;
  for (int t : triangles) {
    std::array<int, 3> tri{};
    for (int c = 0; c < 3; ++c) {
      int &l = local[mesh.triangles[t][c]];
      if (l < 0) l = static_cast<int>(used.size()), used.push_back(mesh.triangles[t][c]);
      tri[c] = l;
    }
    out.triangles.push_back(tri);
    out.triangle_region.push_back(mesh.triangle_region.empty() ? -1 : mesh.triangle_region[t]);
  }
  for (int v : used) out.vertices.push_back(mesh.vertices[v]);
  if (vertex_of) *vertex_of = std::move(used);
  return out;
}

namespace {

std::string lower_extension(const std::string &path)
{
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

} // namespace

namespace {

/// The parser of a format, chosen by extension; throws MeshError for an unknown one.
SurfaceMesh (*parser_for(const std::string &path))(const std::string &, const std::string &)
{
  const std::string ext = lower_extension(path);
  if (ext == ".msh")
    return detail::parse_msh;
  if (ext == ".stl")
    return detail::parse_stl;
  if (ext == ".off")
    return detail::parse_off;
  if (ext == ".obj")
    return detail::parse_obj;
  const std::string what = ext.empty() ? "has no extension" : "has unknown extension '" + ext + "'";
  throw MeshError("mesh file '" + path + "' " + what +
                  " (supported formats: .msh (Gmsh ASCII 2.2/4.1), .stl, .off, .obj)");
}

} // namespace

SurfaceMesh read_mesh(const std::string &path)
{
  const auto parse = parser_for(path);
  return parse(detail::read_file_bytes(path), path);
}

SurfaceMesh parse_mesh(const std::string &bytes, const std::string &name)
{
  return parser_for(name)(bytes, name);
}

namespace detail {

std::string read_file_bytes(const std::string &path)
{
  std::error_code ec;
  // An ifstream on a directory opens fine on Linux and only fails on read; say so up front.
  if (std::filesystem::is_directory(path, ec))
    throw MeshError("cannot open mesh file '" + path + "': it is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw MeshError("cannot open mesh file '" + path + "': " + std::strerror(errno));
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad())
    throw MeshError("cannot open mesh file '" + path + "': read error");
  return std::move(buffer).str();
}

LineReader::LineReader(const std::string &text, const std::string &path, char comment)
    : m_text(text), m_path(path), m_comment(comment)
{
}

bool LineReader::next()
{
  m_tokens.clear();
  m_line = {};
  if (m_pos >= m_text.size())
    return false;
  std::size_t end = m_text.find('\n', m_pos);
  if (end == std::string_view::npos)
    end = m_text.size();
  m_line = m_text.substr(m_pos, end - m_pos);
  if (!m_line.empty() && m_line.back() == '\r') // files written on Windows
    m_line.remove_suffix(1);
  m_pos = end + 1;
  ++m_line_number;
  if (m_comment != '\0')
    m_line = m_line.substr(0, m_line.find(m_comment));
  for (std::size_t i = 0; i < m_line.size();) {
    while (i < m_line.size() && is_space(m_line[i]))
      ++i;
    const std::size_t start = i;
    while (i < m_line.size() && !is_space(m_line[i]))
      ++i;
    if (i > start)
      m_tokens.push_back(m_line.substr(start, i - start));
  }
  return true;
}

bool LineReader::next_nonblank()
{
  while (next())
    if (!m_tokens.empty())
      return true;
  return false;
}

std::string_view LineReader::token(std::size_t i) const
{
  if (i >= m_tokens.size())
    fail("expected at least " + std::to_string(i + 1) + " values, found " +
         std::to_string(m_tokens.size()));
  return m_tokens[i];
}

double LineReader::real(std::size_t i) const
{
  const std::string_view tok = token(i);
  // from_chars rejects a leading '+', which some writers emit.
  const std::size_t skip = (tok.size() > 1 && tok[0] == '+') ? 1 : 0;
  double value = 0.0;
  const auto res = std::from_chars(tok.data() + skip, tok.data() + tok.size(), value);
  if (res.ec != std::errc() || res.ptr != tok.data() + tok.size())
    fail("expected a number, found '" + std::string(tok) + "'");
  if (!std::isfinite(value))
    fail("expected a finite number, found '" + std::string(tok) + "'");
  return value;
}

long long LineReader::integer(std::size_t i) const
{
  const std::string_view tok = token(i);
  const std::size_t skip = (tok.size() > 1 && tok[0] == '+') ? 1 : 0;
  long long value = 0;
  const auto res = std::from_chars(tok.data() + skip, tok.data() + tok.size(), value);
  if (res.ec != std::errc() || res.ptr != tok.data() + tok.size())
    fail("expected an integer, found '" + std::string(tok) + "'");
  return value;
}

void LineReader::expect_tokens(std::size_t lo, std::size_t hi, const char *what) const
{
  const std::size_t n = m_tokens.size();
  if (n >= lo && n <= hi)
    return;
  std::string expected = std::to_string(lo);
  if (hi != lo)
    expected += hi == static_cast<std::size_t>(-1) ? " or more" : " to " + std::to_string(hi);
  fail(std::string(what) + ": expected " + expected + " values, found " + std::to_string(n));
}

void LineReader::fail(const std::string &what) const
{
  throw MeshError(m_path + ":" + std::to_string(m_line_number) + ": " + what);
}

} // namespace detail
} // namespace hssbem
