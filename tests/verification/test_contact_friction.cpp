// Friction against closed forms (contact/): a rigid sphere (radius R = 3) pressed into an elastic
// block that stands for a half-space (meshes/contact_block.msh: 1.2 × 1.2 × 0.6, its bottom
// clamped, its top at z = 0 refined to 0.02 within 0.28 of the centre; ν = 0.49), then
// - slid over it frame by frame: in steady sliding every contact point slips, so the tangential
//   force is μ times the normal force, along the tool's motion (frictionless: none);
// - pulled sideways by a growing displacement δ (Cattaneo–Mindlin partial slip, a rigid sphere on
//   an elastic half-space; Johnson, Contact Mechanics, 7.40–7.42): the stick radius
//   c = a (1 − Q/μP)^(1/3) and δ = 3 μ P (2 − ν) / (16 G a) [1 − (1 − Q/μP)^(2/3)]. Normal and
//   tangential problems decouple exactly only for elastically similar bodies: for a rigid
//   indenter Dundurs' β = (1 − 2ν) / (2 (1 − ν)) is 0.02 at ν = 0.49 (0 at 0.5, which the
//   Kelvin kernels do not take).
// The block is finite: its own compliance adds k Q to the tool's displacement (the far field of
// the net force, linear in Q). The contact area of the pressed tool held stuck (Mindlin's full
// stick: the haptic call's fixed-state system after a frame with μ = 100) measures it:
// δ = (C0 + k) Q_s, C0 = (2 − ν) / (8 G a) Mindlin's initial compliance; the partial-slip curve is
// compared after removing k Q. (Quasi-static frames with μ = 100 do not settle at the rim, where a
// stuck point must also lift: the discrete problem has no solution for such μ.) A flat tool
// (a/R = 0.05) keeps the curvature's share of the forces' directions small.
#include "solve_helpers.hpp"

#include "hssbem/contact/contact_engine.hpp"
#include "hssbem/reference/reference.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

using namespace hssbem;
using namespace hssbem::test;

namespace {

constexpr double E = 1000, nu = 0.49, R = 3, depth = 0.0075; // Hertz: a = sqrt(R depth) = 0.15

/// The block, its operator and dense reference (the bottom clamped), and W's columns: shared.
struct Block {
  ProblemSetup s;
  std::unique_ptr<BemOperator> op;
  NodeConditions base;
  std::unique_ptr<DenseReference> ref;
  std::shared_ptr<ReferenceColumns> columns;
  std::vector<double> area; ///< per vertex: its lumped area (top vertices have one node)
  Block()
  {
    ProblemSpec spec = spec_for("contact_block.msh", E, nu);
    spec.rules = {rule(BoundaryRule::Kind::Displacement, region("bottom"), {{0, 0, 0}})};
    spec.contact.present = true;
    s = setup_problem(std::move(spec), ProblemOverrides{});
    op = std::make_unique<BemOperator>(*s.disc, s.material);
    base = apply_rules(s.spec.rules, *s.disc, s.spec.file);
    ref = std::make_unique<DenseReference>(*op, base.unknown_pattern());
    columns = std::make_shared<ReferenceColumns>(*ref, ContactEngine::spatial_order(*s.disc));
    const std::vector<double> node_area = node_areas(*s.disc);
    area.assign(s.mesh->num_vertices(), 0.0);
    for (int i = 0; i < s.disc->num_nodes(); ++i) area[s.disc->node(i).vertex] += node_area[i];
  }
  /// An engine for the tool with friction mu; candidates: the top within 0.3 of its centre.
  std::unique_ptr<ContactEngine> engine(double mu) const
  {
    ContactSettings settings;
    settings.friction = mu;
    settings.candidate.assign(s.mesh->num_vertices(), 0);
    for (int v = 0; v < s.mesh->num_vertices(); ++v) {
      const Vec3 &x = s.mesh->vertices[v];
      settings.candidate[v] = x[2] == 0 && std::hypot(x[0], x[1]) < 0.3;
    }
    ContactOptions opt;
    opt.reach = 0.02;
    return std::make_unique<ContactEngine>(*s.disc, *ref, std::vector<Obstacle>{Obstacle::sphere("tool", {0, 0, R - depth}, R)}, settings, opt, columns);
  }
  /// The radius of the disc whose area the vertices of status `which` (1 stick; 0: every touching) cover.
  double radius(const ContactSolution &sol, int which) const
  {
    double sum = 0;
    for (int v = 0; v < s.mesh->num_vertices(); ++v)
      if (which ? sol.status[v] == which : sol.status[v] != 0) sum += area[v];
    return std::sqrt(sum / M_PI);
  }
};

Block &block()
{
  static Block b; // one reference for the tests of this file (~15 s)
  return b;
}

double shear_modulus() { return E / (2 * (1 + nu)); }
double hertz_radius(double P) { return std::cbrt(3 * P * R * (1 - nu * nu) / (4 * E)); }

} // namespace

TEST(ContactFriction, SteadySlidingPullsWithMuTimesTheNormalForce)
{
  // The tool pressed in at x = −0.05 and slid along x by 0.1 (two thirds of the contact radius)
  // in steps of 0.01 after a start of 0.001, 0.002, 0.004, 0.007: full sliding sets in once the
  // tool has moved about 1.5 μ P C0 (0.0035 here); the last three frames are steady.
  const Block &b = block();
  std::vector<double> path{0, 0.001, 0.002, 0.004, 0.007};
  for (double x = 0.01; x < 0.1 + 1e-12; x += 0.01) path.push_back(x);
  for (double mu : {0.3, 0.0}) {
    auto engine = b.engine(mu);
    double worst = 0, least_along = 1, Fn = 0;
    long long slip = 0, touching = 0;
    for (std::size_t f = 0; f < path.size(); ++f) {
      ContactSolution sol;
      const ContactFrameReport rep = engine->solve(selection_of(b.base), std::vector<Vec3>{{path[f] - 0.05, 0, 0}}, sol);
      if (f + 3 < path.size()) continue;
      const Vec3 &F = sol.obstacle_force[0]; // on the block: down and, with friction, along the motion
      const double ft = std::hypot(F[0], F[1]);
      Fn = -F[2];
      worst = std::max(worst, mu > 0 ? std::abs(ft / Fn - mu) / mu : ft / Fn);
      if (mu > 0) least_along = std::min(least_along, F[0] / ft);
      slip = rep.slip, touching = rep.active_vertices;
    }
    std::printf("steady sliding, friction %.1f: |F_t| / F_n off by %.2e (%s), direction along the motion %.5f; F_n %.4f; %lld of %lld touching vertices slip\n", mu, worst,
                mu > 0 ? "relative to mu" : "of F_n", least_along, Fn, slip, touching);
    EXPECT_GT(touching, 40);
    if (mu > 0) {
      EXPECT_LE(worst, 0.015); // Coulomb's law in steady sliding: |F_t| = μ F_n; target 3 %, measured 0.48 %
      EXPECT_GE(least_along, 0.999);
      EXPECT_EQ(slip, touching);
    } else {
      EXPECT_LE(worst, 5e-4); // target 1 % of F_n, measured 1.7e-4 (the mesh is not symmetric under the tool)
    }
  }
}

TEST(ContactFriction, CattaneoMindlinPartialSlip)
{
  // Frames: the tool pressed in, then moved along x by δ_i = i δ_max / 8 (δ_max brings Q near
  // 0.9 μ P), with μ = 0.3; the stuck reference: the pressed frame with μ = 100, then the haptic
  // call (its states fixed) at each δ_i.
  const Block &b = block();
  const double mu = 0.3, G = shear_modulus(), delta_max = 0.0031;
  const int n = 8;
  auto slipping = b.engine(mu), stuck = b.engine(100);
  ContactSolution pressed;
  stuck->solve(selection_of(b.base), std::vector<Vec3>{{0, 0, 0}}, pressed);
  double worst_c = 0, worst_d = 0, k_share = 0, a_err = 0;
  int checked = 0;
  for (int i = 0; i <= n; ++i) {
    const double d = delta_max * i / n;
    ContactSolution sol;
    slipping->solve(selection_of(b.base), std::vector<Vec3>{{d, 0, 0}}, sol);
    const double Qs = stuck->haptic_forces(std::vector<Vec3>{{d, 0, 0}})[0][0];
    const double P = -sol.obstacle_force[0][2], Q = sol.obstacle_force[0][0];
    const double a = hertz_radius(P), a_meas = b.radius(sol, 0), C0 = (2 - nu) / (8 * G * a);
    a_err = std::max(a_err, std::abs(a_meas / a - 1));
    if (i == 0) continue;
    const double ratio = Q / (mu * P);
    const double c_meas = b.radius(sol, 1), c = a_meas * std::cbrt(1 - ratio);
    const double k = d / Qs - C0, d_local = d - k * Q, d_mindlin = 1.5 * mu * P * C0 * (1 - std::pow(1 - ratio, 2.0 / 3.0));
    std::printf("Mindlin: delta %.5f: Q / mu P %.3f, c %.4f (Cattaneo %.4f, a %.4f; Hertz a %.4f); delta - k Q %.6f (Mindlin %.6f, %+.2f %%), k %.2f C0\n", d, ratio, c_meas, c,
                a_meas, a, d_local, d_mindlin, 100 * (d_local / d_mindlin - 1), k / C0);
    ASSERT_LT(ratio, 1);
    worst_c = std::max(worst_c, std::abs(c_meas - c) / a_meas);
    worst_d = std::max(worst_d, std::abs(d_local / d_mindlin - 1));
    k_share = std::max(k_share, k / C0);
    ++checked;
  }
  std::printf("Mindlin: stick radius within %.3f of a, the curve within %.2f %%; the block's compliance up to %.2f of Mindlin's; contact radius against Hertz's %.2f %%\n", worst_c,
              100 * worst_d, k_share, 100 * a_err);
  EXPECT_EQ(checked, n);
  EXPECT_LE(worst_c, 0.02);  // Cattaneo's stick radius: target 10 % of a, measured 0.7 %
  EXPECT_LE(worst_d, 0.013); // Mindlin's curve: target 5 %, measured 0.42 %
  EXPECT_LE(a_err, 0.016);   // the contact radius against Hertz's for the force: measured 0.53 %
}
