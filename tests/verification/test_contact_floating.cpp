// Bodies held by contact alone (docs/contact.md, "Bodies held by contact alone"): their rigid
// motions solved beside the contact, their forces balanced. Three cubes stacked on a table and
// pressed from above by a plate, all three free (frictionless: uniaxial compression, each
// interface carries E (δ − 2g) / 3; with friction the same balance); a ball pressed between two
// plates, against the same ball with the plates moved together (the contact is translation
// invariant: the same forces, the ball moved by the plates' shift); a body that would fly away
// refused with the body and its unbalanced force named.
#include "hand_problem.hpp"
#include "solve_helpers.hpp"
#include "test_shapes.hpp"

#include "hssbem/contact/contact_engine.hpp"
#include "hssbem/reference/reference.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

using namespace hssbem;
using namespace hssbem::test;

namespace {

constexpr double E = 1000, nu = 0.3;

/// `count` unit cubes (2 × 2 squares a face) stacked along z, a gap g between neighbours.
SurfaceMesh stack(int count, double g)
{
  const SurfaceMesh one = unit_cube(2);
  SurfaceMesh m;
  for (int k = 0; k < count; ++k) {
    const int base = m.num_vertices();
    for (const Vec3 &v : one.vertices) m.vertices.push_back(v + Vec3{0, 0, k * (1 + g)});
    for (const auto &t : one.triangles) m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    m.triangle_region.insert(m.triangle_region.end(), one.triangle_region.begin(), one.triangle_region.end());
  }
  std::vector<std::string> notices;
  validate_and_orient(m, notices);
  return m;
}

/// A hand-set problem whose bodies contact may hold alone: pinned (floating_pins), a dense
/// reference per body, the engine.
struct Floating : HandProblem {
  ContactSettings settings;
  std::unique_ptr<DenseReference> ref;
  std::unique_ptr<ContactEngine> engine;
  ContactSolution sol;
  ContactFrameReport rep;

  explicit Floating(SurfaceMesh m) : HandProblem(std::move(m), Material{E, nu}) {}
  void build(const std::vector<Obstacle> &obstacles)
  {
    std::vector<char> loaded(mesh.num_vertices(), 0);
    for (int i = 0; i < disc->num_nodes(); ++i)
      for (int c = 0; c < 3; ++c)
        if (!sel.displacement_known[i][c] && sel.known[i][c] != 0) loaded[disc->node(i).vertex] = 1;
    settings.pins = floating_pins(*disc, sel.displacement_known, obstacles, settings, {}, loaded);
    for (int j : settings.pins) sel.displacement_known[j / 3][j % 3] = true, sel.known[j / 3][j % 3] = 0;
    DenseReferenceOptions ro;
    ro.node_body = node_bodies(*disc);
    ref = std::make_unique<DenseReference>(*op, pattern(), ro);
    engine = std::make_unique<ContactEngine>(*disc, *ref, obstacles, settings);
  }
  const ContactFrameReport &solve(const std::vector<Vec3> &offsets) { return rep = engine->solve(sel, offsets, sol); }
};

double rel(const Vec3 &a, const Vec3 &b, double scale) { return norm(a - b) / scale; }

/// The stack of three cubes on a frictionless table (z = 0), pressed by a plate from above moved
/// down by δ: nothing prescribed, every cube held by contact alone.
void press_the_stack(double mu, double &F, Floating &p)
{
  const double g = 0.001, delta = 0.01;
  const std::vector<Obstacle> obstacles{Obstacle::plane("table", {0, 0, 0}, {0, 0, 1}), Obstacle::plane("plate", {0, 0, 3 + 2 * g}, {0, 0, -1})};
  p.settings.bodies = true;
  p.settings.friction = mu;
  p.build(obstacles);
  p.solve({{0, 0, 0}, {0, 0, -delta}});
  const Vec3 table = p.sol.obstacle_force[0], plate = p.sol.obstacle_force[1];
  F = table[2];
  const Vec3 up{0, 0, F};
  std::printf("stack (mu %.1f): pins %zu, table (%.6g, %.6g, %.6g), plate z %.6g, body forces z %.6g %.6g %.6g, translations z %.6g %.6g %.6g, balances %d, iterations %lld\n",
              mu, p.settings.pins.size(), table[0], table[1], table[2], plate[2], p.sol.body_force[0][2], p.sol.body_force[1][2], p.sol.body_force[2][2],
              p.sol.body_translation[0][2], p.sol.body_translation[1][2], p.sol.body_translation[2][2], p.rep.balances, p.rep.iterations);
  EXPECT_EQ(p.engine->floating_bodies(), (std::vector<int>{0, 1, 2}));
  // each interface carries the press (along z; with friction the faces' Poisson expansion leaves a
  // small tangential force at the table and the plate, equal and opposite); the stack as a whole
  // and the middle cube balance
  EXPECT_GT(F, 0.5 * E * (delta - 2 * g) / 3); // it is pressed (uniaxial: E (δ − 2g) / 3)
  EXPECT_NEAR(plate[2], -F, 1e-3 * F);
  EXPECT_NEAR(p.sol.body_force[0][2], -F, 1e-3 * F); // the bottom cube, pushed down by the middle one
  EXPECT_NEAR(p.sol.body_force[2][2], F, 1e-3 * F);  // the top cube, pushed up by the middle one
  EXPECT_LE(norm(plate + table) / F, 1e-6);
  EXPECT_LE(norm(p.sol.body_force[1]) / F, 1e-6); // the middle one: both interfaces, balanced
}

} // namespace

TEST(Floating, AStackOfThreeFreeCubesCarriesThePressThroughEveryInterface)
{
  // Frictionless, the stack is in uniaxial compression: each cube shortens by ε = (δ − 2g) / 3 and
  // carries F = E ε over its unit area; the cubes' surfaces move down on average by ε / 2,
  // 3ε / 2 + g, 5ε / 2 + 2g (their centroids).
  Floating p(stack(3, 0.001));
  double F = 0;
  press_the_stack(0.0, F, p);
  const double eps = (0.01 - 0.002) / 3, want = E * eps;
  std::printf("stack: F %.6g against E (δ - 2g) / 3 = %.6g: %.2e\n", F, want, std::abs(F - want) / want);
  EXPECT_NEAR(F, want, 1e-2 * want);
  const double moved[3] = {0.5 * eps, 1.5 * eps + 0.001, 2.5 * eps + 0.002};
  for (int b = 0; b < 3; ++b) {
    std::printf("cube %d: translation (%.3g, %.3g, %.6g) against -%.6g, rotation %.2e\n", b, p.sol.body_translation[b][0], p.sol.body_translation[b][1],
                p.sol.body_translation[b][2], moved[b], norm(p.sol.body_rotation[b]));
    EXPECT_NEAR(p.sol.body_translation[b][2], -moved[b], 1e-2 * moved[b]);
    // frictionless: the slide along x, y and the spin about z are undetermined (nothing resists or
    // drives them: they stay where the pins leave them, and the rigid part's fit reads them)
  }
}

TEST(Floating, AStackOfThreeFreeCubesWithFrictionBalances)
{
  Floating p(stack(3, 0.001));
  double F = 0;
  press_the_stack(0.3, F, p);
  const double want = E * (0.01 - 0.002) / 3;
  EXPECT_NEAR(F, want, 5e-2 * want); // friction holds the faces' Poisson expansion a little
}

TEST(Floating, ABallPressedBetweenTwoPlatesMovesWithThem)
{
  // The ball between two plates pressed in by δ each, and the same with both plates shifted down
  // by s: linearised contact is invariant under a common translation, so the forces are the
  // same and the ball moves by −s.
  const double delta = 0.01, s = 0.004;
  const std::vector<Obstacle> plates{Obstacle::plane("below", {0, 0, -1}, {0, 0, 1}), Obstacle::plane("above", {0, 0, 1}, {0, 0, -1})};
  Floating a(icosphere(2)), b(icosphere(2));
  a.build(plates), b.build(plates);
  a.solve({{0, 0, delta}, {0, 0, -delta}});
  b.solve({{0, 0, delta - s}, {0, 0, -delta - s}});
  const double F = a.sol.obstacle_force[0][2];
  std::printf("ball: pins %zu, forces z %.6g %.6g (shifted: %.6g %.6g), translation z %.6g, shifted %.6g (want %.6g), balances %d\n", a.settings.pins.size(), F,
              a.sol.obstacle_force[1][2], b.sol.obstacle_force[0][2], b.sol.obstacle_force[1][2], a.sol.body_translation[0][2], b.sol.body_translation[0][2],
              a.sol.body_translation[0][2] - s, b.rep.balances);
  EXPECT_GT(F, 1e-3 * E * delta); // it is pressed
  EXPECT_LE(rel(a.sol.obstacle_force[1], -1.0 * a.sol.obstacle_force[0], F), 1e-6);
  EXPECT_LE(rel(b.sol.obstacle_force[0], a.sol.obstacle_force[0], F), 1e-6);
  EXPECT_LE(rel(b.sol.obstacle_force[1], a.sol.obstacle_force[1], F), 1e-6);
  EXPECT_NEAR(b.sol.body_translation[0][2] - a.sol.body_translation[0][2], -s, 1e-6 * s);
}

TEST(Floating, ABodyThatWouldFlyAwayIsRefused)
{
  // A cube on a frictionless table with its top face pulled sideways: nothing resists the pull.
  Floating p(unit_cube(2));
  for (int i = 0; i < p.disc->num_nodes(); ++i) {
    const Vec3 x = p.disc->node_position(i), n = p.disc->node(i).normal;
    if (x[2] > 1 - 1e-12 && n[2] > 0.9) p.sel.known[i] = Vec3{1, 0, -10};
  }
  p.build({Obstacle::plane("table", {0, 0, 0}, {0, 0, 1})});
  try {
    p.solve({{0, 0, 0}});
    FAIL() << "no error";
  } catch (const std::runtime_error &e) {
    const std::string m = e.what();
    std::printf("%s\n", m.c_str());
    EXPECT_NE(m.find("contact: frame 0: body 0 (the surface of vertex 0) would fly away"), std::string::npos) << m;
    EXPECT_NE(m.find("the force (1,"), std::string::npos) << m; // the unit face's pull along x
  }
}

TEST(Floating, ABodyPressedOnATableByALoadBalancesIt)
{
  // The same cube pressed down by the load alone (no pull): the table carries the load.
  Floating p(unit_cube(2));
  for (int i = 0; i < p.disc->num_nodes(); ++i) {
    const Vec3 x = p.disc->node_position(i), n = p.disc->node(i).normal;
    if (x[2] > 1 - 1e-12 && n[2] > 0.9) p.sel.known[i] = Vec3{0, 0, -10};
  }
  p.build({Obstacle::plane("table", {0, 0, 0}, {0, 0, 1})});
  p.solve({{0, 0, 0}});
  double load = 0;
  std::vector<double> area = node_areas(*p.disc);
  for (int i = 0; i < p.disc->num_nodes(); ++i) load += area[i] * p.sel.known[i][2];
  std::printf("cube on the table: load %.9g, table %.9g, translation z %.6g\n", load, p.sol.obstacle_force[0][2], p.sol.body_translation[0][2]);
  EXPECT_NEAR(load, -10.0, 1e-12 * 10); // the face's area
  EXPECT_NEAR(p.sol.obstacle_force[0][2], 10.0, 1e-6 * 10);
  EXPECT_LE(std::abs(p.sol.obstacle_force[0][0]) + std::abs(p.sol.obstacle_force[0][1]), 1e-9 * 10);
}
