#include "hssbem/bem/discretization.hpp"

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <unordered_map>

namespace hssbem {

namespace {

std::uint64_t edge_key(int a, int b)
{
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}

int corner_of(const std::array<int, 3> &tri, int v)
{
  for (int c = 0; c < 3; ++c)
    if (tri[c] == v) return c;
  return -1;
}

/// Interior angle of triangle t at its corner c (weights vertex normals).
double corner_angle(const SurfaceMesh &mesh, int t, int c)
{
  const auto &tri = mesh.triangles[t];
  const Vec3 e1 = mesh.vertices[tri[(c + 1) % 3]] - mesh.vertices[tri[c]];
  const Vec3 e2 = mesh.vertices[tri[(c + 2) % 3]] - mesh.vertices[tri[c]];
  return std::atan2(norm(cross(e1, e2)), dot(e1, e2));
}

/// Triangles around each vertex in cyclic order (the mesh is closed and manifold).
std::vector<std::vector<int>> ordered_fans(const SurfaceMesh &mesh)
{
  std::unordered_map<std::uint64_t, int> directed;
  directed.reserve(3 * mesh.triangles.size());
  std::vector<int> any_triangle(mesh.vertices.size(), -1);
  for (int t = 0; t < mesh.num_triangles(); ++t)
    for (int c = 0; c < 3; ++c) {
      directed[edge_key(mesh.triangles[t][c], mesh.triangles[t][(c + 1) % 3])] = t;
      any_triangle[mesh.triangles[t][c]] = t;
    }
  std::vector<std::vector<int>> fans(mesh.vertices.size());
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    int t = any_triangle[v];
    while (t >= 0) {
      fans[v].push_back(t);
      const auto &tri = mesh.triangles[t];
      const int w = tri[(corner_of(tri, v) + 1) % 3];
      const auto it = directed.find(edge_key(w, v));
      if (it == directed.end()) throw std::invalid_argument("Discretization: mesh is not closed; validate it first");
      t = it->second == fans[v].front() ? -1 : it->second;
      if (fans[v].size() > mesh.triangles.size()) throw std::invalid_argument("Discretization: non-manifold vertex");
    }
  }
  return fans;
}

/// Split a cyclic fan at sharp edges; returns the groups as runs of the fan.
std::vector<std::vector<int>> smooth_groups(const SurfaceMesh &mesh, const std::vector<int> &fan, double cos_feature)
{
  const int n = static_cast<int>(fan.size());
  std::vector<int> cuts; // cut before fan[k]
  for (int k = 0; k < n; ++k) {
    const Vec3 a = mesh.triangle_normal(fan[(k + n - 1) % n]);
    const Vec3 b = mesh.triangle_normal(fan[k]);
    if (dot(a, b) < cos_feature) cuts.push_back(k);
  }
  if (cuts.size() <= 1) return {fan};
  std::vector<std::vector<int>> groups;
  for (std::size_t g = 0; g < cuts.size(); ++g) {
    std::vector<int> run;
    const int end = cuts[(g + 1) % cuts.size()];
    for (int k = cuts[g]; run.empty() || k != end; k = (k + 1) % n) run.push_back(fan[k]);
    groups.push_back(std::move(run));
  }
  return groups;
}

} // namespace

Discretization::Discretization(const SurfaceMesh &mesh, double feature_angle_deg) : m_mesh(&mesh), m_feature_angle(feature_angle_deg)
{
  const double cos_feature = std::cos(feature_angle_deg * M_PI / 180.0);
  const auto fans = ordered_fans(mesh);
  m_element_nodes.assign(mesh.triangles.size(), {-1, -1, -1});
  m_vertex_first.assign(mesh.vertices.size() + 1, 0);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    m_vertex_first[v] = num_nodes();
    if (fans[v].empty()) continue;
    const auto groups = smooth_groups(mesh, fans[v], cos_feature);
    if (groups.size() > 1) ++m_num_sharp;
    for (std::size_t g = 0; g < groups.size(); ++g) {
      DofNode node{v, static_cast<int>(g), mesh.vertices[v], {0, 0, 0}, -1, {0, 0, 0}};
      for (int t : groups[g]) {
        node.normal = node.normal + corner_angle(mesh, t, corner_of(mesh.triangles[t], v)) * mesh.triangle_normal(t);
        m_element_nodes[t][corner_of(mesh.triangles[t], v)] = num_nodes();
      }
      node.normal = normalized(node.normal);
      if (groups.size() > 1) {
        // Collocate inside the group, away from the feature, so that each double node gets an
        // equation of its own; (2/3, 1/6, 1/6) keeps the point close to the vertex it stands for.
        const int t = groups[g][groups[g].size() / 2];
        const auto &tri = mesh.triangles[t];
        const int c = corner_of(tri, v);
        node.element = t;
        node.bary = {1.0 / 6, 1.0 / 6, 1.0 / 6};
        node.bary[c] = 2.0 / 3;
        node.point = {0, 0, 0};
        for (int k = 0; k < 3; ++k) node.point = node.point + node.bary[k] * mesh.vertices[tri[k]];
      }
      m_nodes.push_back(node);
    }
  }
  m_vertex_first[mesh.vertices.size()] = num_nodes();
  m_support_offset.assign(m_nodes.size() + 1, 0);
  for (const auto &en : m_element_nodes)
    for (int i : en) ++m_support_offset[i + 1];
  for (std::size_t i = 0; i < m_nodes.size(); ++i) m_support_offset[i + 1] += m_support_offset[i];
  m_support.resize(m_support_offset.back());
  std::vector<int> fill(m_support_offset.begin(), m_support_offset.end() - 1);
  for (int t = 0; t < mesh.num_triangles(); ++t)
    for (int i : m_element_nodes[t]) m_support[fill[i]++] = t;
}

std::vector<double> node_areas(const Discretization &disc)
{
  std::vector<double> a(disc.num_nodes(), 0.0);
  for (int e = 0; e < disc.mesh().num_triangles(); ++e)
    for (int c = 0; c < 3; ++c) a[disc.element_node(e, c)] += disc.mesh().triangle_area(e) / 3.0;
  return a;
}

} // namespace hssbem
