/// \file discretization.hpp
/// P1 collocation nodes ("dof nodes") on a validated surface mesh, with double nodes at sharp
/// edges and corners.
///
/// A vertex on a smooth part of the surface carries one dof node, collocated at the vertex. At a
/// vertex where the surface has a sharp edge or corner (dihedral angle above the feature angle),
/// the triangle fan splits into k smooth groups; the vertex then carries k dof nodes, one per
/// group, each collocated at a point moved from the vertex into one triangle of its group
/// (barycentric (2/3, 1/6, 1/6)). Each node carries 3 displacement and 3 traction components, so
/// traction (and, where it is unknown, displacement) may jump across the feature. Every triangle
/// interpolates P1 over the dof nodes of its three corners.
#pragma once

#include "hssbem/mesh/mesh.hpp"
#include "hssbem/core/geometry.hpp"

#include <vector>

namespace hssbem {

struct DofNode {
  int vertex;             ///< mesh vertex this node belongs to
  int group;              ///< smooth group index around the vertex (0 for a smooth vertex)
  Vec3 point;             ///< collocation point
  Vec3 normal;            ///< unit outward normal of the group (angle-weighted)
  int element;            ///< triangle containing a moved point, -1 when collocated at the vertex
  std::array<double, 3> bary; ///< barycentric coordinates of `point` in `element`
};

class Discretization {
public:
  /// Build dof nodes; `feature_angle_deg` is the dihedral angle above which an edge is sharp.
  Discretization(const SurfaceMesh &mesh, double feature_angle_deg);

  const SurfaceMesh &mesh() const { return *m_mesh; }
  int num_nodes() const { return static_cast<int>(m_nodes.size()); }
  const DofNode &node(int i) const { return m_nodes[i]; }
  /// Where node i's values live: its vertex (a double node is only collocated elsewhere). Rigid
  /// motions, moments and exact solutions are evaluated here.
  const Vec3 &node_position(int i) const { return m_mesh->vertices[m_nodes[i].vertex]; }
  const std::vector<DofNode> &nodes() const { return m_nodes; }
  /// dof node at corner c of triangle t
  int element_node(int t, int c) const { return m_element_nodes[t][c]; }
  const std::array<int, 3> &element_nodes(int t) const { return m_element_nodes[t]; }
  /// dof nodes of vertex v are first_node(v) .. first_node(v)+node_count(v)-1 (none if unused)
  int first_node(int v) const { return m_vertex_first[v]; }
  int node_count(int v) const { return m_vertex_first[v + 1] - m_vertex_first[v]; }
  /// triangles that use node i (its P1 support), CSR
  const int *support_begin(int i) const { return m_support.data() + m_support_offset[i]; }
  const int *support_end(int i) const { return m_support.data() + m_support_offset[i + 1]; }
  int num_sharp_vertices() const { return m_num_sharp; }
  double feature_angle_deg() const { return m_feature_angle; }

private:
  const SurfaceMesh *m_mesh;
  double m_feature_angle;
  std::vector<DofNode> m_nodes;
  std::vector<std::array<int, 3>> m_element_nodes;
  std::vector<int> m_vertex_first;
  std::vector<int> m_support_offset, m_support;
  int m_num_sharp = 0;
};

/// Lumped area of each dof node (integral of its shape function).
std::vector<double> node_areas(const Discretization &disc);

} // namespace hssbem
