/// \file test_contact_geometry.cpp
/// Contact's geometry (contact/): closest points on triangles and the hierarchy against brute
/// force, the obstacles' gaps and normals, the bodies of a mesh; the "contact" keys of the
/// problem file and their errors.
#include "hssbem/mesh/mesh.hpp"
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

/// An L-shaped prism: the polygon (0,0) (2,0) (2,1) (1,1) (1,2) (0,2) over z in [0, 1], outward;
/// its edge at x = y = 1 is reflex (concave), its corners there are saddles.
SurfaceMesh l_prism()
{
  const double px[6] = {0, 2, 2, 1, 1, 0}, py[6] = {0, 0, 1, 1, 2, 2};
  SurfaceMesh m;
  for (int z = 0; z < 2; ++z)
    for (int k = 0; k < 6; ++k) m.vertices.push_back({px[k], py[k], double(z)});
  for (int k = 0; k < 6; ++k) { // the sides: quads (k, k+1) from bottom to top
    const int a = k, b = (k + 1) % 6;
    m.triangles.push_back({a, b, b + 6});
    m.triangles.push_back({a, b + 6, a + 6});
  }
  for (int k = 1; k < 5; ++k) { // the caps: fans from (0, 0), which sees the whole L
    m.triangles.push_back({0, k + 1, k});
    m.triangles.push_back({6, 6 + k, 6 + k + 1});
  }
  m.triangle_region.assign(m.triangles.size(), -1);
  return m;
}

bool inside_l_prism(const Vec3 &x)
{
  const bool in_l = (x[0] > 0 && x[0] < 2 && x[1] > 0 && x[1] < 1) || (x[0] > 0 && x[0] < 1 && x[1] > 0 && x[1] < 2);
  return in_l && x[2] > 0 && x[2] < 1;
}

/// The distance from a point x outside the box [lo, hi] to it (the L prism is the union of two
/// boxes: outside it, its distance is the smaller of theirs).
double box_distance(const Vec3 &x, const Vec3 &lo, const Vec3 &hi)
{
  double d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const double e = std::max({lo[k] - x[k], 0.0, x[k] - hi[k]});
    d2 += e * e;
  }
  return std::sqrt(d2);
}

SurfaceMesh flipped(SurfaceMesh m)
{
  for (auto &t : m.triangles) std::swap(t[1], t[2]);
  return m;
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

TEST(ContactGeometry, SignedDistanceOfAClosedMeshByPseudoNormals)
{
  // The L prism (a reflex edge, saddle corners) and its copy with every square split the other
  // way (other ties at edges and corners): the sign against the exact inside test of the L, the
  // distance outside against the two boxes', at random points and at points crowded around its
  // vertices and edges.
  const SurfaceMesh l = l_prism();
  SurfaceMesh other = l;
  for (std::size_t t = 0; t + 1 < 12; t += 2) { // the side quads along their other diagonal
    const auto a = other.triangles[t], b = other.triangles[t + 1];
    other.triangles[t] = {a[0], a[1], b[2]}, other.triangles[t + 1] = {a[1], a[2], b[2]};
  }
  std::mt19937 gen(11);
  std::uniform_real_distribution<double> u(-0.5, 2.5), near(-0.15, 0.15);
  for (const SurfaceMesh &m : {l, other}) {
    const ObstacleGeometry g(Obstacle::mesh("l", m));
    ASSERT_FALSE(g.open());
    int checked = 0, inside = 0;
    for (int q = 0; q < 4000; ++q) {
      Vec3 x{u(gen), u(gen), 0.5 * u(gen)};
      if (q % 2) x = m.vertices[q % m.num_vertices()] + Vec3{near(gen), near(gen), near(gen)};
      ObstacleSide s;
      ASSERT_TRUE(g.side(x, Pose{}, 1e9, s));
      if (std::abs(s.distance) < 1e-9) continue;
      ++checked;
      const bool in = inside_l_prism(x);
      inside += in;
      ASSERT_EQ(s.distance < 0, in) << "at " << x[0] << " " << x[1] << " " << x[2] << ": " << s.distance;
      if (!in) EXPECT_NEAR(s.distance, std::min(box_distance(x, {0, 0, 0}, {2, 1, 1}), box_distance(x, {0, 0, 0}, {1, 2, 1})), 1e-12);
      ObstacleGap gp;
      if (g.gap(x, Pose{}, 1e9, gp)) EXPECT_NEAR(gp.gap, s.distance, 1e-14); // a solid: no depth bound
    }
    EXPECT_GT(checked, 3900);
    EXPECT_GT(inside, 400);
  }
  // A sharp pyramid (base [-0.5, 0.5]^2 at z = 0, apex (0, 0, 5)): around its apex the faces'
  // normals point nearly opposite ways, so a point over the apex lies behind some of them; the
  // sign of a triangle there would depend on which one the search meets first.
  SurfaceMesh pyramid;
  pyramid.vertices = {{-0.5, -0.5, 0}, {0.5, -0.5, 0}, {0.5, 0.5, 0}, {-0.5, 0.5, 0}, {0, 0, 5}};
  pyramid.triangles = {{0, 2, 1}, {0, 3, 2}, {0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}};
  const ObstacleGeometry g(Obstacle::mesh("pyramid", pyramid));
  int outside = 0;
  for (int q = 0; q < 2000; ++q) {
    const Vec3 x = Vec3{0, 0, 5} + Vec3{near(gen), near(gen), near(gen)};
    const double half = 0.5 * (1 - x[2] / 5);
    const bool in = x[2] > 0 && x[2] < 5 && std::abs(x[0]) < half && std::abs(x[1]) < half;
    ObstacleSide s;
    ASSERT_TRUE(g.side(x, Pose{}, 1e9, s));
    if (std::abs(s.distance) < 1e-9) continue;
    outside += !in;
    ASSERT_EQ(s.distance < 0, in) << "at " << x[0] << " " << x[1] << " " << x[2] << ": " << s.distance;
  }
  EXPECT_GT(outside, 1000);
}

TEST(ContactGeometry, AVertexOnAnObstacleEdgeTakesTheEdgesNormal)
{
  // A point on an edge of a box (no distance to take a direction from) takes the edge's
  // pseudo-normal, the bisector of its two faces, however the box is triangulated; and the
  // corner's at a corner. The box is the unit cube turned 45 degrees about y, its lower edge
  // along y at x = 0, z = 0.
  SurfaceMesh coarse;
  add_cube(coarse, {-0.5, -0.5, -0.5});
  SurfaceMesh fine = coarse; // each triangle split in three at its centroid: other ties
  fine.triangles.clear();
  for (const auto &t : coarse.triangles) {
    const int c = fine.num_vertices();
    fine.vertices.push_back((1.0 / 3) * (coarse.vertices[t[0]] + coarse.vertices[t[1]] + coarse.vertices[t[2]]));
    fine.triangles.insert(fine.triangles.end(), {{t[0], t[1], c}, {t[1], t[2], c}, {t[2], t[0], c}});
  }
  const Pose turn = Pose::turn({0, 1, 0}, 45, {0, 0, 0}, {0, 0, std::sqrt(0.5)});
  for (SurfaceMesh *m : {&coarse, &fine})
    for (Vec3 &v : m->vertices) v = turn.apply(v);
  for (const SurfaceMesh &m : {coarse, fine}) {
    const ObstacleGeometry g(Obstacle::mesh("box", m));
    ObstacleGap h;
    for (double y : {-0.45, -0.2, 0.0, 0.31, 0.45}) {
      ASSERT_TRUE(g.gap({0, y, 0}, Pose{}, 0.1, h));
      EXPECT_NEAR(h.gap, 0, 1e-15);
      EXPECT_NEAR(norm(h.normal - Vec3{0, 0, -1}), 0, 1e-14) << "y = " << y;
    }
    ASSERT_TRUE(g.gap({0, 0.5, 0}, Pose{}, 0.1, h)); // a corner: its three faces' normals, each face's angle there 90 degrees
    EXPECT_NEAR(norm(h.normal - normalized(Vec3{0, 1, -std::sqrt(2.0)})), 0, 1e-14);
  }
}

TEST(ContactGeometry, AnOpenPlateTouchesOnlyWhatLiesOverIt)
{
  // The plate z = 0 over [-2, 2]^2 facing +z, depth 0.3: a point over it has the plane's gap; a
  // point behind it, within its outline, a negative gap down to the depth and none deeper; a
  // point behind it but past its edge is beside it: no contact; in front and past the edge, the
  // gap to the edge (the plate's rim).
  SurfaceMesh plate;
  plate.vertices = {{-2, -2, 0}, {2, -2, 0}, {2, 2, 0}, {-2, 2, 0}};
  plate.triangles = {{0, 1, 2}, {0, 2, 3}};
  const ObstacleGeometry g(Obstacle::mesh("plate", plate), 0.3);
  ASSERT_TRUE(g.open());
  EXPECT_EQ(g.depth(), 0.3);
  ObstacleGap h;
  ASSERT_TRUE(g.gap({1, 1.5, 0.4}, Pose{}, 1.0, h));
  EXPECT_NEAR(h.gap, 0.4, 1e-15);
  ASSERT_TRUE(g.gap({1.9, -1, -0.25}, Pose{}, 1.0, h));
  EXPECT_NEAR(h.gap, -0.25, 1e-15);
  EXPECT_NEAR(h.normal[2], 1, 1e-15);
  EXPECT_FALSE(g.gap({1.9, -1, -0.35}, Pose{}, 1.0, h)); // deeper than the depth
  for (const Vec3 &x : {Vec3{2.1, 0, -0.05}, Vec3{3, 0, -1}, Vec3{2.5, 2.5, -0.01}, Vec3{-2.01, 0.3, -0.2}})
    EXPECT_FALSE(g.gap(x, Pose{}, 10.0, h)) << x[0] << " " << x[1] << " " << x[2]; // beside it
  ASSERT_TRUE(g.gap({2.3, 0, 0.4}, Pose{}, 1.0, h));
  EXPECT_NEAR(h.gap, 0.5, 1e-15);
  ASSERT_TRUE(g.gap({2.5, 0, 0}, Pose{}, 1.0, h)); // in its plane, past its edge: in front of the rim
  EXPECT_NEAR(h.gap, 0.5, 1e-15);
  // The same plate turned and moved by a pose: the same answers at the moved points.
  const Pose pose = Pose::turn({1, 1, 0}, 30, {0, 0, 0}, {0.2, 0, 0.1});
  EXPECT_FALSE(g.gap(pose.apply({2.1, 0, -0.05}), pose, 10.0, h));
  ASSERT_TRUE(g.gap(pose.apply({1.9, -1, -0.25}), pose, 1.0, h));
  EXPECT_NEAR(h.gap, -0.25, 1e-14);
  // A closed mesh and the solids have no depth.
  SurfaceMesh box;
  add_cube(box, {0, 0, 0});
  EXPECT_FALSE(ObstacleGeometry(Obstacle::mesh("box", box), 0.01).open());
  EXPECT_TRUE(std::isinf(ObstacleGeometry(Obstacle::mesh("box", box), 0.01).depth()));
}

TEST(ContactGeometry, AnObstacleMeshMustFaceTheBodies)
{
  // Body points over a plate facing them pass; the plate flipped is refused in one line. A box
  // with its normals turned inward, the bodies outside, is refused; a container (normals inward)
  // with the body inside passes. Points far from the obstacle decide nothing.
  SurfaceMesh plate;
  plate.vertices = {{-2, -2, 0}, {2, -2, 0}, {2, 2, 0}, {-2, 2, 0}};
  plate.triangles = {{0, 1, 2}, {0, 2, 3}};
  std::vector<Vec3> body;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) body.push_back({-1 + 0.5 * i, -1 + 0.5 * j, 0.05}), body.push_back({-1 + 0.5 * i, -1 + 0.5 * j, 1.0});
  EXPECT_TRUE(check_obstacle_faces(ObstacleGeometry(Obstacle::mesh("plate", plate)), body, Pose{}, 0.1));
  try {
    check_obstacle_faces(ObstacleGeometry(Obstacle::mesh("plate", flipped(plate))), body, Pose{}, 0.1);
    ADD_FAILURE() << "a plate facing away was accepted";
  } catch (const std::invalid_argument &e) {
    EXPECT_NE(std::string(e.what()).find("obstacle 'plate': its triangles face away from the bodies (25 of the 25 body vertices within reach"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(check_obstacle_faces(ObstacleGeometry(Obstacle::mesh("plate", flipped(plate))), body, Pose::translation({0, 0, -5}), 0.1)); // nothing near: no verdict
  SurfaceMesh box;
  add_cube(box, {-0.5, -0.5, -1.04}); // its top face 0.04 under the body's lowest points... all but the plate's
  std::vector<Vec3> over(body.begin(), body.end());
  EXPECT_TRUE(check_obstacle_faces(ObstacleGeometry(Obstacle::mesh("box", box)), over, Pose{}, 0.1));
  EXPECT_THROW(check_obstacle_faces(ObstacleGeometry(Obstacle::mesh("box", flipped(box))), over, Pose{}, 0.1), std::invalid_argument);
  SurfaceMesh container;
  add_cube(container, {-2, -2, -0.5}, 4.0);
  EXPECT_TRUE(check_obstacle_faces(ObstacleGeometry(Obstacle::mesh("skull", flipped(container))), {{0, 0, -0.45}, {0, 1.95, 0}}, Pose{}, 0.1));
  EXPECT_THROW(check_obstacle_faces(ObstacleGeometry(Obstacle::mesh("skull", container)), {{0, 0, -0.45}, {0, 1.95, 0}}, Pose{}, 0.1), std::invalid_argument);
}

TEST(ContactGeometry, AnInterferenceIsNoEvidenceOfAMeshFacingAway)
{
  // A body's bottom face (outward normal -z) pressed 0.02 into a plate that faces it (+z): by the
  // side alone every point lies behind the plate and the plate looks turned away; with the body's
  // normals every point faces the plate's front. The plate flipped is still refused.
  SurfaceMesh plate;
  plate.vertices = {{-2, -2, 0}, {2, -2, 0}, {2, 2, 0}, {-2, 2, 0}};
  plate.triangles = {{0, 1, 2}, {0, 2, 3}};
  std::vector<Vec3> bottom, down;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) bottom.push_back({-1 + 0.5 * i, -1 + 0.5 * j, -0.02}), down.push_back({0, 0, -1});
  EXPECT_THROW(check_obstacle_faces(ObstacleGeometry(Obstacle::mesh("plate", plate)), bottom, Pose{}, 0.1), std::invalid_argument);
  EXPECT_TRUE(check_obstacle_faces(ObstacleGeometry(Obstacle::mesh("plate", plate)), bottom, Pose{}, 0.1, down));
  try {
    check_obstacle_faces(ObstacleGeometry(Obstacle::mesh("plate", flipped(plate))), bottom, Pose{}, 0.1, down);
    ADD_FAILURE() << "a plate facing away was accepted";
  } catch (const std::invalid_argument &e) {
    EXPECT_NE(std::string(e.what()).find("(25 of the 25 body vertices within reach of its faces face their back)"), std::string::npos) << e.what();
  }
  // Turned by the pose, the plate's normals turn with it: tilted 170 degrees it faces away.
  EXPECT_THROW(check_obstacle_faces(ObstacleGeometry(Obstacle::mesh("plate", plate)), bottom, Pose::turn({1, 0, 0}, 170, {0, 0, 0}), 0.1, down), std::invalid_argument);
}

TEST(ContactGeometry, ObstacleSurfacesToDraw)
{
  // A sphere: 162 vertices on it, closed, facing out (its volume within 5 % of the ball's at
  // this refinement); a plane: a patch in the plane, facing along its normal, centred under the
  // bodies' box; a mesh: its own triangles.
  const SurfaceMesh s = obstacle_surface(Obstacle::sphere("s", {1, 2, 3}, 0.5), {0, 0, 0}, {1, 1, 1});
  ASSERT_EQ(s.num_vertices(), 162);
  EXPECT_TRUE(validate_open_surface(s));
  double volume = 0;
  for (int t = 0; t < s.num_triangles(); ++t) {
    const auto &tri = s.triangles[t];
    EXPECT_NEAR(norm(s.vertices[tri[0]] - Vec3{1, 2, 3}), 0.5, 1e-15);
    volume += dot(s.vertices[tri[0]] - Vec3{1, 2, 3}, cross(s.vertices[tri[1]] - Vec3{1, 2, 3}, s.vertices[tri[2]] - Vec3{1, 2, 3})) / 6;
  }
  const double ball = 4.0 / 3 * M_PI * 0.125;
  EXPECT_GT(volume, 0.95 * ball);
  EXPECT_LT(volume, ball);
  const Vec3 n = normalized(Vec3{0, 1, 1});
  const SurfaceMesh p = obstacle_surface(Obstacle::plane("p", {0, 0, -1}, {0, 2, 2}), {0, 0, 0}, {2, 2, 2});
  Vec3 centre{0, 0, 0};
  for (const Vec3 &v : p.vertices) {
    EXPECT_NEAR(dot(v - Vec3{0, 0, -1}, n), 0, 1e-14);
    centre = centre + (1.0 / p.num_vertices()) * v;
  }
  for (int t = 0; t < p.num_triangles(); ++t) EXPECT_NEAR(norm(p.triangle_normal(t) - n), 0, 1e-14);
  const Vec3 under = Vec3{1, 1, 1} - dot(Vec3{1, 1, 1} - Vec3{0, 0, -1}, n) * n;
  EXPECT_NEAR(norm(centre - under), 0, 1e-13);
  double side = 0;
  for (const Vec3 &v : p.vertices) side = std::max(side, norm(v - under));
  EXPECT_NEAR(side, 1.5 * std::sqrt(12.0) / std::sqrt(2.0), 1e-12); // half the diagonal of a square of side 1.5 x the box's diagonal
  SurfaceMesh box;
  add_cube(box, {0, 0, 0});
  EXPECT_EQ(obstacle_surface(Obstacle::mesh("m", box), {0, 0, 0}, {1, 1, 1}).triangles, box.triangles);
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
  SurfaceMesh twisted; // two triangles that traverse their shared edge the same way
  twisted.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  twisted.triangles = {{0, 1, 2}, {0, 3, 2}};
  EXPECT_NE(message(Obstacle::mesh("m", twisted)).find("obstacle 'm': mesh 'm': inconsistent orientation: triangles 0 and 1 both traverse edge"), std::string::npos)
      << message(Obstacle::mesh("m", twisted));
  SurfaceMesh fin = twisted; // three triangles on one edge
  fin.vertices.push_back({0.5, 0.5, 1});
  fin.triangles = {{0, 1, 2}, {2, 3, 0}, {0, 2, 4}};
  EXPECT_NE(message(Obstacle::mesh("m", fin)).find("non-manifold edge (0, 2)"), std::string::npos) << message(Obstacle::mesh("m", fin));
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
  // A small cube standing on the middle of the big one's top face: its bottom vertices lie on
  // that face (winding number 1/2 there), the rest outside: a body of its own, not a cavity.
  SurfaceMesh stacked;
  add_cube(stacked, {0, 0, 0}, 2.0);
  add_cube(stacked, {0.5, 0.5, 2.0}, 1.0);
  const Bodies two = find_bodies(stacked);
  EXPECT_EQ(two.count, 2);
  EXPECT_EQ(two.of_vertex[8], 1);
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
  // Names that cannot name the result's datasets, or that clash with a body's force.
  auto named = [](const std::string &name) { return R"({"name": )" + name + R"(, "plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}})"; };
  EXPECT_NE(error(R"("contact": {"obstacles": [)" + named(R"("a/b")") + "]}}").find("p.json: contact.obstacles[0].name: the name \"a/b\" cannot name the result's datasets"),
            std::string::npos);
  EXPECT_NE(error(R"("contact": {"obstacles": [)" + named(R"(".")") + "]}}").find("contact.obstacles[0].name: the name '.' cannot name"), std::string::npos);
  const std::string tab = error(R"("contact": {"obstacles": [)" + named(R"("tab\tle")") + "]}}");
  EXPECT_NE(tab.find("the name \"tab\\tle\" cannot name the result's datasets (/contact/forces/<name>, /obstacles/<name>): it holds a control character"), std::string::npos) << tab;
  EXPECT_NE(error(R"("contact": {"obstacles": [)" + named(R"("")") + "]}}").find("contact.obstacles[0].name: expected a non-empty string"), std::string::npos);
  EXPECT_NE(error(R"("contact": {"bodies": true, "obstacles": [)" + plane + "," + named(R"("body_12")") + "]}}")
                .find("contact.obstacles[1].name: the name 'body_12' is that of a body's force in the result"),
            std::string::npos);
  EXPECT_EQ(error(R"("contact": {"obstacles": [)" + named(R"("body_12")") + "]}}"), "no error");       // no bodies' forces without "bodies"
  EXPECT_EQ(error(R"("contact": {"bodies": true, "obstacles": [)" + named(R"("body_x")") + "]}}"), "no error");
  EXPECT_NE(error(R"("contact": {"obstacles": [{"name": "a", "plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}, "sphere": {"center": [0, 0, 0], "radius": 1}}]}})")
                .find("has more than one of 'plane', 'sphere', 'mesh'"),
            std::string::npos);
}
