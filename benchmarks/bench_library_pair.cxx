// Two bodies pressed together through the library (session/contact_scene.hpp), one reference per
// body: the figures a simulator linking hssbem gets for bench_contact's pair scenario.
//
//   bench_library_pair -mesh FILE [-depth 0.03] [-frames 20] [-candidates 0.2]
//                      [-reference auto|dense|h2] [-E 3000 -nu 0.45]
//
// FILE is two bodies face to face along z (scripts/gen_meshes.py --disk-pair GAP). As in
// bench_contact's pair: the lower body's bottom cap (its lower 20 % in z) clamped, the upper
// body's top cap pushed down, frame f by depth (f + 1) / frames; per body the `candidates`
// share of its vertices nearest the other body may touch. Prints the set-up time, each body's
// reference, the frame rate and the peak RSS.
#include "bench_support.hpp"

#include "hssbem/mesh/mesh.hpp"
#include "hssbem/petsc/log.h"
#include "hssbem/session/contact_scene.hpp"

#include <petscsys.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <ctime>
#include <vector>

namespace {

using namespace hssbem;
using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

double cpu_seconds()
{
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

/// The pair's held caps (bench_contact's pair_of): per vertex whether it is held, and whether it
/// is on the upper body's top cap (pushed); `candidate` the share of each body nearest the middle.
struct Pair {
  ContactScene::Pattern held;
  std::vector<bool> pushed;
  std::vector<char> candidate;
};

Pair pair_of(const SurfaceMesh &m, double share)
{
  Vec3 lo = m.vertices[0], hi = lo;
  for (const Vec3 &v : m.vertices)
    for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], v[d]), hi[d] = std::max(hi[d], v[d]);
  const double mid = 0.5 * (lo[2] + hi[2]), cap = 0.2 * (hi[2] - mid);
  const int nv = m.num_vertices();
  Pair p{ContactScene::Pattern(nv), std::vector<bool>(nv), std::vector<char>(nv, 0)};
  for (int v = 0; v < nv; ++v) {
    const double z = m.vertices[v][2];
    p.pushed[v] = z > hi[2] - cap;
    const bool h = p.pushed[v] || z < lo[2] + cap;
    p.held[v] = {h, h, h};
  }
  for (int side = 0; side < 2; ++side) {
    std::vector<int> vs;
    for (int v = 0; v < nv; ++v)
      if ((m.vertices[v][2] > mid) == (side == 0)) vs.push_back(v);
    std::sort(vs.begin(), vs.end(), [&](int a, int b) { return std::abs(m.vertices[a][2] - mid) < std::abs(m.vertices[b][2] - mid); });
    for (std::size_t k = 0; k < static_cast<std::size_t>(share * vs.size()); ++k) p.candidate[vs[k]] = 1;
  }
  return p;
}

int run(MPI_Comm comm)
{
  char file[PETSC_MAX_PATH_LEN] = "", reference[16] = "auto";
  PetscReal E = 3000, nu = 0.45, depth = 0.03, share = 0.2;
  PetscInt frames = 20;
  PetscBool has_mesh;
  PetscOptionsBegin(comm, NULL, "bench_library_pair options", NULL);
  PetscCall(PetscOptionsString("-mesh", "Two bodies face to face along z", NULL, file, file, sizeof(file), &has_mesh));
  PetscCall(PetscOptionsReal("-E", "Young's modulus (Pa)", NULL, E, &E, NULL));
  PetscCall(PetscOptionsReal("-nu", "Poisson's ratio", NULL, nu, &nu, NULL));
  PetscCall(PetscOptionsReal("-depth", "How far the upper body's top cap is pushed down at the last frame", NULL, depth, &depth, NULL));
  PetscCall(PetscOptionsReal("-candidates", "Share of each body's vertices (nearest the other) that may touch", NULL, share, &share, NULL));
  PetscCall(PetscOptionsInt("-frames", "Frames of the push", NULL, frames, &frames, NULL));
  PetscCall(PetscOptionsString("-reference", "Reference per body: auto, dense or h2", NULL, reference, reference, sizeof(reference), NULL));
  PetscOptionsEnd();
  PetscCheck(has_mesh, comm, PETSC_ERR_USER_INPUT, "give -mesh FILE");
  ContactSceneReference ref;
  if (!std::strcmp(reference, "dense")) ref.type = OperatorType::Dense;
  else if (!std::strcmp(reference, "h2")) ref.type = OperatorType::H2;
  else if (std::strcmp(reference, "auto")) throw std::invalid_argument(std::string("-reference is auto, dense or h2, not ") + reference);

  SurfaceMesh mesh = read_mesh(file);
  std::vector<std::string> notices;
  validate_and_orient(mesh, notices);
  const Pair pair = pair_of(mesh, share);
  ContactSettings settings;
  settings.bodies = true;
  settings.candidate = pair.candidate;

  const double cpu0 = cpu_seconds();
  const Clock::time_point t0 = Clock::now();
  ContactScene scene(mesh, Material::from_young(E, nu), pair.held, {}, settings, {}, option_default::bem_feature_angle, ref);
  const double t_setup = since(t0), cpu_setup = cpu_seconds() - cpu0;
  PetscCall(PetscPrintf(comm, "bench_library_pair: %d unknowns, %zu bodies; set-up %.1f s (CPU %.1f s) on the %s reference (-reference %s)\n",
                        3 * scene.discretization().num_nodes(), scene.session().body_reports().size(), t_setup, cpu_setup, scene.session().mat_type().c_str(), reference));
  for (std::size_t b = 0; b < scene.session().body_reports().size(); ++b) {
    const ContactBodyReport &r = scene.session().body_reports()[b];
    PetscCall(PetscPrintf(comm, "  body %zu: %d unknowns, %s reference, %.1f s, %.0f MB\n", b, r.unknowns, r.h2 ? "H2" : "dense", r.seconds, r.bytes / 1048576.0));
  }

  std::vector<double> seconds;
  double cpu_frames = 0;
  long long iterations = 0, touching = 0;
  std::vector<Vec3> values(mesh.vertices.size(), Vec3{0, 0, 0});
  for (PetscInt f = 0; f < frames; ++f) {
    const double push = -depth * (f + 1) / frames;
    for (std::size_t v = 0; v < values.size(); ++v) values[v] = {0, 0, pair.pushed[v] ? push : 0.0};
    const double c = cpu_seconds();
    const Clock::time_point t = Clock::now();
    scene.set_values(values);
    const ContactFrameReport &rep = scene.solve();
    seconds.push_back(since(t));
    cpu_frames += cpu_seconds() - c;
    iterations += rep.iterations;
    touching = rep.active_vertices;
  }
  std::vector<double> sorted = seconds;
  std::sort(sorted.begin(), sorted.end());
  double total = 0;
  for (double s : seconds) total += s;
  PetscCall(PetscPrintf(comm, "bench_library_pair: frames %.1f Hz (median %.1f ms, slowest %.1f ms, CPU %.1f ms each), %.2f iterations each; last frame %lld of %d vertices touching, body 0 pushed with %.4e; peak RSS %.0f MB\n",
                        frames / total, 1e3 * sorted[sorted.size() / 2], 1e3 * sorted.back(), 1e3 * cpu_frames / frames, static_cast<double>(iterations) / frames, touching,
                        mesh.num_vertices(), scene.body_forces()[0][2], bench::peak_rss_mb()));
  return 0;
}

} // namespace

int main(int argc, char **argv)
{
  PetscCall(PetscInitialize(&argc, &argv, NULL, "bench_library_pair: two bodies pressed together through hssbem::ContactScene\n"));
  PetscCall(HssbemInitializePackage());
  int rc = 0;
  try {
    rc = run(PETSC_COMM_WORLD);
  } catch (const std::exception &e) {
    std::fprintf(stderr, "bench_library_pair: %s\n", e.what());
    rc = 1;
  }
  PetscCall(PetscFinalize());
  return rc;
}
