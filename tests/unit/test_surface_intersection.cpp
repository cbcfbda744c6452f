/// \file test_surface_intersection.cpp
/// The intersection check (mesh/surface_intersection.hpp): the triangle–triangle test on the
/// cases that decide it (crossing, touching, coplanar), the hierarchy against an all-pairs
/// search, and the meshes the validator refuses (bodies overlapping, a surface through itself)
/// or accepts (separate or touching bodies, cavities); and the scale check of the validator.
#include "hssbem/mesh/mesh.hpp"
#include "hssbem/mesh/surface_intersection.hpp"

#include "mesh/triangle_crossing.hpp"
#include "test_shapes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace hssbem;
using detail::Triangle;
using detail::triangles_cross;

namespace {

SurfaceMesh cube(double size = 1.0, Vec3 origin = {0, 0, 0})
{
  SurfaceMesh m;
  for (int k = 0; k < 8; ++k)
    m.vertices.push_back(origin + size * Vec3{double(k & 1), double((k >> 1) & 1), double((k >> 2) & 1)});
  m.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4}, {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  m.triangle_region.assign(m.triangles.size(), -1);
  m.source = "cube";
  return m;
}

SurfaceMesh merge(SurfaceMesh a, const SurfaceMesh &b)
{
  const int base = a.num_vertices();
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (auto t : b.triangles) a.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  a.triangle_region.resize(a.triangles.size(), -1);
  return a;
}

/// A sphere of (n+1)² vertices by latitude and longitude (poles collapsed into one vertex each).
SurfaceMesh uv_sphere(int n, double radius = 1.0, Vec3 centre = {0, 0, 0})
{
  SurfaceMesh m;
  const double pi = 3.14159265358979323846;
  m.vertices.push_back(centre + Vec3{0, 0, radius});
  for (int i = 1; i < n; ++i)
    for (int j = 0; j < 2 * n; ++j) {
      const double th = pi * i / n, ph = pi * j / n;
      m.vertices.push_back(centre + radius * Vec3{std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)});
    }
  m.vertices.push_back(centre + Vec3{0, 0, -radius});
  const int south = m.num_vertices() - 1;
  auto      at    = [n](int i, int j) { return 1 + (i - 1) * 2 * n + (j % (2 * n)); };
  for (int j = 0; j < 2 * n; ++j) {
    m.triangles.push_back({0, at(1, j), at(1, j + 1)});
    m.triangles.push_back({south, at(n - 1, j + 1), at(n - 1, j)});
    for (int i = 1; i < n - 1; ++i) {
      m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  }
  m.triangle_region.assign(m.triangles.size(), -1);
  m.source = "sphere";
  return m;
}

/// The cube origin + [0, size]^3 with n x n squares per face (unit_cube of test_shapes.hpp).
SurfaceMesh grid_cube(int n, double size = 1.0, Vec3 origin = {0, 0, 0}, bool diamond = false)
{
  SurfaceMesh m = test::unit_cube(n, diamond);
  for (Vec3 &v : m.vertices) v = origin + size * v;
  m.source = "grid cube";
  return m;
}

/// All pairs, for reference: the first (lowest first, then second) non-neighbouring pair that
/// crosses.
std::optional<TrianglePair> all_pairs(const SurfaceMesh &m, double eps)
{
  auto corners = [&](int t) { return Triangle{m.vertices[m.triangles[t][0]], m.vertices[m.triangles[t][1]], m.vertices[m.triangles[t][2]]}; };
  for (int t = 0; t < m.num_triangles(); ++t)
    for (int u = t + 1; u < m.num_triangles(); ++u) {
      bool shared = false;
      for (int a : m.triangles[t])
        for (int b : m.triangles[u]) shared |= a == b;
      if (!shared && triangles_cross(corners(t), corners(u), eps)) return TrianglePair{t, u};
    }
  return std::nullopt;
}

std::string validation_error(SurfaceMesh m)
{
  std::vector<std::string> notices;
  try {
    validate_and_orient(m, notices);
  } catch (const MeshError &e) {
    return e.what();
  }
  return "";
}

const Triangle k_base{Vec3{0, 0, 0}, Vec3{2, 0, 0}, Vec3{0, 2, 0}};

} // namespace

TEST(TriangleCrossing, PiercingAndApart)
{
  EXPECT_TRUE(triangles_cross(k_base, Triangle{Vec3{0.5, 0.5, -1}, Vec3{0.5, 0.5, 1}, Vec3{0.6, 0.4, 1}}, 1e-12));
  EXPECT_TRUE(triangles_cross(Triangle{Vec3{0.5, 0.5, -1}, Vec3{0.5, 0.5, 1}, Vec3{0.6, 0.4, 1}}, k_base, 1e-12)); // symmetric
  EXPECT_FALSE(triangles_cross(k_base, Triangle{Vec3{0.5, 0.5, 0.1}, Vec3{0.5, 0.5, 1}, Vec3{0.6, 0.4, 1}}, 1e-12));  // above
  EXPECT_FALSE(triangles_cross(k_base, Triangle{Vec3{3, 3, -1}, Vec3{3, 3, 1}, Vec3{3.1, 2.9, 1}}, 1e-12));        // beside the plane's crossing
  EXPECT_FALSE(triangles_cross(k_base, Triangle{Vec3{1.2, 1.2, -1}, Vec3{1.2, 1.2, 1}, Vec3{1.3, 1.1, 1}}, 1e-12)); // beyond the hypotenuse
}

TEST(TriangleCrossing, TouchingIsNotCrossing)
{
  // a corner on the face, an edge along the face, within the tolerance of it
  EXPECT_FALSE(triangles_cross(k_base, Triangle{Vec3{0.5, 0.5, 0}, Vec3{0.5, 0.5, 1}, Vec3{0.6, 0.4, 1}}, 1e-12));
  EXPECT_FALSE(triangles_cross(k_base, Triangle{Vec3{0.2, 0.2, 0}, Vec3{1, 0.5, 0}, Vec3{0.6, 0.4, 1}}, 1e-12));
  EXPECT_FALSE(triangles_cross(k_base, Triangle{Vec3{0.5, 0.5, -1e-13}, Vec3{0.5, 0.5, 1}, Vec3{0.6, 0.4, 1}}, 1e-12));
  EXPECT_TRUE(triangles_cross(k_base, Triangle{Vec3{0.5, 0.5, -1e-9}, Vec3{0.5, 0.5, 1}, Vec3{0.6, 0.4, 1}}, 1e-12));
  // edge to edge, crossing in a point
  EXPECT_FALSE(triangles_cross(k_base, Triangle{Vec3{1, -1, 0}, Vec3{1, 1, 0}, Vec3{1, 0, 1}}, 1e-12));
}

TEST(TriangleCrossing, CoplanarOverlapCountsWhenFacingTheSameWay)
{
  const Triangle shifted{Vec3{0.5, 0.5, 0}, Vec3{2.5, 0.5, 0}, Vec3{0.5, 2.5, 0}};
  EXPECT_TRUE(triangles_cross(k_base, shifted, 1e-12));
  const Triangle reversed{shifted[0], shifted[2], shifted[1]}; // bodies in contact, face to face
  EXPECT_FALSE(triangles_cross(k_base, reversed, 1e-12));
  const Triangle inside{Vec3{0.2, 0.2, 0}, Vec3{0.5, 0.2, 0}, Vec3{0.2, 0.5, 0}}; // no edge crosses
  EXPECT_TRUE(triangles_cross(k_base, inside, 1e-12));
  EXPECT_TRUE(triangles_cross(k_base, k_base, 1e-12)); // the same triangle twice (other vertex indices)
  const Triangle beside{Vec3{2, 0, 0}, Vec3{2, 2, 0}, Vec3{0, 2, 0}}; // shares the hypotenuse only
  EXPECT_FALSE(triangles_cross(k_base, beside, 1e-12));
}

TEST(SurfaceIntersection, ClosedSurfacesAndSeparateBodiesHaveNone)
{
  EXPECT_FALSE(find_intersection(cube()));
  EXPECT_FALSE(find_intersection(uv_sphere(24)));
  EXPECT_FALSE(find_intersection(merge(cube(), cube(1.0, {3, 0, 0}))));
  EXPECT_FALSE(find_intersection(merge(cube(4.0), cube(1.0, {1, 1, 1})))); // a cavity
  EXPECT_FALSE(find_intersection(merge(cube(), cube(1.0, {1, 0, 0}))));   // face to face: contact
  EXPECT_FALSE(find_intersection(cube(), cube(1.0, {1, 0, 0})));
}

TEST(SurfaceIntersection, OverlappingBodiesAreFoundAsAllPairsFindsThem)
{
  for (const Vec3 &shift : {Vec3{0.5, 0.5, 0.5}, Vec3{0.5, 0.0, 0.0}, Vec3{0.3, 0.2, 0.9}}) {
    const SurfaceMesh m   = merge(cube(), cube(1.0, shift));
    const auto        got = find_intersection(m);
    const auto        ref = all_pairs(m, 1e-10 * std::sqrt(3.0) * 2);
    ASSERT_TRUE(got && ref);
    EXPECT_EQ(got->first, ref->first);
    EXPECT_EQ(got->second, ref->second);
    EXPECT_LT(got->first, 12);
    EXPECT_GE(got->second, 12);
    const auto two = find_intersection(cube(), cube(1.0, shift));
    ASSERT_TRUE(two);
  }
}

TEST(SurfaceIntersection, SurfaceThroughItself)
{
  SurfaceMesh m = uv_sphere(12);
  m.vertices[0] = {0.05, 0.02, -1.5}; // the north pole pushed out through the south
  const auto got = find_intersection(m), ref = all_pairs(m, 1e-10 * 3.2);
  ASSERT_TRUE(got && ref);
  EXPECT_EQ(got->first, ref->first);
  EXPECT_EQ(got->second, ref->second);
  EXPECT_EQ(m.triangles[got->first][0], 0); // a triangle of the pole
}

TEST(SurfaceIntersection, RandomSoupsAgreeWithAllPairs)
{
  std::mt19937                           gen(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int                                    found = 0;
  for (int trial = 0; trial < 40; ++trial) {
    SurfaceMesh m;
    for (int t = 0; t < 60; ++t) {
      const Vec3 c{u(gen) * 4, u(gen) * 4, u(gen) * 4};
      for (int k = 0; k < 3; ++k) m.vertices.push_back(c + Vec3{u(gen) * 0.6, u(gen) * 0.6, u(gen) * 0.6});
      m.triangles.push_back({3 * t, 3 * t + 1, 3 * t + 2});
    }
    const auto got = find_intersection(m);
    Vec3       lo = m.vertices[0], hi = m.vertices[0];
    for (const Vec3 &x : m.vertices)
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], x[k]), hi[k] = std::max(hi[k], x[k]);
    const auto ref = all_pairs(m, 1e-10 * norm(hi - lo));
    ASSERT_EQ(bool(got), bool(ref)) << "trial " << trial;
    if (!got) continue;
    ++found;
    EXPECT_EQ(got->first, ref->first) << "trial " << trial;
    EXPECT_EQ(got->second, ref->second) << "trial " << trial;
  }
  EXPECT_GT(found, 10); // the soups are dense enough to cross: the comparison means something
}

TEST(MeshValidateIntersections, OverlapAndSelfIntersectionAreRefusedNamingTheTriangles)
{
  std::string e = validation_error(merge(cube(), cube(1.0, {0.5, 0.5, 0.5})));
  EXPECT_NE(e.find("mesh 'cube': triangles "), std::string::npos) << e;
  EXPECT_NE(e.find("intersect: the surfaces of components 0 and 1 pass through each other"), std::string::npos) << e;
  SurfaceMesh m = uv_sphere(12);
  m.vertices[0] = {0.05, 0.02, -1.5};
  e = validation_error(m);
  EXPECT_NE(e.find("intersect: the surface (component 0) passes through itself"), std::string::npos) << e;
  EXPECT_EQ(validation_error(merge(cube(4.0), cube(1.0, {1, 1, 1}))), ""); // the cavity stays a cavity
}

TEST(MeshValidateIntersections, SurfacesThatCrossAlongEdgesOrAtVerticesAreRefused)
{
  // Along edges: two cubes of 2 x 2 squares a face, the second shifted by half a side along each
  // axis, so that every line where their faces meet is a grid line of both. No two triangles'
  // interiors cross (find_intersection finds none); the second cube's corner (0.5, 0.5, 0.5)
  // lies inside the first, its far corner outside: it used to be taken for a cavity, flipped.
  const SurfaceMesh edges = merge(grid_cube(2), grid_cube(2, 1.0, {0.5, 0.5, 0.5}));
  EXPECT_FALSE(find_intersection(edges));
  std::string e = validation_error(edges);
  EXPECT_NE(e.find("mesh 'grid cube': the surfaces of component 0 and component 1 pass through each other along triangle edges or at vertices: vertex "), std::string::npos) << e;
  EXPECT_NE(e.find("(of component 0) lies inside component 1, vertex "), std::string::npos) << e;
  // At vertices: an octahedron whose equator is the square inscribed in the top face of a cube
  // (its edges the face's diagonals, its corners the face's vertices), one pole above the face
  // and one below: the two surfaces meet only along those shared edges and vertices.
  SurfaceMesh octahedron;
  octahedron.vertices = {{0.5, 0, 1}, {1, 0.5, 1}, {0.5, 1, 1}, {0, 0.5, 1}, {0.5, 0.5, 1.3}, {0.5, 0.5, 0.7}};
  for (int k = 0; k < 4; ++k) {
    octahedron.triangles.push_back({k, (k + 1) % 4, 4});
    octahedron.triangles.push_back({(k + 1) % 4, k, 5});
  }
  const SurfaceMesh vertices = merge(grid_cube(2, 1.0, {0, 0, 0}, true), octahedron);
  EXPECT_FALSE(find_intersection(vertices));
  e = validation_error(vertices);
  EXPECT_NE(e.find("pass through each other along triangle edges or at vertices"), std::string::npos) << e;
  // Through triangle interiors: still named by the triangles (above); coinciding surfaces (the
  // same cube twice, facing opposite ways: no triangle pair crosses) are refused too.
  SurfaceMesh reversed = grid_cube(2);
  for (auto &t : reversed.triangles) std::swap(t[1], t[2]);
  e = validation_error(merge(grid_cube(2), reversed));
  EXPECT_NE(e.find("the surfaces of component 0 and component 1 coincide"), std::string::npos) << e;
}

TEST(MeshValidateIntersections, TouchingAndNestedSurfacesWhoseGridsLineUpAreAccepted)
{
  // Face to face (bodies in contact) with matching grids: the shared face's samples lie on the
  // other cube and decide nothing; a cavity touching nothing, wholly inside: kept a cavity.
  EXPECT_EQ(validation_error(merge(grid_cube(2), grid_cube(2, 1.0, {1, 0, 0}))), "");
  EXPECT_EQ(validation_error(merge(grid_cube(2), grid_cube(2, 0.5, {0.25, 0.25, 1}))), ""); // a smaller cube on the top face
  SurfaceMesh m = merge(grid_cube(4, 2.0), grid_cube(2, 1.0, {0.5, 0.5, 0.5}));
  std::vector<std::string> notices;
  validate_and_orient(m, notices);
  ASSERT_EQ(notices.size(), 1u);
  EXPECT_NE(notices[0].find("cavity boundary) was oriented inward; flipped"), std::string::npos) << notices[0];
  std::vector<int> surface(m.num_triangles(), 0);
  for (int t = grid_cube(4, 2.0).num_triangles(); t < m.num_triangles(); ++t) surface[t] = 1;
  const SurfaceNesting n = nest_surfaces(m, surface, 2);
  EXPECT_FALSE(n.crossing);
  EXPECT_TRUE(n.inside[1][0]);
  EXPECT_FALSE(n.inside[0][1]);
}

TEST(MeshValidateScale, SizeAndDigitsOfTheCoordinates)
{
  SurfaceMesh big = cube(1e120);
  std::string e   = validation_error(big);
  EXPECT_NE(e.find("its size (bounding-box diagonal 1.7"), std::string::npos) << e;
  EXPECT_NE(e.find("rescale the coordinates"), std::string::npos) << e;
  EXPECT_NE(validation_error(cube(1e-40)).find("lies outside [1e-30, 1e+30]"), std::string::npos);
  e = validation_error(cube(1.0, {1e15, 0, 0}));
  EXPECT_NE(e.find("keep only 0.71 significant digits of the mean edge length (1.1)"), std::string::npos) << e;
  EXPECT_NE(e.find("translate the mesh near the origin"), std::string::npos) << e;
  EXPECT_EQ(validation_error(cube(1e-3, {1e6, 2e6, 0})), "");  // UTM-like: 6.4 digits kept
  EXPECT_EQ(validation_error(cube(1e25)), "");
  EXPECT_EQ(validation_error(cube(1e-25)), "");
}
