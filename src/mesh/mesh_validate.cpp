/// \file mesh_validate.cpp
/// Topology checks of a closed triangulated surface and outward orientation of its components.

#include "hssbem/mesh/mesh.hpp"
#include "hssbem/mesh/surface_intersection.hpp"


#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <sstream>
#include <unordered_map>

namespace hssbem {
namespace {

/// Relative size below which an area (times diag^2) or a volume (times diag^3) counts as zero.
constexpr double k_degenerate = 1e-12;
/// The sizes (bounding-box diagonals) a mesh may have: physical bodies from nanometres to planets
/// in any unit lie far inside, and the sixth power of either bound is a normal double.
constexpr double k_min_extent = 1e-30, k_max_extent = 1e30;
/// Significant digits that the coordinates must keep of the shortest edge (UTM coordinates of
/// about 1e6 m with millimetre edges keep 6.6).
constexpr double k_min_digits = 5;

/// Undirected edge as one 64-bit key: lower index in the high half.
std::uint64_t edge_key(int a, int b)
{
  const auto lo = static_cast<std::uint64_t>(static_cast<std::uint32_t>(std::min(a, b)));
  const auto hi = static_cast<std::uint64_t>(static_cast<std::uint32_t>(std::max(a, b)));
  return (lo << 32) | hi;
}

/// The triangles using one undirected edge; the first two are kept, the rest only counted.
struct EdgeUse {
  int count = 0;
  int tri[2] = {-1, -1};
  bool ascending[2] = {false, false}; ///< traversed from the lower to the higher vertex index
};

struct TripleHash {
  std::size_t operator()(const std::array<int, 3> &k) const
  {
    std::uint64_t h = static_cast<std::uint32_t>(k[0]);
    h = h * 0x9e3779b97f4a7c15ULL + static_cast<std::uint32_t>(k[1]);
    h = (h ^ (h >> 29)) * 0xbf58476d1ce4e5b9ULL + static_cast<std::uint32_t>(k[2]);
    return static_cast<std::size_t>(h ^ (h >> 32));
  }
};


std::string triple(const std::array<int, 3> &t)
{
  return "(" + std::to_string(t[0]) + ", " + std::to_string(t[1]) + ", " + std::to_string(t[2]) + ")";
}

std::string edge_text(int a, int b) { return "(" + std::to_string(a) + ", " + std::to_string(b) + ")"; }

/// Runs the checks in order; each throws at the first fault it finds, in triangle order.
class MeshValidator {
public:
  MeshValidator(SurfaceMesh &mesh, std::vector<std::string> &notices)
      : m_mesh(mesh), m_notices(notices)
  {
  }

  void run()
  {
    check_triangles_and_edges();
    check_open_edges();
    check_vertex_fans();
    check_orientation();
    find_components();
    check_intersections();
    check_nesting();
    orient_components();
    report_unused_vertices();
  }

  /// The checks of a surface that need not be closed; returns whether it is.
  bool run_open()
  {
    check_triangles_and_edges();
    check_orientation();
    find_components();
    check_intersections();
    return std::all_of(m_edges.begin(), m_edges.end(), [](const auto &e) { return e.second.count == 2; });
  }

private:
  /// The checks every surface takes, closed or not, up to its edges (none of more than two triangles).
  void check_triangles_and_edges()
  {
    check_indices();
    check_scale();
    check_degenerate();
    check_duplicates();
    build_edges();
    check_non_manifold_edges();
  }

  [[noreturn]] void fail(const std::string &what) const
  {
    throw MeshError("mesh '" + m_mesh.source + "': " + what);
  }
  void notice(const std::string &what) { m_notices.push_back("mesh '" + m_mesh.source + "': " + what); }

  const EdgeUse &edge(int a, int b) const { return m_edges.find(edge_key(a, b))->second; }
  int other_triangle(int a, int b, int t) const
  {
    const EdgeUse &e = edge(a, b);
    return e.tri[0] == t ? e.tri[1] : e.tri[0];
  }
  const Vec3 &corner(int t, int k) const { return m_mesh.vertices[m_mesh.triangles[t][k]]; }

  void check_indices();
  void check_scale();
  void check_degenerate();
  void check_duplicates();
  void build_edges();
  void check_non_manifold_edges();
  void check_open_edges();
  void check_vertex_fans();
  int fan_size(int v, int start) const;
  void check_orientation();
  void find_components();
  void check_intersections();
  void check_nesting();
  std::string sample_text(const SurfaceSample &s) const;
  void orient_components();
  double signed_volume(int c, const Vec3 &origin) const;
  int nesting_depth(int c) const;
  void report_unused_vertices();

  SurfaceMesh &m_mesh;
  std::vector<std::string> &m_notices;
  std::unordered_map<std::uint64_t, EdgeUse> m_edges;
  std::vector<int> m_degree;                 ///< triangles per vertex
  std::vector<int> m_first_triangle;         ///< some triangle of each vertex, -1 if unused
  std::vector<std::vector<int>> m_components; ///< triangles of each component
  std::vector<int> m_component_of;            ///< component of each triangle
  std::vector<Box> m_component_box;
  std::vector<std::vector<char>> m_inside; ///< m_inside[c][d]: component c lies inside component d
};

void MeshValidator::check_indices()
{
  const int n = m_mesh.num_vertices();
  if (m_mesh.triangles.empty())
    fail("no triangles (a surface mesh needs at least one closed triangulated surface)");
  for (int t = 0; t < m_mesh.num_triangles(); ++t) {
    const auto &tri = m_mesh.triangles[t];
    for (int v : tri)
      if (v < 0 || v >= n)
        fail("triangle " + std::to_string(t) + " " + triple(tri) + " references vertex " +
             std::to_string(v) + ", but the mesh has " + std::to_string(n) + " vertices");
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2])
      fail("triangle " + std::to_string(t) + " " + triple(tri) + " has a repeated vertex");
  }
}

/// Coordinates the solver can compute with: the kernels raise distances to powers up to about 6
/// and the quadrature multiplies areas by them, so a size far from 1 overflows or underflows
/// double precision (a sphere of radius 1e120 gave NaN entries); and coordinates far from the
/// origin beside the triangles' size keep too few digits of their shape (shifted by 1e15, a
/// sphere of edges 0.06 kept none, and gave NaN entries too). Refused with the cure.
void MeshValidator::check_scale()
{
  Box    box;
  double largest = 0, edges = 0;
  for (const auto &tri : m_mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const Vec3 &x = m_mesh.vertices[tri[k]];
      box.add(x);
      largest = std::max({largest, std::abs(x[0]), std::abs(x[1]), std::abs(x[2])});
      edges += norm(m_mesh.vertices[tri[(k + 1) % 3]] - x);
    }
  std::ostringstream msg;
  const double       diag = box.diagonal();
  if (!(diag >= k_min_extent && diag <= k_max_extent)) {
    msg << "its size (bounding-box diagonal " << diag << ") lies outside [" << k_min_extent << ", " << k_max_extent
        << "], where the kernels' powers of distances overflow or underflow double precision; rescale the coordinates (another length unit)";
    fail(msg.str());
  }
  // The mean edge, not the shortest: a single tiny edge is the degenerate check's to name.
  const double mean_edge = edges / (3.0 * static_cast<double>(m_mesh.triangles.size()));
  const double digits    = std::log10(mean_edge / (largest * std::numeric_limits<double>::epsilon()));
  if (digits < k_min_digits) {
    msg.precision(2);
    msg << "the coordinates (up to " << largest << " from the origin) keep only " << std::max(digits, 0.0) << " significant digits of the mean edge length (" << mean_edge
        << "), fewer than " << k_min_digits << ": the triangles' shape is lost to rounding (precision); translate the mesh near the origin";
    fail(msg.str());
  }
}

void MeshValidator::check_degenerate()
{
  Box box;
  for (const auto &tri : m_mesh.triangles)
    for (int v : tri)
      box.add(m_mesh.vertices[v]);
  const double threshold = k_degenerate * box.diagonal() * box.diagonal();
  for (int t = 0; t < m_mesh.num_triangles(); ++t) {
    const double area = m_mesh.triangle_area(t);
    if (area <= threshold) {
      std::ostringstream msg;
      msg << "degenerate triangle " << t << " " << triple(m_mesh.triangles[t]) << ": area " << area
          << " is at most 1e-12 x (bounding-box diagonal)^2 = " << threshold;
      fail(msg.str());
    }
  }
}

void MeshValidator::check_duplicates()
{
  std::unordered_map<std::array<int, 3>, int, TripleHash> seen;
  seen.reserve(m_mesh.triangles.size());
  for (int t = 0; t < m_mesh.num_triangles(); ++t) {
    std::array<int, 3> key = m_mesh.triangles[t];
    std::sort(key.begin(), key.end());
    const auto [it, inserted] = seen.emplace(key, t);
    if (!inserted)
      fail("duplicate triangle: triangles " + std::to_string(it->second) + " and " +
           std::to_string(t) + " have the same vertices " + triple(key));
  }
}

void MeshValidator::build_edges()
{
  m_edges.reserve(m_mesh.triangles.size() * 3 / 2 + 1);
  m_degree.assign(m_mesh.vertices.size(), 0);
  m_first_triangle.assign(m_mesh.vertices.size(), -1);
  for (int t = 0; t < m_mesh.num_triangles(); ++t) {
    const auto &tri = m_mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const int a = tri[k], b = tri[(k + 1) % 3];
      EdgeUse &e = m_edges[edge_key(a, b)];
      if (e.count < 2) {
        e.tri[e.count] = t;
        e.ascending[e.count] = a < b;
      }
      ++e.count;
      if (m_first_triangle[a] < 0)
        m_first_triangle[a] = t;
      ++m_degree[a];
    }
  }
}

void MeshValidator::check_non_manifold_edges()
{
  for (int t = 0; t < m_mesh.num_triangles(); ++t) {
    const auto &tri = m_mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const int a = std::min(tri[k], tri[(k + 1) % 3]), b = std::max(tri[k], tri[(k + 1) % 3]);
      const EdgeUse &e = edge(a, b);
      if (e.count <= 2)
        continue;
      std::string users;
      for (int s = 0; s < m_mesh.num_triangles(); ++s) {
        const auto &o = m_mesh.triangles[s];
        if (std::count(o.begin(), o.end(), a) + std::count(o.begin(), o.end(), b) == 2)
          users += (users.empty() ? "" : ", ") + std::to_string(s);
      }
      fail("non-manifold edge " + edge_text(a, b) + " is shared by " + std::to_string(e.count) +
           " triangles (" + users + ")");
    }
  }
}

void MeshValidator::check_open_edges()
{
  for (int t = 0; t < m_mesh.num_triangles(); ++t) {
    const auto &tri = m_mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const int a = std::min(tri[k], tri[(k + 1) % 3]), b = std::max(tri[k], tri[(k + 1) % 3]);
      if (edge(a, b).count == 1)
        fail("open surface: edge " + edge_text(a, b) + " belongs to only one triangle (" +
             std::to_string(t) + ")");
    }
  }
}

void MeshValidator::check_vertex_fans()
{
  for (int v = 0; v < m_mesh.num_vertices(); ++v) {
    if (m_first_triangle[v] < 0)
      continue;
    const int size = fan_size(v, m_first_triangle[v]);
    if (size != m_degree[v])
      fail("non-manifold vertex " + std::to_string(v) + ": its " + std::to_string(m_degree[v]) +
           " triangles form more than one fan (the fan through triangle " +
           std::to_string(m_first_triangle[v]) + " holds " + std::to_string(size) +
           "), e.g. two surfaces touching at a point");
  }
}

/// Number of triangles met walking around v from `start` across the edges at v, back to `start`.
/// Every edge is shared by exactly two triangles here, so the walk closes.
int MeshValidator::fan_size(int v, int start) const
{
  int t = start;
  int entry = -1; // the vertex of t on the edge we came in through
  int size = 0;
  do {
    const auto &tri = m_mesh.triangles[t];
    int exit = -1;
    for (int w : tri)
      if (w != v && w != entry && exit < 0)
        exit = w;
    t = other_triangle(v, exit, t);
    entry = exit;
    ++size;
  } while (t != start && size <= m_degree[v]);
  return size;
}

void MeshValidator::check_orientation()
{
  for (int t = 0; t < m_mesh.num_triangles(); ++t) {
    const auto &tri = m_mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const int a = tri[k], b = tri[(k + 1) % 3];
      const EdgeUse &e = edge(a, b);
      if (e.count == 2 && e.ascending[0] == e.ascending[1]) // an open edge (count 1) has one use
        fail("inconsistent orientation: triangles " + std::to_string(e.tri[0]) + " and " +
             std::to_string(e.tri[1]) + " both traverse edge " + edge_text(a, b) +
             " in the same direction (reorder the vertices of one of them)");
    }
  }
}

void MeshValidator::find_components()
{
  std::vector<int> &component = m_component_of;
  component.assign(m_mesh.triangles.size(), -1);
  std::vector<int> stack;
  for (int seed = 0; seed < m_mesh.num_triangles(); ++seed) {
    if (component[seed] >= 0)
      continue;
    const int c = static_cast<int>(m_components.size());
    m_components.emplace_back();
    m_component_box.emplace_back();
    component[seed] = c;
    stack.assign(1, seed);
    while (!stack.empty()) {
      const int t = stack.back();
      stack.pop_back();
      m_components[c].push_back(t);
      const auto &tri = m_mesh.triangles[t];
      for (int k = 0; k < 3; ++k) {
        m_component_box[c].add(m_mesh.vertices[tri[k]]);
        const int s = other_triangle(tri[k], tri[(k + 1) % 3], t);
        if (s >= 0 && component[s] < 0) { // s < 0: an open edge (an open surface's)
          component[s] = c;
          stack.push_back(s);
        }
      }
    }
    std::sort(m_components[c].begin(), m_components[c].end());
  }
}

/// A closed surface that passes through itself, or two that pass through each other (bodies that
/// overlap, a cavity that crosses its body's boundary), bound no body: refused, naming the pair.
void MeshValidator::check_intersections()
{
  const std::optional<TrianglePair> hit = find_intersection(m_mesh);
  if (!hit) return;
  const int a = hit->first, b = hit->second, ca = m_component_of[a], cb = m_component_of[b];
  const std::string pair = "triangles " + std::to_string(a) + " " + triple(m_mesh.triangles[a]) + " and " + std::to_string(b) + " " + triple(m_mesh.triangles[b]) + " intersect";
  if (ca == cb) fail(pair + ": the surface (component " + std::to_string(ca) + ") passes through itself");
  fail(pair + ": the surfaces of components " + std::to_string(ca) + " and " + std::to_string(cb) +
       " pass through each other (two bodies overlap, or a cavity crosses its body's boundary)");
}

std::string MeshValidator::sample_text(const SurfaceSample &s) const
{
  return s.vertex >= 0 ? "vertex " + std::to_string(s.vertex) : "the centroid of triangle " + std::to_string(s.triangle);
}

/// Surfaces that pass through each other where no two triangles' interiors cross (along edges or
/// at vertices, when the grids line up) or coincide: refused. Otherwise each component's place
/// (inside or outside every other) comes from all its samples, so a cavity lies wholly inside
/// its parent.
void MeshValidator::check_nesting()
{
  SurfaceNesting n = nest_surfaces(m_mesh, m_component_of, static_cast<int>(m_components.size()));
  if (n.crossing) {
    const SurfaceCrossing &c = *n.crossing;
    const std::string a = "component " + std::to_string(c.first), b = "component " + std::to_string(c.second);
    if (c.coincide) fail("the surfaces of " + a + " and " + b + " coincide (every vertex and triangle centroid of " + a + " lies on " + b + ")");
    fail("the surfaces of " + a + " and " + b + " pass through each other along triangle edges or at vertices: " + sample_text(c.inside) + " (of " + a + ") lies inside " + b + ", " +
         sample_text(c.outside) + " outside it (two bodies overlap, or a cavity crosses its body's boundary)");
  }
  m_inside = std::move(n.inside);
}

void MeshValidator::orient_components()
{
  for (int c = 0; c < static_cast<int>(m_components.size()); ++c) {
    const auto &tris = m_components[c];
    const double diag = m_component_box[c].diagonal();
    const double volume = signed_volume(c, m_component_box[c].center());
    const std::string name =
        "component " + std::to_string(c) + " (" + std::to_string(tris.size()) + " triangles";
    if (std::abs(volume) <= k_degenerate * diag * diag * diag)
      fail(name + ", first triangle " + std::to_string(tris.front()) + ") encloses no volume");
    // A component inside an odd number of others bounds a cavity: its normals point into the
    // cavity, which is out of the solid, so its signed volume is negative.
    const bool cavity = nesting_depth(c) % 2 == 1;
    if ((volume < 0) == cavity)
      continue;
    for (int t : tris)
      std::swap(m_mesh.triangles[t][1], m_mesh.triangles[t][2]);
    notice(name + (cavity ? ", cavity boundary" : "") + ") was oriented inward; flipped");
  }
}

double MeshValidator::signed_volume(int c, const Vec3 &origin) const
{
  // Measured from a point near the component so large offsets do not cancel digits.
  double six_volume = 0.0;
  for (int t : m_components[c])
    six_volume += dot(corner(t, 0) - origin, cross(corner(t, 1) - origin, corner(t, 2) - origin));
  return six_volume / 6.0;
}

int MeshValidator::nesting_depth(int c) const
{
  return static_cast<int>(std::count(m_inside[c].begin(), m_inside[c].end(), 1));
}

void MeshValidator::report_unused_vertices()
{
  const auto unused = std::count(m_first_triangle.begin(), m_first_triangle.end(), -1);
  if (unused == 0)
    return;
  const auto first = std::find(m_first_triangle.begin(), m_first_triangle.end(), -1);
  notice(std::to_string(unused) + " of " + std::to_string(m_mesh.num_vertices()) +
         " vertices are used by no triangle (first: vertex " +
         std::to_string(first - m_first_triangle.begin()) + ")");
}

} // namespace

void validate_and_orient(SurfaceMesh &mesh, std::vector<std::string> &notices)
{
  MeshValidator(mesh, notices).run();
}

bool validate_open_surface(const SurfaceMesh &mesh)
{
  SurfaceMesh copy = mesh; // the validator's interface orients in place; nothing is changed here
  std::vector<std::string> notices;
  return MeshValidator(copy, notices).run_open();
}

} // namespace hssbem
