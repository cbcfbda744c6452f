// Dof nodes: one per smooth vertex, one per smooth group at sharp edges and corners.
#include "hssbem/bem/discretization.hpp"
#include "test_shapes.hpp"

#include <gtest/gtest.h>

using namespace hssbem;

TEST(Discretization, SmoothSphereHasOneNodePerVertexAtTheVertex)
{
  const SurfaceMesh m = test::icosphere(2);
  const Discretization d(m, 40.0);
  EXPECT_EQ(d.num_nodes(), m.num_vertices());
  EXPECT_EQ(d.num_sharp_vertices(), 0);
  for (int i = 0; i < d.num_nodes(); ++i) {
    EXPECT_EQ(d.node(i).element, -1);
    EXPECT_DOUBLE_EQ(norm(d.node(i).point - m.vertices[d.node(i).vertex]), 0.0);
    EXPECT_GT(dot(d.node(i).normal, normalized(d.node(i).point)), 0.99); // outward
  }
}

TEST(Discretization, CubeGetsDoubleNodesOnEdgesAndTripleAtCorners)
{
  const int n = 3;
  const SurfaceMesh m = test::unit_cube(n);
  const Discretization d(m, 40.0);
  const int corners = 8, edge_vertices = 12 * (n - 1), faces = 6 * (n - 1) * (n - 1);
  EXPECT_EQ(d.num_sharp_vertices(), corners + edge_vertices);
  EXPECT_EQ(d.num_nodes(), 3 * corners + 2 * edge_vertices + faces);
  for (int v = 0; v < m.num_vertices(); ++v) {
    const Vec3 x = m.vertices[v];
    int on_faces = 0;
    for (int c = 0; c < 3; ++c) on_faces += (x[c] == 0.0 || x[c] == 1.0);
    EXPECT_EQ(d.node_count(v), on_faces == 1 ? 1 : on_faces) << "vertex " << v;
  }
}

TEST(Discretization, MovedNodesLieInsideTheirGroupAndElementsUseTheirGroupsNode)
{
  const SurfaceMesh m = test::unit_cube(2);
  const Discretization d(m, 40.0);
  for (int i = 0; i < d.num_nodes(); ++i) {
    const DofNode &node = d.node(i);
    if (node.element < 0) continue;
    // the point is strictly inside its triangle and on the face whose normal the node carries
    EXPECT_NEAR(node.bary[0] + node.bary[1] + node.bary[2], 1.0, 1e-14);
    EXPECT_GT(dot(m.triangle_normal(node.element), node.normal), 0.999);
    EXPECT_LT(norm(node.point - m.vertices[node.vertex]), 0.5);
  }
  for (int t = 0; t < m.num_triangles(); ++t)
    for (int c = 0; c < 3; ++c) {
      const DofNode &node = d.node(d.element_node(t, c));
      EXPECT_EQ(node.vertex, m.triangles[t][c]);
      EXPECT_GT(dot(node.normal, m.triangle_normal(t)), 0.99) << "triangle " << t << " corner " << c;
    }
}

TEST(Discretization, SupportListsEveryTriangleOfANodeOnce)
{
  const SurfaceMesh m = test::unit_cube(2);
  const Discretization d(m, 40.0);
  int total = 0;
  for (int i = 0; i < d.num_nodes(); ++i) {
    for (const int *t = d.support_begin(i); t != d.support_end(i); ++t) {
      const auto &en = d.element_nodes(*t);
      EXPECT_TRUE(en[0] == i || en[1] == i || en[2] == i);
    }
    total += static_cast<int>(d.support_end(i) - d.support_begin(i));
  }
  EXPECT_EQ(total, 3 * m.num_triangles());
}

TEST(Discretization, FeatureAngleAboveNinetyDegreesMakesTheCubeSmooth)
{
  const SurfaceMesh m = test::unit_cube(2);
  const Discretization d(m, 100.0);
  EXPECT_EQ(d.num_sharp_vertices(), 0);
  EXPECT_EQ(d.num_nodes(), m.num_vertices());
}
