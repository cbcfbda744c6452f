// Contact on the H² reference (reference/h2_reference.hpp) against the dense one: the Hertz
// hemisphere on a plane (meshes/hertz_hemisphere.msh, 3.8k unknowns) solved by the contact
// engine over both; the H² reference's approximate columns corrected by accurate solves.
#include "solve_helpers.hpp"

#include "hssbem/contact/contact_engine.hpp"
#include "hssbem/petsc/krylov.h"
#include "hssbem/reference/h2_reference.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

using namespace hssbem;
using namespace hssbem::test;

namespace {

constexpr double E = 1000, nu = 0.3, delta = 0.05;

struct ContactRun {
  ContactSolution sol;
  ContactFrameReport rep;
};

ContactRun contact(const ProblemSetup &s, const NodeConditions &base, const ReferenceFactorization &ref)
{
  ContactOptions opt;
  opt.reach = 0.05;
  ContactEngine engine(*s.disc, ref, {Obstacle::plane("table", {0, 0, 0}, {0, 0, 1})}, {}, opt);
  ContactRun r;
  r.rep = engine.solve(selection_of(base), {Vec3{0, 0, 0}}, r.sol);
  return r;
}

/// A problem's dense reference and its H² one (the driver's H² defaults, `leaf_size` if given).
struct References {
  ProblemSetup s;
  std::unique_ptr<BemOperator> op;
  NodeConditions base;
  std::unique_ptr<DenseReference> dense;
  std::unique_ptr<H2Reference> h2;
  References(const std::string &mesh, BoundaryRule held, int leaf_size = 0)
  {
    ProblemSpec spec = spec_for(mesh, E, nu);
    spec.rules = {std::move(held)};
    spec.contact.present = true;
    s = setup_problem(std::move(spec), ProblemOverrides{});
    op = std::make_unique<BemOperator>(*s.disc, s.material);
    base = apply_rules(s.spec.rules, *s.disc, s.spec.file);
    dense = std::make_unique<DenseReference>(*op, base.unknown_pattern());
    H2ReferenceOptions ho;
    ho.compression.rel_tol = 1e-5, ho.compression.single_precision = true;
    if (leaf_size > 0) ho.compression.leaf_size = leaf_size;
    h2 = std::make_unique<H2Reference>(*op, base.unknown_pattern(), ho, HssbemH2ReferenceKrylovCreate());
  }
};

/// The largest differences of displacement and pressure between two contact solutions, and the
/// largest values of the reference's, over the solutions added.
struct Differences {
  double du = 0, um = 0, dp = 0, pm = 0;
  void add(const ContactSolution &ref, const ContactSolution &other)
  {
    for (std::size_t i = 0; i < ref.u.size(); ++i) du = std::max(du, norm(other.u[i] - ref.u[i])), um = std::max(um, norm(ref.u[i]));
    for (std::size_t v = 0; v < ref.pressure.size(); ++v)
      dp = std::max(dp, std::abs(other.pressure[v] - ref.pressure[v])), pm = std::max(pm, ref.pressure[v]);
  }
};

} // namespace

TEST(ContactH2, HertzAgreesWithTheDenseReference)
{
  const References r("hertz_hemisphere.msh", rule(BoundaryRule::Kind::Displacement, region("flat"), {{0, 0, -delta}}));
  const H2Reference &h2 = *r.h2;
  const ContactRun d = contact(r.s, r.base, *r.dense), h = contact(r.s, r.base, h2);

  Differences diff;
  diff.add(d.sol, h.sol);
  const double du = diff.du, um = diff.um, dp = diff.dp, pm = diff.pm;
  const double F = d.sol.obstacle_force[0][2], dF = std::abs(h.sol.obstacle_force[0][2] - F);
  const H2ReferenceStats &st = h2.stats();
  std::printf("H2 reference: %lld columns, %d corrections (last %.1e), %lld accurate solves, %lld GMRES iterations; touching %lld (dense %lld)\n", st.columns,
              h.rep.corrections, h.rep.correction, st.solves, st.iterations, h.rep.active_vertices, d.rep.active_vertices);
  std::printf("H2 against dense: u %.2e, pressure %.2e (of the peak), force %.2e (relative)\n", du / um, dp / pm, dF / F);
  EXPECT_GE(d.rep.active_vertices, 20); // a real contact area
  EXPECT_GE(h.rep.corrections, 1);
  EXPECT_LE(h.rep.correction, 1e-8);
  // Measured: u 2.1e-5, pressure 2.0e-5 of the peak, force 2.1e-8 (the H² operator's own
  // difference from the dense one at the driver's 1e-5; the corrections end at 5e-13).
  EXPECT_LE(du, 6e-5 * um);
  EXPECT_LE(dp, 6e-5 * pm);
  EXPECT_LE(dF, 6e-8 * F);

  // The blocked solve of the columns against the factorization's own solve, column by column.
  const H2Factorization &Fh = h2.factorization();
  const int n = 3 * Fh.num_points(), nrhs = 5;
  std::vector<double> B(static_cast<std::size_t>(n) * nrhs), X(B.size()), x(n);
  for (std::size_t i = 0; i < B.size(); ++i) B[i] = std::sin(0.37 * static_cast<double>(i) + 1.0);
  std::copy(B.begin(), B.end(), X.begin());
  Fh.solve_block(X.data(), nrhs, n);
  double worst = 0;
  for (int c = 0; c < nrhs; ++c) {
    Fh.solve(&B[static_cast<std::size_t>(c) * n], x.data());
    double d = 0, s = 0;
    for (int i = 0; i < n; ++i) d = std::max(d, std::abs(X[static_cast<std::size_t>(c) * n + i] - x[i])), s = std::max(s, std::abs(x[i]));
    worst = std::max(worst, d / s);
  }
  std::printf("H2 factorization: blocked solve against single solves %.1e\n", worst);
  EXPECT_LE(worst, 3e-14); // measured 2.1e-15 (round-off, 10x)
}

TEST(ContactH2, ToolFramesAndFrictionAgreeWithTheDenseReference)
{
  // The bottom clamped, a tool (sphere) pressed into the top slides along x over four frames,
  // frictionless and with friction 0.3 (quasi-static steps: slip relative to the tool): on
  // the H² reference (columns W̃ corrected by accurate solves every frame) against the dense one.
  const References r("cube_l0.msh", rule(BoundaryRule::Kind::Displacement, region("z0"), {{0, 0, 0}}), 16); // leaves of 16: several levels on the small cube
  const ProblemSetup &s = r.s;
  const NodeConditions &base = r.base;
  const Obstacle tool = Obstacle::sphere("tool", {0.25, 0.5, 1.5 - 0.08}, 0.5);
  for (double mu : {0.0, 0.3}) {
    ContactSettings settings;
    settings.friction = mu;
    ContactEngine ed(*s.disc, *r.dense, {tool}, settings), eh(*s.disc, *r.h2, {tool}, settings);
    Differences diff;
    long long least = 1 << 30, corrections = 0;
    for (int f = 0; f < 4; ++f) {
      ContactSolution sd, sh;
      ed.solve(selection_of(base), {Vec3{0.1 * f, 0, 0}}, sd);
      const ContactFrameReport rh = eh.solve(selection_of(base), {Vec3{0.1 * f, 0, 0}}, sh);
      corrections += rh.corrections;
      least = std::min(least, rh.active_vertices);
      EXPECT_LE(rh.correction, 1e-8) << "mu " << mu << " frame " << f;
      diff.add(sd, sh);
    }
    const double du = diff.du, um = diff.um, dp = diff.dp, pm = diff.pm;
    std::printf("H2 against dense, a tool sliding over four frames, friction %.1f: u %.2e, pressure %.2e (of the peak); %lld corrections; at least %lld touching\n", mu, du / um,
                dp / pm, corrections, least);
    EXPECT_GT(least, 0);
    EXPECT_GE(corrections, 4);
    EXPECT_LE(du, 1.5e-6 * um); // measured 4.6e-7 (frictionless), 4.3e-7 (friction 0.3, the tool dragging the top)
    EXPECT_LE(dp, 1e-7 * pm);   // measured 2.8e-8, 3.1e-8
  }
}
