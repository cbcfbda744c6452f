// Contact benchmark: frames of contact as physics (contact/contact_engine.hpp) on the dense
// reference factorization, one scenario per run, with the frames checked against cold static
// solves of the same obstacle positions (a fresh engine: no warm start, no cached columns) and
// the haptic call timed.
//
//   bench_contact --mesh FILE --scenario wall|instrument|table|pair [--frames 60] [--friction 0]
//                 [--target 0.2] [--check 3] [--haptic 20] [--E 3000 --nu 0.45] [--reach 0]
//                 [--candidates 0.2] [--double-fields]   (frictionless fields in double; single is the default)
//                 [--whole]   (pair: one dense system of the whole mesh, the bodies' blocks zeroed)
//                 [--slide S] (pair: the pushed cap also slides along x by S × the reach over the frames)
//                 [--pair-again F] (ContactOptions::pair_again: 0 pairs the bodies every frame)
//
//   wall:       the mesh's region "base" clamped; a rigid wall (plane) comes in along -x and
//               pushes until `target` of the vertices touch (the paper's cardioid: 20 %).
//   instrument: region "bottom" clamped; a sphere (radius 0.6) pressed into the top slides
//               along x across the organ, its depth such that `target` of the vertices touch.
//   table:      the top cap (z above 40 % of the height) held; a table (plane) rises under the
//               organ until `target` of the vertices touch.
//   pair:       two bodies face to face along z (scripts/gen_meshes.py --disk-pair): the upper
//               one's top cap (its upper 20 % in z) pushed down, the lower one's bottom cap
//               clamped, until `target` (default 0.1) of all vertices touch; `candidates` of
//               each body's vertices (those nearest the other body) are its contact candidates.
//               The reference is composite (reference/composite_reference.hpp): per body its own
//               dense LU and the columns of K₀′ the contact needs.
// Prints one line of figures per scenario (and "csv," the same as a CSV row).
#include "bench_support.hpp"

#include "hssbem/mesh/mesh.hpp"
#include "hssbem/post/post.hpp"
#include "hssbem/contact/contact_engine.hpp"
#include "hssbem/petsc/log.h"
#include "hssbem/problem/problem.hpp"
#include "hssbem/problem/setup.hpp"
#include "hssbem/reference/composite_reference.hpp"
#include "hssbem/reference/reference.hpp"

#include <petscsys.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <functional>
#include <string>
#include <vector>

namespace {

using namespace hssbem;

struct Args {
  std::string mesh, scenario = "wall";
  int frames = 60, check = 3, haptic = 20;
  double friction = 0, target = -1, E = 3000, nu = 0.45, reach = 0, candidates = 0.2;
  bool single_fields = true;
  bool whole = false; ///< pair: the whole mesh's dense reference with the bodies' blocks zeroed (node_body), for comparison
  double slide = 0;   ///< pair: the pushed cap's travel along x over the frames, in reaches
  double pair_again = ContactOptions{}.pair_again;
};

Args parse(int argc, char **argv)
{
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(k + " needs a value");
      return argv[++i];
    };
    if (k == "--mesh") a.mesh = next();
    else if (k == "--scenario") a.scenario = next();
    else if (k == "--frames") a.frames = std::stoi(next());
    else if (k == "--check") a.check = std::stoi(next());
    else if (k == "--haptic") a.haptic = std::stoi(next());
    else if (k == "--friction") a.friction = std::stod(next());
    else if (k == "--target") a.target = std::stod(next());
    else if (k == "--E") a.E = std::stod(next());
    else if (k == "--nu") a.nu = std::stod(next());
    else if (k == "--reach") a.reach = std::stod(next());
    else if (k == "--candidates") a.candidates = std::stod(next());
    else if (k == "--single-fields") a.single_fields = true;
    else if (k == "--double-fields") a.single_fields = false;
    else if (k == "--whole") a.whole = true;
    else if (k == "--slide") a.slide = std::stod(next());
    else if (k == "--pair-again") a.pair_again = std::stod(next());
    else if (k.rfind("-", 0) == 0 && k.rfind("--", 0) != 0) { // a PETSc option and its value
      if (i + 1 < argc && argv[i + 1][0] != '-') ++i;
    } else throw std::invalid_argument("unknown argument " + k);
  }
  if (a.mesh.empty()) throw std::invalid_argument("give --mesh FILE");
  if (a.scenario != "wall" && a.scenario != "instrument" && a.scenario != "table" && a.scenario != "pair")
    throw std::invalid_argument("--scenario is wall, instrument, table or pair");
  if (a.target < 0) a.target = a.scenario == "instrument" ? 0.05 : a.scenario == "pair" ? 0.1 : 0.2;
  if (a.scenario == "pair") a.haptic = 0; // no obstacle to move
  return a;
}

/// A scenario: what holds the body, the obstacle, and its offset at a "depth" s in [0, 1] of
/// frame f (the depth is calibrated to the target share of touching vertices).
struct Scenario {
  std::vector<BoundaryRule> rules;
  std::vector<Obstacle> obstacles; ///< none or one
  std::function<Vec3(int frame, int frames, double depth)> offset;
  /// pair: the known values' factor at frame f (the push), and the bodies' candidates
  std::function<double(int frame, int frames, double depth)> scale = [](int, int, double) { return 1.0; };
  ContactSettings settings;
};

BoundaryRule hold(Selector where, Vec3 u = {0, 0, 0})
{
  BoundaryRule r;
  r.kind = BoundaryRule::Kind::Displacement;
  r.where = std::move(where);
  r.rows = {u};
  return r;
}

/// The pair: the two bodies split at the middle of the z range; the upper body's top 20 % (in z)
/// pushed down (unit values, scaled per frame), the lower one's bottom 20 % clamped; per body the
/// `share` of its vertices nearest the middle are candidates.
void pair_of(const Args &a, const SurfaceMesh &m, const Vec3 &lo, const Vec3 &hi, Scenario &sc)
{
  const double mid = 0.5 * (lo[2] + hi[2]), cap = 0.2 * (hi[2] - mid);
  Selector top, bottom;
  top.kind = bottom.kind = Selector::Kind::Box;
  top.lo = {lo[0] - 1, lo[1] - 1, hi[2] - cap}, top.hi = {hi[0] + 1, hi[1] + 1, hi[2] + 1};
  bottom.lo = {lo[0] - 1, lo[1] - 1, lo[2] - 1}, bottom.hi = {hi[0] + 1, hi[1] + 1, lo[2] + cap};
  sc.rules = {hold(top, {0, 0, -1}), hold(bottom)};
  sc.scale = [](int f, int n, double depth) { return depth * (f + 1) / n; };
  sc.settings.bodies = true;
  sc.settings.candidate.assign(m.num_vertices(), 0);
  for (int side = 0; side < 2; ++side) {
    std::vector<int> vs;
    for (int v = 0; v < m.num_vertices(); ++v)
      if ((m.vertices[v][2] > mid) == (side == 0)) vs.push_back(v);
    std::sort(vs.begin(), vs.end(), [&](int p, int q) { return std::abs(m.vertices[p][2] - mid) < std::abs(m.vertices[q][2] - mid); });
    for (std::size_t k = 0; k < static_cast<std::size_t>(a.candidates * vs.size()); ++k) sc.settings.candidate[vs[k]] = 1;
  }
}

Scenario scenario_of(const Args &a, const SurfaceMesh &m)
{
  Vec3 lo = m.vertices[0], hi = lo;
  for (const Vec3 &v : m.vertices)
    for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], v[d]), hi[d] = std::max(hi[d], v[d]);
  Scenario sc;
  Selector where;
  where.kind = Selector::Kind::Region;
  if (a.scenario == "wall") {
    where.region_name = "base";
    sc.rules = {hold(where)};
    // The wall comes down on the top (the body's end away from its clamped base).
    sc.obstacles = {Obstacle::plane("wall", {0, 0, hi[2] + 1e-3}, {0, 0, -1})};
    sc.offset = [](int f, int n, double depth) { return Vec3{0, 0, -depth * (f + 1) / n}; };
  } else if (a.scenario == "instrument") {
    where.region_name = "bottom";
    sc.rules = {hold(where)};
    const double r = 0.6; // an instrument broad enough to touch 5 % of the organ
    sc.obstacles = {Obstacle::sphere("tool", {lo[0] + 0.25 * (hi[0] - lo[0]), 0.5 * (lo[1] + hi[1]), hi[2] + r}, r)};
    const double travel = 0.5 * (hi[0] - lo[0]);
    sc.offset = [travel](int f, int n, double depth) { return Vec3{travel * f / std::max(1, n - 1), 0, -depth}; };
  } else if (a.scenario == "pair") {
    pair_of(a, m, lo, hi, sc);
    sc.offset = [](int, int, double) { return Vec3{0, 0, 0}; };
  } else {
    where.kind = Selector::Kind::Box;
    where.lo = {lo[0] - 1, lo[1] - 1, lo[2] + 0.6 * (hi[2] - lo[2])};
    where.hi = {hi[0] + 1, hi[1] + 1, hi[2] + 1};
    sc.rules = {hold(where)};
    sc.obstacles = {Obstacle::plane("table", {0, 0, lo[2] - 1e-3}, {0, 0, 1})};
    sc.offset = [](int f, int n, double depth) { return Vec3{0, 0, depth * (f + 1) / n}; };
  }
  if (a.friction > 0) {
    for (Obstacle &o : sc.obstacles) o.friction = a.friction;
    if (sc.settings.bodies) sc.settings.friction = a.friction;
  }
  return sc;
}

double median(std::vector<double> v)
{
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

/// CPU seconds of this process (every thread): on a shared machine, what a frame costs apart
/// from the time it waited for a core.
double cpu_seconds()
{
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

double load_average()
{
  double l = NAN;
  if (FILE *f = std::fopen("/proc/loadavg", "r")) {
    if (std::fscanf(f, "%lf", &l) != 1) l = NAN;
    std::fclose(f);
  }
  return l;
}

struct Setup {
  ProblemSetup s;
  std::unique_ptr<BemOperator> op;
  NodeConditions base;
  std::unique_ptr<ReferenceFactorization> ref;
};

/// The pair's reference: per body its own dense LU and the columns of K₀′ the contact reads (the
/// candidates' and the pushed cap's).
std::unique_ptr<ReferenceFactorization> composite_reference(const Setup &st, const std::vector<char> &pattern, const Scenario &sc, const ContactOptions &opt, bool slide)
{
  const Discretization &disc = *st.s.disc;
  std::vector<char> kept = contact_loaded_unknowns(disc, pattern, sc.obstacles, sc.settings, opt);
  for (int i = 0; i < disc.num_nodes(); ++i) // the pushed cap's (every component when it slides)
    for (int c = 0; c < 3; ++c) kept[3 * i + c] = kept[3 * i + c] || st.base.value[i][c] != 0 || (slide && st.base.value[i][2] != 0);
  const BodyReferenceFactory dense = [](const BemOperator &op, std::vector<char> p, std::vector<char> k, int b) {
    DenseReferenceOptions o;
    o.reference_columns_only = true;
    o.kept_columns = std::move(k);
    const Timer t;
    auto ref = std::make_unique<DenseReference>(op, std::move(p), o);
    std::printf("  body %d: %d unknowns, dense reference in %.1f s (%.0f MB)\n", b, ref->num_unknowns(), t.seconds(), ref->memory_bytes() / 1e6);
    return ref;
  };
  return std::make_unique<CompositeReference>(*st.op, node_bodies(disc), pattern, kept, dense);
}

int run(const Args &a)
{
  Setup st;
  ProblemSpec spec;
  spec.file = "bench_contact";
  spec.mesh_path = a.mesh;
  spec.E = a.E, spec.nu = a.nu;
  spec.contact.present = true;
  {
    const SurfaceMesh m = read_mesh(a.mesh);
    spec.rules = scenario_of(a, m).rules;
  }
  st.s = setup_problem(spec, ProblemOverrides{});
  const Scenario sc = scenario_of(a, *st.s.mesh);
  st.op = std::make_unique<BemOperator>(*st.s.disc, st.s.material);
  st.base = apply_rules(st.s.spec.rules, *st.s.disc, "bench_contact");
  const int nv = st.s.mesh->num_vertices(), N = 3 * st.s.disc->num_nodes();
  std::printf("bench_contact: %s, scenario %s: %d vertices, %d unknowns, friction %.2g, target %.0f %% touching, %d frames; OMP_NUM_THREADS=%s, load %.2f\n", a.mesh.c_str(),
              a.scenario.c_str(), nv, N, a.friction, 100 * a.target, a.frames, std::getenv("OMP_NUM_THREADS") ? std::getenv("OMP_NUM_THREADS") : "unset", load_average());
  const std::vector<char> pattern = st.base.unknown_pattern();
  Timer t;
  ContactOptions opt;
  opt.reach = a.reach;
  opt.single_fields = a.single_fields;
  opt.pair_again = a.pair_again;
  const double cpu0 = cpu_seconds();
  if (sc.settings.bodies && !a.whole) st.ref = composite_reference(st, pattern, sc, opt, a.slide != 0);
  else {
    DenseReferenceOptions ro;
    ro.node_body = node_bodies(*st.s.disc);
    st.ref = std::make_unique<DenseReference>(*st.op, pattern, ro);
  }
  const double t_ref = t.seconds(), cpu_ref = cpu_seconds() - cpu0;
  const SystemSelection base_values = selection_of(st.base);
  auto values_at = [&](int f, double depth) { // the known values of frame f (the pair's push scales them)
    SystemSelection v = base_values;
    const double k = sc.scale(f, a.frames, depth);
    const double reach = a.reach > 0 ? a.reach : 0.05 * Box::of(st.s.mesh->vertices).diagonal();
    for (std::size_t i = 0; i < v.known.size(); ++i) { // the pushed cap: base value (0, 0, −1)
      const bool pushed = base_values.known[i][2] != 0;
      v.known[i] = k * v.known[i];
      if (pushed) v.known[i][0] += a.slide * reach * f / std::max(1, a.frames - 1);
    }
    return v;
  };
  auto offsets_at = [&](int f, double depth) { return sc.obstacles.empty() ? std::vector<Vec3>{} : std::vector<Vec3>{sc.offset(f, a.frames, depth)}; };
  const ContactSettings &settings = sc.settings;
  if (std::getenv("BENCH_CONTACT_MONITOR"))
    opt.monitor = [](const ContactIteration &it) { std::printf("    it %d: %lld touching, %lld changed, residual %.2e\n", it.iteration, it.active, it.changed, it.residual); };
  // One cache of W's columns for every engine below: the calibration's columns serve the frames.
  const auto columns = std::make_shared<ReferenceColumns>(*st.ref, ContactEngine::spatial_order(*st.s.disc));
  auto touching = [&](const ContactSolution &sol) {
    long long n = 0;
    for (std::int8_t s : sol.status) n += s != 0;
    return static_cast<double>(n) / nv;
  };
  // Calibrate the depth (bisection with a cold engine) so that the deepest frame touches `target`.
  double lo = 0, hi = a.scenario == "pair" ? 0.1 : 0.5, depth = 0;
  {
    ContactEngine probe(*st.s.disc, *st.ref, sc.obstacles, settings, opt, columns);
    const int deepest = a.scenario == "instrument" ? a.frames / 2 : a.frames - 1;
    for (int it = 0; it < 14; ++it) {
      depth = 0.5 * (lo + hi);
      ContactSolution sol;
      probe.solve(values_at(deepest, depth), offsets_at(deepest, depth), sol);
      if (std::getenv("BENCH_CONTACT_VERBOSE")) std::printf("  calibration: depth %.4f touches %.1f %%\n", depth, 100 * touching(sol));
      (touching(sol) < a.target ? lo : hi) = depth;
    }
  }
  // The frames, timed; columns for every frame's candidates computed first (prefetch).
  t.restart();
  ContactEngine engine(*st.s.disc, *st.ref, sc.obstacles, settings, opt, columns);
  std::vector<std::vector<Vec3>> placements;
  std::vector<SystemSelection> values;
  for (int f = 0; f < a.frames; ++f) placements.push_back(offsets_at(f, depth)), values.push_back(values_at(f, depth));
  engine.prefetch(placements);
  const double t_prefetch = columns->seconds(); // every column computed, the calibration's included
  const double cpu_setup = cpu_seconds() - cpu0; // the reference, the calibration and every column
  std::vector<double> seconds, cpu, haptic, pairing;
  int paired = 0;
  std::vector<std::vector<Vec3>> sampled;
  std::vector<int> sampled_frame;
  long long iterations = 0, max_it = 0, factorizations = 0, products = 0;
  double most = 0;
  for (int f = 0; f < a.frames; ++f) {
    ContactSolution sol;
    const double c0 = cpu_seconds();
    const ContactFrameReport rep = engine.solve(values[f], placements[f], sol);
    cpu.push_back(cpu_seconds() - c0);
    seconds.push_back(rep.seconds);
    pairing.push_back(rep.pair_seconds), paired += rep.paired;
    if (std::getenv("BENCH_CONTACT_VERBOSE"))
      std::printf("  frame %d: %.3f ms (detect %.3f, solve %.3f, fields %.3f), %lld iterations (%lld factored, %lld products), %lld rounds, %lld candidates, %lld touching%s; pairing %.3f ms%s\n", f,
                  1e3 * rep.seconds, 1e3 * rep.detect_seconds, 1e3 * rep.solve_seconds, 1e3 * rep.fields_seconds, rep.iterations, rep.factorizations, rep.products,
                  static_cast<long long>(rep.rounds), rep.candidates, rep.active_vertices, rep.rebuilt ? ", rebuilt" : "",
                  1e3 * rep.pair_seconds, rep.paired ? " (paired again)" : "");
    iterations += rep.iterations, max_it = std::max(max_it, rep.iterations);
    factorizations += rep.factorizations, products += rep.products;
    most = std::max(most, touching(sol));
    if (a.check > 0 && f % std::max(1, a.frames / a.check) == 0) sampled.push_back(sol.u), sampled_frame.push_back(f);
    for (int h = 0; h < a.haptic; ++h) { // the instrument moves on a little between frames
      const Vec3 next = placements[f][0] + (0.1 * (h + 1) / a.haptic) * ((f + 1 < a.frames ? placements[f + 1][0] : placements[f][0]) - placements[f][0]);
      const Timer th;
      const std::vector<Vec3> F = engine.haptic_forces({next});
      haptic.push_back(th.seconds());
      (void)F;
    }
  }
  // Cold static solves of the sampled frames: a fresh engine each (no warm start, its own
  // active-set inverse; W's columns are the same numbers whichever engine computes them).
  // Frictionless frames only: with friction a frame depends on the frames before it.
  double worst = 0, scale = 0;
  if (a.friction > 0) sampled.clear();
  for (std::size_t k = 0; k < sampled.size(); ++k) {
    ContactOptions cold = opt;
    cold.warm_start = false;
    ContactEngine fresh(*st.s.disc, *st.ref, sc.obstacles, settings, cold, columns);
    ContactSolution sol;
    fresh.solve(values[sampled_frame[k]], placements[sampled_frame[k]], sol);
    for (std::size_t i = 0; i < sol.u.size(); ++i) worst = std::max(worst, norm(sol.u[i] - sampled[k][i])), scale = std::max(scale, norm(sol.u[i]));
  }
  const double ms = 1e3 * median(seconds);
  std::printf("  set-up: reference %.1f s (CPU %.1f s; %.0f MB), columns %.1f s (%.0f MB), CPU %.1f s with the calibration; frames: median %.2f ms (%.0f Hz; CPU %.2f ms), slowest %.2f ms; iterations %.2f per frame (max %lld; "
              "friction: %.2f factorizations, %.1f GMRES products per frame); touching up to %.1f %%; cold static solves of %zu frames differ by %.1e (relative); haptic median %.1f us (%.0f Hz); peak RSS %.0f MB; load %.2f\n",
              t_ref, cpu_ref, st.ref->memory_bytes() / 1e6, t_prefetch, engine.memory_bytes() / 1e6, cpu_setup, ms, 1e3 / ms, 1e3 * median(cpu), 1e3 * *std::max_element(seconds.begin(), seconds.end()), static_cast<double>(iterations) / a.frames, max_it,
              static_cast<double>(factorizations) / a.frames, static_cast<double>(products) / a.frames, 100 * most, sampled.size(), scale > 0 ? worst / scale : worst, 1e6 * median(haptic), 1.0 / median(haptic), bench::peak_rss_mb(), load_average());
  if (settings.bodies)
    std::printf("  body pairing: %d of %d frames paired again (pair_again %g, slide %g reaches); pairing per frame median %.3f ms, slowest %.3f ms\n", paired, a.frames, a.pair_again, a.slide,
                1e3 * median(pairing), 1e3 * *std::max_element(pairing.begin(), pairing.end()));
  std::printf("csv,%s,%s,%d,%.2g,%d,%.2f,%.2f,%.3f,%.0f,%.3f,%.2f,%lld,%.3f,%.2e,%.2f,%.0f,%.2f\n", a.scenario.c_str(), a.mesh.c_str(), N, a.friction, a.frames, t_ref, t_prefetch, ms, 1e3 / ms, 1e3 * median(cpu),
              static_cast<double>(iterations) / a.frames, max_it, most, scale > 0 ? worst / scale : worst, 1e6 * median(haptic), bench::peak_rss_mb(), load_average());
  return 0;
}

} // namespace

int main(int argc, char **argv)
{
  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(HssbemInitializePackage());
  int rc = 0;
  try {
    rc = run(parse(argc, argv));
  } catch (const std::exception &e) {
    std::fprintf(stderr, "bench_contact: %s\n", e.what());
    rc = 1;
  }
  PetscCall(PetscFinalize());
  return rc;
}
