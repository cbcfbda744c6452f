// Mesh obstacles in the contact engine (contact/obstacle.hpp): a box pressed with its edge into a
// block gives the same force however the box is triangulated (the signed distance by
// pseudo-normals: the vertices on the edge take its bisector, not one face's normal), and a plate
// beside the body, not over it, touches nothing (no contact past an open mesh's boundary).
#include "contact_case.hpp"
#include "test_shapes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

using namespace hssbem;
using namespace hssbem::test;

namespace {

using Kind = BoundaryRule::Kind;
constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();
constexpr double E = 1000, nu = 0.3;

/// The box [-h, h] x [-l, l] x [-h, h] with n x n squares a face, outward.
SurfaceMesh grid_box(int n, double h, double l)
{
  SurfaceMesh m = unit_cube(n);
  for (Vec3 &v : m.vertices) v = {h * (2 * v[0] - 1), l * (2 * v[1] - 1), h * (2 * v[2] - 1)};
  return m;
}

} // namespace

TEST(ContactObstacles, ABoxPressedWithItsEdgeGivesTheSameForceHoweverItIsMeshed)
{
  // The unit block (cube_l1, 1/8 squares) pushed up by delta at its bottom, into a rigid box
  // (0.4 x 1.5 x 0.4) turned 45 degrees about y whose lower edge lies along y on the block's top,
  // on its middle row of vertices (x = 0.5, gap 0). The box as 12 triangles and as 6 x 6 squares
  // a face: the same force (the target: 2 %), and only vertices under the edge in contact.
  constexpr double delta = 0.02, h = 0.2;
  const Pose place = Pose::turn({0, 1, 0}, 45, {0, 0, 0}, {0.5, 0.5, 1.0 + h * std::sqrt(2.0)});
  std::vector<Vec3> force;
  for (int n : {1, 6}) {
    SurfaceMesh box = grid_box(n, h, 0.75);
    for (Vec3 &v : box.vertices) v = place.apply(v);
    ProblemSpec spec = spec_for("cube_l1.msh", E, nu);
    spec.rules = {rule(Kind::Displacement, region("z0"), {{0, 0, delta}})};
    ContactCase c(spec, {Obstacle::mesh("box", box)});
    c.solve({{0, 0, 0}});
    const SurfaceMesh &m = c.s.disc->mesh();
    int under = 0;
    for (int v = 0; v < m.num_vertices(); ++v) {
      if (c.sol.status[v] == 0) continue;
      ++under;
      EXPECT_NEAR(m.vertices[v][2], 1.0, 1e-12) << "vertex " << v << " in contact off the top face";
      EXPECT_LE(std::abs(m.vertices[v][0] - 0.5), 0.125 + 1e-12) << "vertex " << v << " in contact away from the edge";
    }
    EXPECT_GE(under, 9); // the row under the edge at least
    force.push_back(c.sol.obstacle_force[0]);
    std::printf("box of %d x %d squares a face: force (%.6e, %.6e, %.6e), %d vertices touching, %lld iterations\n", n, n, force.back()[0], force.back()[1], force.back()[2], under,
                c.rep.iterations);
  }
  const double diff = norm(force[1] - force[0]) / norm(force[0]);
  std::printf("the two boxes' forces differ by %.2e (relative)\n", diff);
  EXPECT_LT(force[0][2], -0.01 * E * delta); // it presses the block down (a line load over the block's width)
  EXPECT_LE(std::abs(force[0][0]), 1e-12 * std::abs(force[0][2])); // symmetric about the edge (measured 0 and 5.9e-16)
  EXPECT_LE(diff, 1e-13); // the same geometry: round-off (measured 5.9e-16; the target was 2 %; the old tie rule: 0.40)
}

TEST(ContactObstacles, APlateBesideTheBodyTouchesNothing)
{
  // The unit cube (cube_l0) pushed down by delta at its top, rollers on x0 and y0, nothing under
  // it: a rigid translation. A rigid plate beside it (z = 0.52, x from 1.03 to 3, facing up): the
  // cube's vertices at mid-height on its face x = 1 lie within reach of the plate's edge (0.036),
  // behind its plane but past its edge. They used to take the distance to the edge as a
  // penetration and be pushed; now the plate touches nothing and the answer is the rigid
  // translation.
  constexpr double delta = 0.01;
  SurfaceMesh plate;
  plate.vertices = {{1.03, -1, 0.52}, {3, -1, 0.52}, {3, 2, 0.52}, {1.03, 2, 0.52}};
  plate.triangles = {{0, 1, 2}, {0, 2, 3}};
  ProblemSpec spec = spec_for("cube_l0.msh", E, nu);
  spec.rules = {rule(Kind::Displacement, region("z1"), {{k_nan, k_nan, -delta}}), rule(Kind::Displacement, region("x0"), {{0, k_nan, k_nan}}),
                rule(Kind::Displacement, region("y0"), {{k_nan, 0, k_nan}})};
  ContactCase c(spec, {Obstacle::mesh("plate", plate)});
  c.solve({{0, 0, 0}});
  double t = 0, u = 0;
  for (std::size_t i = 0; i < c.sol.t.size(); ++i) t = std::max(t, norm(c.sol.t[i])), u = std::max(u, norm(c.sol.u[i] - Vec3{0, 0, -delta}));
  std::printf("a plate beside the cube: %lld candidates, %lld touching, max |t| %.2e (E delta = %.0f), max |u - rigid| %.2e\n", c.rep.candidates, c.rep.active_vertices, t,
              E * delta, u);
  EXPECT_EQ(c.rep.active_vertices, 0);
  EXPECT_EQ(norm(c.sol.obstacle_force[0]), 0.0);
  EXPECT_LE(t, 1e-6 * E * delta); // as with no obstacle at all (a gap wider than the push: 3e-13 of E delta)
  EXPECT_LE(u, 1e-8 * delta);
}
