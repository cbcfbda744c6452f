/// \file mesh_read_msh.cpp
/// Gmsh .msh reader, ASCII versions 2.x and 4.1: keeps 3-node triangles (element type 2) and the
/// dimension-2 physical names; every other element type is checked for syntax and dropped.

#include "hssbem/mesh/mesh.hpp"

#include <algorithm>
#include <unordered_map>
#include <utility>

namespace hssbem::detail {
namespace {

constexpr long long k_triangle_type = 2;
/// Counts come from the file: do not let a corrupt one reserve gigabytes up front.
constexpr long long k_max_reserve = 1 << 20;

/// One pass over the sections of a .msh file, in file order.
class MshReader {
public:
  MshReader(const std::string &text, const std::string &path) : m_in(text, path) {}
  SurfaceMesh read();

private:
  void read_format();
  void read_physical_names();
  void read_entities();
  void skip_entity_records(long long count, const char *kind);
  void read_nodes_v2();
  void read_nodes_v41();
  void add_node(long long tag, std::size_t first_coordinate);
  void finish_nodes();
  void read_elements_v2();
  void read_elements_v41();
  void add_triangle(std::size_t first_node, int region_or_entity);
  void check_numeric() const;
  void skip_section(const std::string &header);
  void next_record(const char *section);
  void expect_end(const char *section);
  long long count_line(const char *section, const char *what);
  int vertex_of(long long tag) const;
  void resolve_v41_regions();

  LineReader m_in;
  bool m_v41 = false;
  bool m_have_format = false;
  bool m_have_nodes = false;
  std::vector<std::pair<long long, Vec3>> m_nodes;          ///< (tag, coordinates) as read
  std::unordered_map<long long, int> m_node_index;          ///< node tag -> vertex index
  std::unordered_map<long long, int> m_surface_physical;    ///< 4.1 surface entity -> first tag
  SurfaceMesh m_mesh;
};

SurfaceMesh MshReader::read()
{
  m_mesh.source = m_in.path();
  while (m_in.next_nonblank()) {
    const std::string header(m_in.token(0));
    if (header.front() != '$')
      m_in.fail("expected a section header such as $Nodes, found '" + header + "'");
    if (header == "$MeshFormat")
      read_format();
    else if (!m_have_format)
      m_in.fail("file does not start with $MeshFormat (not a Gmsh .msh file?)");
    else if (header == "$PhysicalNames")
      read_physical_names();
    else if (header == "$Entities" && m_v41)
      read_entities();
    else if (header == "$Nodes")
      m_v41 ? read_nodes_v41() : read_nodes_v2();
    else if (header == "$Elements")
      m_v41 ? read_elements_v41() : read_elements_v2();
    else
      skip_section(header);
  }
  if (!m_have_format)
    m_in.fail("no $MeshFormat section (empty file or not a Gmsh .msh file)");
  if (m_v41)
    resolve_v41_regions();
  return std::move(m_mesh);
}

void MshReader::read_format()
{
  next_record("$MeshFormat");
  m_in.expect_tokens(3, 3, "$MeshFormat");
  const std::string version(m_in.token(0));
  // Checked before anything else: the rest of a binary file is not text.
  if (m_in.integer(1) != 0)
    m_in.fail("binary .msh not supported, save as ASCII (Gmsh option Mesh.Binary = 0)");
  if (version.rfind("2.", 0) == 0)
    m_v41 = false;
  else if (version == "4.1")
    m_v41 = true;
  else
    m_in.fail("unsupported .msh version " + version + " (supported: ASCII 2.2 and 4.1)");
  m_in.integer(2);
  expect_end("MeshFormat");
  m_have_format = true;
}

void MshReader::read_physical_names()
{
  const long long count = count_line("$PhysicalNames", "number of names");
  for (long long i = 0; i < count; ++i) {
    next_record("$PhysicalNames");
    m_in.expect_tokens(3, static_cast<std::size_t>(-1), "physical name");
    const long long dim = m_in.integer(0);
    const long long tag = m_in.integer(1);
    // The name may hold blanks: take the rest of the line, then drop the quotes.
    const std::string_view line = m_in.line();
    std::string_view name = line.substr(static_cast<std::size_t>(m_in.token(2).data() - line.data()));
    name = name.substr(0, name.find_last_not_of(" \t\r") + 1);
    if (name.size() >= 2 && name.front() == '"' && name.back() == '"')
      name = name.substr(1, name.size() - 2);
    if (dim == 2)
      m_mesh.region_tags[std::string(name)] = static_cast<int>(tag);
  }
  expect_end("PhysicalNames");
}

void MshReader::read_entities()
{
  next_record("$Entities");
  m_in.expect_tokens(4, 4, "$Entities counts");
  long long counts[4];
  for (std::size_t i = 0; i < 4; ++i)
    counts[i] = m_in.integer(i);
  skip_entity_records(counts[0], "point entity");
  skip_entity_records(counts[1], "curve entity");
  for (long long i = 0; i < counts[2]; ++i) {
    next_record("$Entities");
    // tag, bounding box (6), number of physical tags, the tags, bounding curves
    m_in.expect_tokens(9, static_cast<std::size_t>(-1), "surface entity");
    check_numeric();
    const long long num_physical = m_in.integer(7);
    m_in.token(8 + static_cast<std::size_t>(std::max(num_physical, 0LL)));
    const int physical = num_physical > 0 ? static_cast<int>(m_in.integer(8)) : -1;
    m_surface_physical[m_in.integer(0)] = physical;
  }
  skip_entity_records(counts[3], "volume entity");
  expect_end("Entities");
}

void MshReader::skip_entity_records(long long count, const char *kind)
{
  for (long long i = 0; i < count; ++i) {
    next_record("$Entities");
    m_in.expect_tokens(5, static_cast<std::size_t>(-1), kind);
    m_in.integer(0);
  }
}

void MshReader::read_nodes_v2()
{
  if (m_have_nodes)
    m_in.fail("second $Nodes section");
  const long long count = count_line("$Nodes", "number of nodes");
  m_nodes.reserve(static_cast<std::size_t>(std::min(count, k_max_reserve)));
  for (long long i = 0; i < count; ++i) {
    next_record("$Nodes");
    m_in.expect_tokens(4, 4, "node");
    add_node(m_in.integer(0), 1);
  }
  expect_end("Nodes");
  finish_nodes();
}

void MshReader::read_nodes_v41()
{
  if (m_have_nodes)
    m_in.fail("second $Nodes section");
  next_record("$Nodes");
  m_in.expect_tokens(4, 4, "$Nodes header");
  const long long num_blocks = m_in.integer(0);
  const long long num_nodes = m_in.integer(1);
  m_nodes.reserve(static_cast<std::size_t>(std::clamp(num_nodes, 0LL, k_max_reserve)));
  std::vector<long long> tags;
  for (long long b = 0; b < num_blocks; ++b) {
    next_record("$Nodes");
    m_in.expect_tokens(4, 4, "node block header");
    const long long dim = m_in.integer(0);
    // Parametric nodes carry one extra coordinate per entity dimension.
    const std::size_t extra = m_in.integer(2) != 0 ? static_cast<std::size_t>(dim) : 0;
    const long long in_block = m_in.integer(3);
    if (in_block < 0 || in_block > num_nodes - static_cast<long long>(m_nodes.size()))
      m_in.fail("node block holds " + std::to_string(in_block) + " nodes, more than the " +
                std::to_string(num_nodes) + " declared in the $Nodes header");
    tags.assign(static_cast<std::size_t>(in_block), 0);
    for (long long &tag : tags) {
      next_record("$Nodes");
      m_in.expect_tokens(1, 1, "node tag");
      tag = m_in.integer(0);
    }
    for (long long tag : tags) {
      next_record("$Nodes");
      m_in.expect_tokens(3 + extra, 3 + extra, "node coordinates");
      add_node(tag, 0);
    }
  }
  if (static_cast<long long>(m_nodes.size()) != num_nodes)
    m_in.fail("$Nodes header declares " + std::to_string(num_nodes) + " nodes but its blocks hold " +
              std::to_string(m_nodes.size()));
  expect_end("Nodes");
  finish_nodes();
}

void MshReader::add_node(long long tag, std::size_t first_coordinate)
{
  if (!m_node_index.emplace(tag, -1).second)
    m_in.fail("node tag " + std::to_string(tag) + " defined twice");
  const Vec3 x{m_in.real(first_coordinate), m_in.real(first_coordinate + 1),
               m_in.real(first_coordinate + 2)};
  m_nodes.emplace_back(tag, x);
}

void MshReader::finish_nodes()
{
  std::sort(m_nodes.begin(), m_nodes.end(),
            [](const auto &a, const auto &b) { return a.first < b.first; });
  m_mesh.vertices.reserve(m_nodes.size());
  for (const auto &[tag, x] : m_nodes) {
    m_node_index[tag] = static_cast<int>(m_mesh.vertices.size());
    m_mesh.vertices.push_back(x);
  }
  m_nodes.clear();
  m_have_nodes = true;
}

void MshReader::read_elements_v2()
{
  if (!m_have_nodes)
    m_in.fail("$Elements before $Nodes");
  const long long count = count_line("$Elements", "number of elements");
  for (long long i = 0; i < count; ++i) {
    next_record("$Elements");
    m_in.expect_tokens(3, static_cast<std::size_t>(-1), "element");
    check_numeric();
    const std::size_t num_tags = static_cast<std::size_t>(std::max(m_in.integer(2), 0LL));
    if (m_in.integer(1) != k_triangle_type) {
      m_in.token(3 + num_tags); // at least one node
      continue;
    }
    m_in.expect_tokens(6 + num_tags, 6 + num_tags, "triangle element");
    // Physical tag 0 is what Gmsh writes for elements outside any physical group.
    const int physical = num_tags > 0 ? static_cast<int>(m_in.integer(3)) : -1;
    add_triangle(3 + num_tags, physical > 0 ? physical : -1);
  }
  expect_end("Elements");
}

void MshReader::read_elements_v41()
{
  if (!m_have_nodes)
    m_in.fail("$Elements before $Nodes");
  next_record("$Elements");
  m_in.expect_tokens(4, 4, "$Elements header");
  const long long num_blocks = m_in.integer(0);
  for (long long b = 0; b < num_blocks; ++b) {
    next_record("$Elements");
    m_in.expect_tokens(4, 4, "element block header");
    const long long dim = m_in.integer(0);
    const long long entity = m_in.integer(1);
    const bool triangles = m_in.integer(2) == k_triangle_type;
    const long long count = m_in.integer(3);
    for (long long i = 0; i < count; ++i) {
      next_record("$Elements");
      if (triangles) {
        m_in.expect_tokens(4, 4, "triangle element");
        // Regions come from $Entities, which may follow; store the entity for now.
        add_triangle(1, dim == 2 ? static_cast<int>(entity) : -1);
      } else {
        m_in.expect_tokens(2, static_cast<std::size_t>(-1), "element");
        check_numeric();
      }
    }
  }
  expect_end("Elements");
}

void MshReader::add_triangle(std::size_t first_node, int region_or_entity)
{
  std::array<int, 3> tri{};
  for (std::size_t k = 0; k < 3; ++k)
    tri[k] = vertex_of(m_in.integer(first_node + k));
  m_mesh.triangles.push_back(tri);
  m_mesh.triangle_region.push_back(region_or_entity);
}

int MshReader::vertex_of(long long tag) const
{
  const auto it = m_node_index.find(tag);
  if (it == m_node_index.end())
    m_in.fail("element " + std::string(m_in.token(0)) + " references unknown node tag " +
              std::to_string(tag));
  return it->second;
}

void MshReader::resolve_v41_regions()
{
  for (int &region : m_mesh.triangle_region) {
    const auto it = m_surface_physical.find(region);
    region = it == m_surface_physical.end() ? -1 : it->second;
  }
}

void MshReader::check_numeric() const
{
  for (std::size_t i = 0; i < m_in.tokens().size(); ++i)
    m_in.real(i);
}

void MshReader::skip_section(const std::string &header)
{
  const std::string end = "$End" + header.substr(1);
  const int start = m_in.line_number();
  while (m_in.next_nonblank())
    if (m_in.token(0) == end)
      return;
  m_in.fail("section " + header + " (line " + std::to_string(start) + ") has no " + end +
            " (file truncated?)");
}

void MshReader::next_record(const char *section)
{
  if (!m_in.next_nonblank())
    m_in.fail(std::string("file truncated inside section ") + section);
  if (m_in.token(0).front() == '$')
    m_in.fail(std::string("section ") + section + " is truncated: found '" +
              std::string(m_in.token(0)) + "' where more data was expected");
}

void MshReader::expect_end(const char *section)
{
  const std::string end = std::string("$End") + section;
  if (!m_in.next_nonblank())
    m_in.fail(std::string("section $") + section + " has no " + end + " (file truncated?)");
  if (m_in.tokens().size() != 1 || m_in.token(0) != end)
    m_in.fail("expected " + end + ", found '" + std::string(m_in.line()) + "'");
}

long long MshReader::count_line(const char *section, const char *what)
{
  next_record(section);
  m_in.expect_tokens(1, 1, what);
  const long long count = m_in.integer(0);
  if (count < 0)
    m_in.fail(std::string("negative ") + what);
  return count;
}

} // namespace

SurfaceMesh parse_msh(const std::string &text, const std::string &path) { return MshReader(text, path).read(); }

} // namespace hssbem::detail
