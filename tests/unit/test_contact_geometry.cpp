/// \file test_contact_geometry.cpp
/// Contact's geometry (contact/): closest points on triangles and the hierarchy against brute
/// force, the obstacles' gaps and normals, the bodies of a mesh; the "contact" keys of the
/// problem file and their errors.
#include "hssbem/contact/bodies.hpp"
#include "hssbem/contact/obstacle.hpp"
#include "hssbem/contact/triangle_bvh.hpp"
#include "hssbem/problem/problem.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

using namespace hssbem;

namespace {

/// The unit cube [0,1]^3 shifted by `shift`, 12 outward triangles, vertices numbered from `first`.
void add_cube(SurfaceMesh &m, const Vec3 &shift, double size = 1.0)
{
  const int first = m.num_vertices();
  for (int v = 0; v < 8; ++v) m.vertices.push_back(shift + size * Vec3{double(v & 1), double((v >> 1) & 1), double((v >> 2) & 1)});
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto &q : quads) {
    m.triangles.push_back({first + q[0], first + q[1], first + q[2]});
    m.triangles.push_back({first + q[0], first + q[2], first + q[3]});
  }
  m.triangle_region.resize(m.triangles.size(), -1);
}

/// The cube with its triangles flipped (normals into it): a cavity when nested in another.
void add_cavity(SurfaceMesh &m, const Vec3 &shift, double size)
{
  const std::size_t t0 = m.triangles.size();
  add_cube(m, shift, size);
  for (std::size_t t = t0; t < m.triangles.size(); ++t) std::swap(m.triangles[t][1], m.triangles[t][2]);
}

} // namespace

TEST(ContactGeometry, ClosestPointsMatchBruteForce)
{
  std::mt19937 gen(4);
  std::uniform_real_distribution<double> u(-2, 2);
  SurfaceMesh m;
  for (int i = 0; i < 60; ++i) m.vertices.push_back({u(gen), u(gen), u(gen)});
  for (int t = 0; t < 20; ++t) m.triangles.push_back({3 * t, 3 * t + 1, 3 * t + 2});
  const TriangleBvh bvh(m.vertices, m.triangles);
  for (int q = 0; q < 200; ++q) {
    const Vec3 x{u(gen), u(gen), u(gen)};
    double best = INFINITY;
    for (const auto &t : m.triangles) best = std::min(best, closest_point_on_triangle(x, m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]).distance);
    const TriangleHit h = bvh.closest(x);
    ASSERT_GE(h.triangle, 0);
    EXPECT_NEAR(h.distance, best, 1e-12);
    const auto &t = m.triangles[h.triangle];
    const Vec3 p = h.bary[0] * m.vertices[t[0]] + h.bary[1] * m.vertices[t[1]] + h.bary[2] * m.vertices[t[2]];
    EXPECT_LT(norm(p - h.point), 1e-12);
    EXPECT_EQ(bvh.closest(x, 0.5 * best).triangle, -1); // nothing within a tighter bound
  }
}

TEST(ContactGeometry, ObstacleGapsAndNormals)
{
  const ObstacleGeometry plane(Obstacle::plane("table", {0, 0, -1}, {0, 0, 2}));
  ObstacleGap g;
  ASSERT_TRUE(plane.gap({0.3, 0.1, -0.5}, {0, 0, 0}, 1.0, g));
  EXPECT_NEAR(g.gap, 0.5, 1e-15);
  EXPECT_NEAR(g.normal[2], 1.0, 1e-15);
  ASSERT_TRUE(plane.gap({0.3, 0.1, -0.5}, {0, 0, 0.7}, 1.0, g)); // translated up by 0.7: overlap
  EXPECT_NEAR(g.gap, -0.2, 1e-15);
  EXPECT_FALSE(plane.gap({0, 0, 5}, {0, 0, 0}, 1.0, g));

  const ObstacleGeometry ball(Obstacle::sphere("tool", {0, 0, 2}, 0.5));
  ASSERT_TRUE(ball.gap({0, 0.6, 2}, {0, 0, 0}, 1.0, g));
  EXPECT_NEAR(g.gap, 0.1, 1e-15);
  EXPECT_NEAR(g.normal[1], 1.0, 1e-15);

  // The plane z = -1 as a rigid mesh of two triangles facing +z: the same gaps inside it; beyond
  // its edge the gap is the distance to the edge.
  SurfaceMesh wall;
  wall.vertices = {{-2, -2, -1}, {2, -2, -1}, {2, 2, -1}, {-2, 2, -1}};
  wall.triangles = {{0, 1, 2}, {0, 2, 3}};
  const ObstacleGeometry mesh(Obstacle::mesh("wall", wall));
  for (const Vec3 x : {Vec3{0.3, 0.1, -0.5}, Vec3{-1.5, 1.2, -1.3}}) {
    ObstacleGap a, b;
    ASSERT_TRUE(plane.gap(x, {0, 0, 0}, 1.0, a));
    ASSERT_TRUE(mesh.gap(x, {0, 0, 0}, 1.0, b));
    EXPECT_NEAR(a.gap, b.gap, 1e-15);
    EXPECT_NEAR(dot(a.normal, b.normal), 1.0, 1e-15);
  }
  ASSERT_TRUE(mesh.gap({3, 0, -1}, {0, 0, 0}, 2.0, g));
  EXPECT_NEAR(g.gap, 1.0, 1e-14);
  EXPECT_NEAR(g.normal[0], 1.0, 1e-14);
}

TEST(ContactGeometry, ATurnedObstacleEqualsTheObstacleGivenAtTheTurnedPlace)
{
  // A turn of 90 degrees about z maps x to y: checked on the matrix itself.
  const Pose quarter = Pose::turn({0, 0, 2}, 90, {0, 0, 0});
  const Vec3 ex = quarter.apply({1, 0, 0});
  EXPECT_NEAR(ex[0], 0, 1e-15);
  EXPECT_NEAR(ex[1], 1, 1e-15);
  EXPECT_NEAR(ex[2], 0, 1e-15);
  // Each shape turned by 35 degrees about a tilted axis through a centre, then translated,
  // against the same shape given at its turned place: the same gaps, normals and points.
  const Pose pose = Pose::turn({1, -2, 0.5}, 35, {0.2, 0.1, -0.3}, {0.05, -0.4, 0.3});
  SurfaceMesh box;
  add_cube(box, {-0.5, -0.5, -2.0});
  SurfaceMesh moved = box;
  for (Vec3 &v : moved.vertices) v = pose.apply(v);
  const std::vector<std::pair<Obstacle, Obstacle>> pairs{
      {Obstacle::plane("p", {0, 0, -1}, {0, 0, 1}), Obstacle::plane("p", pose.apply({0, 0, -1}), pose.rotate({0, 0, 1}))},
      {Obstacle::sphere("s", {0.3, 0, 1.5}, 0.4), Obstacle::sphere("s", pose.apply({0.3, 0, 1.5}), 0.4)},
      {Obstacle::mesh("m", box), Obstacle::mesh("m", moved)}};
  std::mt19937 gen(7);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (const auto &[base, placed] : pairs) {
    const ObstacleGeometry a(base), b(placed);
    for (int q = 0; q < 50; ++q) {
      const Vec3 x{u(gen), u(gen), u(gen)};
      ObstacleGap ga, gb;
      ASSERT_EQ(a.gap(x, pose, 10.0, ga), b.gap(x, Vec3{0, 0, 0}, 10.0, gb));
      EXPECT_NEAR(ga.gap, gb.gap, 1e-12);
      EXPECT_NEAR(norm(ga.normal - gb.normal), 0, 1e-12);
      EXPECT_NEAR(norm(ga.point - gb.point), 0, 1e-12);
      EXPECT_NEAR(norm(pose.apply(ga.base_point) - ga.point), 0, 1e-12); // the material point moves with the pose
    }
  }
  EXPECT_THROW(Pose::turn({0, 0, 0}, 10, {0, 0, 0}), std::invalid_argument);
}

TEST(ContactGeometry, ObstacleDescriptionsAreChecked)
{
  auto message = [](const Obstacle &o) {
    try {
      const ObstacleGeometry g(o);
    } catch (const std::invalid_argument &e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message(Obstacle::plane("p", {0, 0, 0}, {0, 0, 0})).find("normal is zero"), std::string::npos);
  EXPECT_NE(message(Obstacle::sphere("s", {0, 0, 0}, 0)).find("radius must be > 0"), std::string::npos);
  SurfaceMesh flat;
  flat.vertices = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  flat.triangles = {{0, 1, 2}};
  EXPECT_NE(message(Obstacle::mesh("m", flat)).find("degenerate"), std::string::npos);
  Obstacle rough = Obstacle::plane("r", {0, 0, 0}, {0, 0, 1});
  rough.friction = -0.1;
  EXPECT_NE(message(rough).find("friction"), std::string::npos);
}

TEST(ContactGeometry, BodiesAreSurfacesAndCavitiesBelongToThem)
{
  SurfaceMesh m;
  add_cube(m, {3, 0, 0});            // body 1 (its lowest vertex is 0, but ...)
  add_cube(m, {0, 0, 0}, 2.0);       // the big cube: vertices 8..15
  add_cavity(m, {0.5, 0.5, 0.5}, 1.0); // a cavity inside the big cube: vertices 16..23
  const Bodies b = find_bodies(m);
  EXPECT_EQ(b.count, 2);
  EXPECT_EQ(b.of_vertex[0], 0);  // numbered by lowest vertex: the small cube first
  EXPECT_EQ(b.of_vertex[8], 1);
  EXPECT_EQ(b.of_vertex[16], 1); // the cavity is the big cube's
  EXPECT_EQ(b.of_triangle.back(), 1);
}

TEST(ContactProblemFile, KeysFramesAndErrors)
{
  const std::string head = R"({"mesh": "m.msh", "material": {"E": 1000, "nu": 0.3}, )";
  const ProblemSpec spec = parse_problem(head + R"("contact": {"obstacles": [
      {"name": "table", "plane": {"point": [0, 0, -1], "normal": [0, 0, 1]}},
      {"name": "tool", "sphere": {"center": [0, 0, 1.3], "radius": 0.3}, "friction": 0.5},
      {"name": "wall", "mesh": "wall.off"}], "friction": 0.2, "bodies": true, "where": {"region": "front"}},
    "frames": [{"obstacles": {"tool": {"translate": [0.1, 0, 0]}}}, {"boundary": []}]})",
                                         "dir/p.json");
  ASSERT_TRUE(spec.contact.present);
  ASSERT_EQ(spec.contact.obstacles.size(), 3u);
  EXPECT_EQ(spec.contact.obstacles[1].shape, ObstacleSpec::Shape::Sphere);
  EXPECT_EQ(spec.contact.obstacles[1].friction, 0.5);
  EXPECT_TRUE(std::isnan(spec.contact.obstacles[0].friction));
  EXPECT_EQ(spec.contact.obstacles[2].mesh_path, "dir/wall.off");
  EXPECT_EQ(spec.contact.friction, 0.2);
  EXPECT_TRUE(spec.contact.bodies);
  ASSERT_EQ(spec.frames.size(), 2u);
  ASSERT_EQ(spec.frames[0].obstacles.size(), 1u);
  EXPECT_EQ(spec.frames[0].obstacles[0].first, "tool");
  EXPECT_EQ(spec.frames[0].obstacles[0].second[0], 0.1);

  auto error = [&](const std::string &body) {
    try {
      parse_problem(head + body, "p.json");
    } catch (const ProblemError &e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string plane = R"({"name": "a", "plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}})";
  EXPECT_NE(error(R"("contact": {"obstacles": [)" + plane + "," + plane + "]}}").find("contact.obstacles[1].name: duplicate obstacle name 'a'"), std::string::npos);
  EXPECT_NE(error(R"("contact": {"obstacles": [{"name": "a", "plane": {"point": [0, 0, 0], "normal": [0, 0, 0]}}]}})").find("plane.normal: the normal is zero"), std::string::npos);
  EXPECT_NE(error(R"("contact": {"friction": -0.1}})").find("contact.friction: the friction coefficient must be >= 0"), std::string::npos);
  EXPECT_NE(error(R"("contact": {"obstacles": [{"name": "s", "sphere": {"center": [0, 0, 0], "radius": 0}}]}})").find("sphere.radius: the radius must be > 0"), std::string::npos);
  EXPECT_NE(error(R"("contact": {"obstacles": [)" + plane + R"(]}, "frames": [{"boundary": []}, {"obstacles": {"b": {"translate": [0, 0, 1]}}}]})")
                .find("frames[1].obstacles: no obstacle named 'b' (known: a)"),
            std::string::npos);
  EXPECT_NE(error(R"("contact": {"obstacles": [{"name": "a", "plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}, "sphere": {"center": [0, 0, 0], "radius": 1}}]}})")
                .find("has more than one of 'plane', 'sphere', 'mesh'"),
            std::string::npos);
}
