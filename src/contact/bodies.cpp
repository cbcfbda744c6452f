// The bodies of a mesh (bodies.hpp): connected surfaces by shared vertices, nesting by every
// vertex and triangle centroid of a surface with respect to each other surface (nest_surfaces).
#include "hssbem/contact/bodies.hpp"

#include "hssbem/mesh/surface_intersection.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace hssbem {

namespace {

int find_root(std::vector<int> &parent, int i)
{
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

/// Connected surfaces: per triangle, the index of its surface (0, 1, ... by first triangle).
std::vector<int> surfaces_of(const SurfaceMesh &m, int &count)
{
  std::vector<int> parent(m.vertices.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (const auto &t : m.triangles)
    for (int k = 1; k < 3; ++k) parent[find_root(parent, t[k])] = find_root(parent, t[0]);
  std::vector<int> label(m.vertices.size(), -1), surface(m.triangles.size());
  count = 0;
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    const int r = find_root(parent, m.triangles[t][0]);
    if (label[r] < 0) label[r] = count++;
    surface[t] = label[r];
  }
  return surface;
}

} // namespace

Bodies find_bodies(const SurfaceMesh &m)
{
  int ns = 0;
  const std::vector<int> surface = surfaces_of(m, ns);
  // inside[s][r]: surface s lies inside surface r (all its samples, not one: nest_surfaces)
  const std::vector<std::vector<char>> inside = nest_surfaces(m, surface, ns).inside;
  std::vector<int> depth(ns, 0);
  for (int s = 0; s < ns; ++s) depth[s] = static_cast<int>(std::count(inside[s].begin(), inside[s].end(), 1));
  // A surface's body: itself at even depth; else the enclosing surface one level up.
  std::vector<int> owner(ns);
  for (int s = 0; s < ns; ++s) {
    owner[s] = s;
    if (depth[s] % 2 == 0) continue;
    for (int r = 0; r < ns; ++r)
      if (inside[s][r] && depth[r] == depth[s] - 1) owner[s] = r;
  }
  Bodies b;
  b.of_vertex.assign(m.vertices.size(), -1);
  b.of_triangle.resize(m.triangles.size());
  std::vector<int> lowest(ns, static_cast<int>(m.vertices.size()));
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (int v : m.triangles[t]) lowest[owner[surface[t]]] = std::min(lowest[owner[surface[t]]], v);
  std::vector<int> outer; // the bodies' outer surfaces, by lowest vertex
  for (int s = 0; s < ns; ++s)
    if (owner[s] == s) outer.push_back(s);
  std::sort(outer.begin(), outer.end(), [&](int a, int c) { return lowest[a] < lowest[c]; });
  std::vector<int> number(ns, -1);
  for (std::size_t k = 0; k < outer.size(); ++k) number[outer[k]] = static_cast<int>(k);
  b.count = static_cast<int>(outer.size());
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    b.of_triangle[t] = number[owner[surface[t]]];
    for (int v : m.triangles[t]) b.of_vertex[v] = b.of_triangle[t];
  }
  return b;
}

std::vector<int> node_bodies(const Discretization &disc)
{
  const Bodies b = find_bodies(disc.mesh());
  if (b.count < 2) return {};
  std::vector<int> out(disc.num_nodes());
  for (int i = 0; i < disc.num_nodes(); ++i) out[i] = b.of_vertex[disc.node(i).vertex];
  return out;
}

} // namespace hssbem
