// Real-time scene benchmark: a broad contact patch moving around a body's middle, re-solved every
// frame by the scene engine (scene/dense_scene.hpp), side by side in one run with a dense LU per
// frame (refactor: LU of the frame's system from the stored H and G) and with a dense solve from
// scratch (assembly + LU, what the source paper's LAPACK baseline does per frame). Prints frame
// rates, the set-up's time and memory, the accuracy of sampled frames against the from-scratch
// solve, the values-only and haptic (contact forces only) rates, and the measured crossover
// between the Woodbury update and a refactorization as the number of switched unknowns grows.
//
//   bench_scene --mesh meshes/cardioid_832.msh --base base [--lame 1000,500 | --E 3000 --nu 0.49]
//               [--fraction 0.2] [--frames 60] [--step-deg 3] [--components 3] [--depth 0.04]
//               [--refactor-frames 5] [--krylov-frames 3] [--scratch-frames 2] [--check 6]
//               [--crossover] [--all-columns]
#include "bench_support.hpp"

#include "hssbem/mesh/mesh.hpp"
#include "hssbem/petsc/log.h"
#include "hssbem/petsc/scene_krylov.h"
#include "hssbem/problem/problem.hpp"
#include "hssbem/problem/setup.hpp"
#include "hssbem/scene/dense_scene.hpp"

#include <petscsys.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <numeric>
#include <string>
#include <vector>

namespace {

using namespace hssbem;

struct Args {
  std::string mesh, base = "base";
  double E = NAN, nu = NAN, lambda = 1000, mu = 500;
  double fraction = 0.2, step_deg = 3, depth = 0.04;
  int frames = 60, components = 3, refactor_frames = 5, krylov_frames = 3, scratch_frames = 2, check = 6;
  bool crossover = false;
  bool all_columns = false; ///< --all-columns: W for every unknown, not only the frames' candidates
  std::string csv, label = "scene"; ///< --csv FILE: append one row per printed line, tagged --label
  int single_from = 1024, single_fields_from = 1024;
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
    else if (k == "--base") a.base = next();
    else if (k == "--E") a.E = std::stod(next());
    else if (k == "--nu") a.nu = std::stod(next());
    else if (k == "--lame") {
      const std::string v = next();
      a.lambda = std::stod(v.substr(0, v.find(','))), a.mu = std::stod(v.substr(v.find(',') + 1));
    } else if (k == "--fraction") a.fraction = std::stod(next());
    else if (k == "--frames") a.frames = std::stoi(next());
    else if (k == "--step-deg") a.step_deg = std::stod(next());
    else if (k == "--components") a.components = std::stoi(next());
    else if (k == "--depth") a.depth = std::stod(next());
    else if (k == "--refactor-frames") a.refactor_frames = std::stoi(next());
    else if (k == "--krylov-frames") a.krylov_frames = std::stoi(next());
    else if (k == "--scratch-frames") a.scratch_frames = std::stoi(next());
    else if (k == "--check") a.check = std::stoi(next());
    else if (k == "--crossover") a.crossover = true;
    else if (k == "--all-columns") a.all_columns = true;
    else if (k == "--csv") a.csv = next();
    else if (k == "--label") a.label = next();
    else if (k == "--single-from") a.single_from = std::stoi(next());
    else if (k == "--single-fields-from") a.single_fields_from = std::stoi(next());
    else if (k.rfind("-", 0) == 0 && k.rfind("--", 0) != 0) { // a PETSc option and its value
      if (i + 1 < argc && argv[i + 1][0] != '-') ++i;
    } else throw std::invalid_argument("unknown argument " + k);
  }
  if (a.mesh.empty()) throw std::invalid_argument("give --mesh FILE");
  if (a.components != 1 && a.components != 3) throw std::invalid_argument("--components is 1 or 3");
  return a;
}

/// The contact of frame f: the patch of the `fraction` (of all vertices) free vertices nearest to
/// the free surface point at angle phi around the body's middle (clamped vertices never touch), pushed in along -(cos phi, sin phi, 0) with a smooth
/// profile (deepest at the centre); all three components prescribed, or only the one along the
/// dominant axis of the push (the others traction-free).
struct Scenario {
  const SurfaceMesh &mesh;
  const Discretization &disc;
  Args args;
  Vec3 centre{};
  double size = 0;

  std::vector<char> clamped; ///< vertices of the base region: never in the contact

  Scenario(const SurfaceMesh &m, const Discretization &d, const Args &a) : mesh(m), disc(d), args(a)
  {
    const VertexConditions vc = apply_rules(base(), m, "bench_scene");
    clamped.resize(m.vertices.size());
    for (std::size_t v = 0; v < clamped.size(); ++v) clamped[v] = vc.displacement_prescribed[v][0] && vc.displacement_prescribed[v][1] && vc.displacement_prescribed[v][2];
    Vec3 lo = m.vertices[0], hi = m.vertices[0];
    for (const Vec3 &v : m.vertices)
      for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], v[c]), hi[c] = std::max(hi[c], v[c]);
    for (int c = 0; c < 3; ++c) centre[c] = 0.5 * (lo[c] + hi[c]), size = std::max(size, hi[c] - lo[c]);
  }

  std::vector<BoundaryRule> base() const
  {
    BoundaryRule clamp;
    clamp.kind = BoundaryRule::Kind::Displacement;
    clamp.where.kind = Selector::Kind::Region;
    clamp.where.region_name = args.base;
    clamp.rows = {{0, 0, 0}};
    return {clamp};
  }

  std::vector<BoundaryRule> rules(int f, double depth_scale = 1.0, double fraction = -1) const
  {
    if (fraction < 0) fraction = args.fraction;
    const double phi = f * args.step_deg * M_PI / 180.0;
    const Vec3 dir{std::cos(phi), std::sin(phi), 0.0};
    const Vec3 far{centre[0] + 10 * size * dir[0], centre[1] + 10 * size * dir[1], centre[2]};
    const int nv = mesh.num_vertices();
    int c = -1;
    for (int v = 0; v < nv; ++v)
      if (!clamped[v] && (c < 0 || norm(mesh.vertices[v] - far) < norm(mesh.vertices[c] - far))) c = v;
    std::vector<std::pair<double, int>> d; // the free vertices by distance to the contact point
    for (int v = 0; v < nv; ++v)
      if (!clamped[v]) d.push_back({norm(mesh.vertices[v] - mesh.vertices[c]), v});
    const int np = std::min(static_cast<int>(d.size()), std::max(1, static_cast<int>(std::lround(fraction * nv))));
    std::partial_sort(d.begin(), d.begin() + np, d.end());
    const double R = std::max(d[np - 1].first, 1e-12) * 1.05;
    std::vector<std::pair<int, double>> patch;
    for (int p = 0; p < np; ++p) patch.push_back({d[p].second, 1.0 - (d[p].first / R) * (d[p].first / R)});
    std::sort(patch.begin(), patch.end());
    BoundaryRule r;
    r.kind = BoundaryRule::Kind::Displacement;
    r.where.kind = Selector::Kind::Vertices;
    const double nan = std::nan("");
    const int axis = std::abs(dir[0]) >= std::abs(dir[1]) ? 0 : 1;
    for (const auto &[v, w] : patch) {
      r.where.vertices.push_back(v);
      const double s = -args.depth * size * depth_scale * w;
      Vec3 row{s * dir[0], s * dir[1], 0.0};
      if (args.components == 1) row = {axis == 0 ? s * dir[0] : nan, axis == 1 ? s * dir[1] : nan, nan};
      r.rows.push_back(row);
    }
    std::vector<BoundaryRule> all = base();
    all.push_back(r);
    return all;
  }

  SystemSelection selection(const std::vector<BoundaryRule> &rules) const
  {
    return selection_of(apply_rules(rules, disc, "bench_scene"));
  }
};

struct Rate {
  std::vector<double> seconds;
  double max_err = 0;
  long long changed = 0, switched = 0, iterations = 0, refinements = 0;
  int rebuilt = 0;
  double update = 0, capacitance = 0, fields = 0; ///< summed seconds of the frames' parts
  std::map<std::string, int> strategies;
  void add(const SceneFrameReport &r)
  {
    seconds.push_back(r.seconds);
    changed += r.changed, switched += r.switched, iterations += r.iterations, rebuilt += r.rebuilt, refinements += r.refinements;
    update += r.update_seconds, capacitance += r.capacitance_seconds, fields += r.fields_seconds;
    strategies[scene_strategy_name(r.strategy)]++;
  }
  double mean() const { return seconds.empty() ? NAN : std::accumulate(seconds.begin(), seconds.end(), 0.0) / seconds.size(); }
  double p95() const
  {
    if (seconds.empty()) return NAN;
    std::vector<double> s = seconds;
    std::sort(s.begin(), s.end());
    return s[std::min(s.size() - 1, static_cast<std::size_t>(0.95 * s.size()))];
  }
};

/// The CSV of --csv (null: none) and the prefix of its rows (label, mesh, unknowns, fraction).
std::FILE *g_csv = nullptr;
std::string g_csv_prefix;

void print(const char *name, const Rate &r, const char *note = "")
{
  std::string used;
  for (const auto &[k, n] : r.strategies) used += (used.empty() ? "" : " ") + k + ":" + std::to_string(n);
  const double n = std::max<double>(1, r.seconds.size());
  std::printf("  %-34s %6zu %10.3f %10.3f %10.1f %10.1e %8.2f %8.2f %8.2f %6.2f  %s%s\n", name, r.seconds.size(), 1e3 * r.mean(), 1e3 * r.p95(), 1.0 / r.mean(), r.max_err,
              1e3 * r.update / n, 1e3 * r.capacitance / n, 1e3 * r.fields / n, r.refinements / n, used.c_str(), note);
  std::string line = name;
  line.erase(0, line.find_first_not_of(' '));
  if (g_csv)
    std::fprintf(g_csv, "%s,%s,%zu,%.4f,%.4f,%.2f,%.2e,%.3f,%.3f,%.3f,%.2f,%.0f,%.1f\n", g_csv_prefix.c_str(), line.c_str(), r.seconds.size(), 1e3 * r.mean(), 1e3 * r.p95(),
                 1.0 / r.mean(), r.max_err, 1e3 * r.update / n, 1e3 * r.capacitance / n, 1e3 * r.fields / n, r.refinements / n, r.switched / n, r.changed / n);
}

int run(const Args &a)
{
  SurfaceMesh mesh = read_mesh(a.mesh);
  std::vector<std::string> notices;
  validate_and_orient(mesh, notices);
  const Discretization disc(mesh, 40.0);
  const Material mat = std::isnan(a.E) ? Material::from_lame(a.lambda, a.mu) : Material::from_young(a.E, a.nu);
  const BemOperator op(disc, mat);
  const Scenario sc(mesh, disc, a);
  const int N = 3 * disc.num_nodes();
  std::printf("bench_scene: %s: %d vertices, %d triangles, %d unknowns; E %.4g nu %.3g; contact %.0f %% of the vertices (%d), %d component(s), "
              "moving %.1f deg per frame; OMP_NUM_THREADS=%s\n",
              a.mesh.c_str(), mesh.num_vertices(), mesh.num_triangles(), N, mat.E, mat.nu, 100 * a.fraction, static_cast<int>(std::lround(a.fraction * mesh.num_vertices())),
              a.components, a.step_deg, std::getenv("OMP_NUM_THREADS") ? std::getenv("OMP_NUM_THREADS") : "(unset)");

  if (!a.csv.empty()) {
    std::FILE *probe = std::fopen(a.csv.c_str(), "r");
    const bool fresh = !probe;
    if (probe) std::fclose(probe);
    g_csv = std::fopen(a.csv.c_str(), "a");
    if (!g_csv) throw std::invalid_argument("cannot write " + a.csv);
    if (fresh) std::fprintf(g_csv, "label,mesh,unknowns,fraction,line,frames,mean_ms,p95_ms,hz,max_err,update_ms,capacitance_ms,fields_ms,refinements,switched,changed\n");
    g_csv_prefix = a.label + "," + a.mesh.substr(a.mesh.find_last_of('/') + 1) + "," + std::to_string(N) + "," + std::to_string(a.fraction);
  }
  const SystemSelection reference = sc.selection(sc.base());
  SceneOptions so;
  so.single_from = a.single_from < 0 ? INT_MAX : a.single_from;
  so.single_fields_from = a.single_fields_from < 0 ? INT_MAX : a.single_fields_from;
  std::vector<SystemSelection> frames;
  for (int f = 0; f < a.frames; ++f) frames.push_back(sc.selection(sc.rules(f)));
  if (!a.all_columns && !a.crossover) { // the driver's default: W for the unknowns some frame switches or loads
    for (const SystemSelection &f : frames) mark_scene_candidates(reference, f, so.candidates);
    for (double depth : {0.5, 1.5}) mark_scene_candidates(reference, sc.selection(sc.rules(a.frames - 1, depth)), so.candidates); // the values-only frames' pattern
    std::printf("candidates: %ld of %d unknowns (W's columns computed)\n", static_cast<long>(std::count(so.candidates.begin(), so.candidates.end(), 1)), N);
  }
  DenseScene scene(op, reference, so, HssbemSceneKrylovCreate());
  std::printf("set-up %.2f s (assembly of H and G and LU of the reference %.2f s, W = A0^-1 K0' %.2f s); scene memory %.0f MB; peak RSS %.0f MB; measured %.1f GB/s, %.1f GF/s\n",
              scene.setup_seconds(), scene.reference_seconds(), scene.columns_seconds(), scene.memory_bytes() / 1e6, bench::peak_rss_mb(), scene.bandwidth() / 1e9, scene.flop_rate() / 1e9);

  std::vector<double> x;
  const int check_every = a.check > 0 ? std::max(1, a.frames / a.check) : a.frames + 1;

  std::printf("\n  %-34s %6s %10s %10s %10s %10s %8s %8s %8s %6s  %s\n", "per frame", "frames", "mean ms", "p95 ms", "Hz", "max err", "upd. ms", "cap. ms", "fld. ms", "refine",
              "strategies");
  Rate moving, changes, incremental, rebuilt, values, haptic, refactor, krylov, scratch;
  std::vector<std::vector<double>> solutions(a.frames);
  for (int f = 0; f < a.frames; ++f) { // the moving contact, auto
    const SceneFrameReport &rep = scene.solve(frames[f], x);
    moving.add(rep);
    if (rep.changed > 0) changes.add(rep);
    if (rep.changed > 0 && !rep.rebuilt) incremental.add(rep);
    if (rep.rebuilt) rebuilt.add(rep);
    if (f % check_every == 0) {
      const bench::DenseReference ref = bench::dense_reference(op, frames[f]);
      moving.max_err = std::max(moving.max_err, bench::rel_diff(x, ref.x));
      if (scratch.seconds.size() < static_cast<std::size_t>(a.scratch_frames)) scratch.seconds.push_back(ref.t_assembly + ref.t_lu);
    }
  }
  char note[160];
  std::snprintf(note, sizeof(note), "; switched %.0f, changed %.1f per frame, capacitance rebuilt %d times", double(moving.switched) / a.frames,
                double(moving.changed) / std::max(1, a.frames - 1), moving.rebuilt);
  print("moving contact (auto)", moving, note);
  changes.max_err = moving.max_err;
  print("  of which pattern changes", changes);
  incremental.max_err = moving.max_err;
  print("  of which incremental updates", incremental, "; without the capacitance's rebuilds (the first contact)");
  rebuilt.max_err = moving.max_err;
  print("  of which rebuilds", rebuilt, "; the capacitance built from nothing (the first contact)");

  // values only: the last pattern, the indentation deepening and easing (a haptic instrument)
  const int last = a.frames - 1;
  std::vector<double> sw;
  for (int f = 0; f < std::max(50, a.frames); ++f) {
    const SystemSelection sel = sc.selection(sc.rules(last, 1.0 + 0.5 * std::sin(0.3 * f)));
    values.add(scene.solve(sel, x));
    const Timer t;
    scene.solve_switched(sel, sw);
    haptic.seconds.push_back(t.seconds());
    if (a.check > 0 && f % 17 == 0) values.max_err = std::max(values.max_err, bench::rel_diff(x, bench::dense_reference(op, sel).x));
  }
  print("values only (whole surface)", values);
  print("contact forces only (haptic)", haptic);

  for (int f = 0; f < a.refactor_frames && f < a.frames; ++f) { // a dense LU per frame
    refactor.add(scene.solve(frames[f], x, SceneStrategy::Refactor));
    if (f == 0) refactor.max_err = bench::rel_diff(x, bench::dense_reference(op, frames[f]).x);
  }
  print("dense LU per frame (refactor)", refactor);
  for (int f = 0; f < a.krylov_frames && f + 1 < a.frames; ++f) {
    scene.solve(frames[f], x, SceneStrategy::Update);
    krylov.add(scene.solve(frames[f + 1], x, SceneStrategy::Krylov));
    if (f == 0) krylov.max_err = bench::rel_diff(x, bench::dense_reference(op, frames[f + 1]).x);
  }
  print("krylov (GMRES, previous factor)", krylov);
  std::snprintf(note, sizeof(note), "; the source paper's LAPACK baseline");
  print("dense from scratch (assembly + LU)", scratch, note);

  if (a.crossover) { // Woodbury (capacitance rebuilt) against refactor as the contact grows
    std::printf("\n  crossover: one frame from the reference pattern, contact fraction growing\n  %10s %10s %12s %12s %12s %12s\n", "fraction", "switched", "update ms",
                "refactor ms", "pred. upd.", "pred. ref.");
    for (double fr : {0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8}) {
      const SystemSelection sel = sc.selection(sc.rules(0, 1.0, fr));
      scene.solve(reference, x, SceneStrategy::Update); // back to the reference: the next update rebuilds from nothing
      const std::array<double, 5> pred = scene.predict(sel);
      const SceneFrameReport up = scene.solve(sel, x, SceneStrategy::Update);
      const SceneFrameReport re = scene.solve(sel, x, SceneStrategy::Refactor);
      std::printf("  %10.2f %10lld %12.2f %12.2f %12.2f %12.2f\n", fr, up.switched, 1e3 * up.seconds, 1e3 * re.seconds, 1e3 * pred[2], 1e3 * pred[3]);
    }
  }
  std::printf("\npeak RSS %.0f MB\n", bench::peak_rss_mb());
  if (g_csv) std::fclose(g_csv);
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
    std::fprintf(stderr, "bench_scene: %s\n", e.what());
    rc = 1;
  }
  PetscCall(PetscFinalize());
  return rc;
}
