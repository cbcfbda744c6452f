/* contact_instrument: how a simulator drives hssbem's contact API (session/contact_scene.hpp).

   A soft body is held on its bottom 10 % (by height). A spherical instrument comes down on its
   top and slides across it; the simulator only says where the instrument is, and the solver
   finds, every frame, which part of the surface touches, with what pressure (and, with
   friction, whether it sticks or slips). Between frames a haptic loop asks for the force on the
   instrument alone, for the instrument's newest position. Prints the set-up time, the reference
   the scene stands on and the rates it measured.

   Usage: contact_instrument -mesh FILE [-E 3000] [-nu 0.45] [-radius 0.3] [-depth 0.05]
                             [-frames 40] [-friction 0] [-haptic_per_frame 10]
                             [-reference auto|dense|h2]
   -reference: the reference factorization (ContactSceneReference::type): dense (fast frames, 8 N²
   bytes: up to about 15k unknowns), h2 (compressed: 40k unknowns and more), auto (dense while it
   fits the machine's memory).                                                                   */

static const char help[] = "contact_instrument: a spherical instrument pressed into a body and slid across it, with hssbem::ContactScene\n";

#include "hssbem/mesh/mesh.hpp"
#include "hssbem/session/contact_scene.hpp"
#include "hssbem/petsc/log.h"

#include <petscsys.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

using Clock = std::chrono::steady_clock;
static double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

static int Run(MPI_Comm comm)
{
  char      file[PETSC_MAX_PATH_LEN] = "", reference[16] = "auto";
  PetscReal E = 3000, nu = 0.45, radius = 0.3, depth = 0.05, friction = 0;
  PetscInt  frames = 40, haptic = 10;
  PetscBool has_mesh;

  PetscOptionsBegin(comm, NULL, "contact_instrument options", NULL);
  PetscCall(PetscOptionsString("-mesh", "Surface mesh (.msh, .stl, .off, .obj)", NULL, file, file, sizeof(file), &has_mesh));
  PetscCall(PetscOptionsReal("-E", "Young's modulus (Pa)", NULL, E, &E, NULL));
  PetscCall(PetscOptionsReal("-nu", "Poisson's ratio", NULL, nu, &nu, NULL));
  PetscCall(PetscOptionsReal("-radius", "Instrument radius, relative to the body's size", NULL, radius, &radius, NULL));
  PetscCall(PetscOptionsReal("-depth", "How far the instrument goes into the body, relative to its size", NULL, depth, &depth, NULL));
  PetscCall(PetscOptionsInt("-frames", "Frames of the slide", NULL, frames, &frames, NULL));
  PetscCall(PetscOptionsReal("-friction", "Coulomb coefficient between instrument and body", NULL, friction, &friction, NULL));
  PetscCall(PetscOptionsInt("-haptic_per_frame", "Force queries per frame (the haptic loop)", NULL, haptic, &haptic, NULL));
  PetscCall(PetscOptionsString("-reference", "Reference factorization: auto, dense or h2", NULL, reference, reference, sizeof(reference), NULL));
  PetscOptionsEnd();
  PetscCheck(has_mesh, comm, PETSC_ERR_USER_INPUT, "give -mesh FILE");

  /* The reference the scene stands on: left empty, the scene chooses (dense while it fits). */
  hssbem::ContactSceneReference ref;
  if (!std::strcmp(reference, "dense")) ref.type = hssbem::OperatorType::Dense;
  else if (!std::strcmp(reference, "h2")) ref.type = hssbem::OperatorType::H2;
  else if (std::strcmp(reference, "auto")) throw std::invalid_argument(std::string("-reference is auto, dense or h2, not ") + reference);

  hssbem::SurfaceMesh      mesh = hssbem::read_mesh(file);
  std::vector<std::string> notices;
  hssbem::validate_and_orient(mesh, notices);
  hssbem::Vec3 lo = mesh.vertices[0], hi = lo;
  for (const hssbem::Vec3 &v : mesh.vertices)
    for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], v[d]), hi[d] = std::max(hi[d], v[d]);
  const double size = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});

  /* What holds the body: its bottom 10 %, clamped. The rest of the surface may touch. */
  hssbem::ContactScene::Pattern held(mesh.vertices.size());
  for (std::size_t v = 0; v < held.size(); ++v) {
    const bool bottom = mesh.vertices[v][2] < lo[2] + 0.1 * (hi[2] - lo[2]);
    held[v]           = {bottom, bottom, bottom};
  }
  /* The instrument at its base position: resting on the top, at the body's -x end. */
  const double          r = radius * size;
  hssbem::Obstacle      tool = hssbem::Obstacle::sphere("tool", {lo[0] + 0.25 * (hi[0] - lo[0]), 0.5 * (lo[1] + hi[1]), hi[2] + r}, r);
  hssbem::ContactSettings settings;
  settings.friction = friction;

  const Clock::time_point t0 = Clock::now(); /* set-up, once: the reference factorization */
  hssbem::ContactScene    scene(mesh, hssbem::Material::from_young(E, nu), held, {tool}, settings, {}, hssbem::option_default::bem_feature_angle, ref);
  const double            t_setup = since(t0);
  PetscCall(PetscPrintf(comm, "contact_instrument: %d unknowns, set-up %.2f s on the %s reference (-reference %s)\n", 3 * scene.discretization().num_nodes(), t_setup,
                        scene.session().mat_type().c_str(), reference));

  double t_frames = 0, t_haptic = 0, fmax = 0;
  long long touching = 0, iterations = 0;
  for (PetscInt f = 0; f < frames; ++f) {
    const double       s = static_cast<double>(f) / std::max<PetscInt>(1, frames - 1);
    const hssbem::Vec3 at{0.5 * (hi[0] - lo[0]) * s, 0, -depth * size}; /* down, then across */
    Clock::time_point  t = Clock::now();
    scene.set_obstacle_offset("tool", at);
    const hssbem::ContactFrameReport &rep = scene.solve(); /* contact area, pressure, fields */
    t_frames += since(t);
    touching = std::max(touching, rep.active_vertices);
    iterations += rep.iterations;
    for (PetscInt h = 0; h < haptic; ++h) { /* the haptic loop: the force on the tool alone */
      const hssbem::Vec3 ahead{at[0] + 0.01 * size * (h + 1) / haptic, at[1], at[2]};
      t = Clock::now();
      const std::vector<hssbem::Vec3> F = scene.haptic_forces({ahead});
      t_haptic += since(t);
      fmax = std::max(fmax, hssbem::norm(F[0]));
    }
  }
  PetscCall(PetscPrintf(comm, "contact_instrument: frames %.3g Hz (%.0f ms each, %.2f iterations each, up to %lld vertices touching); haptic %.0f Hz; max |F| = %.4e\n", frames / t_frames, 1e3 * t_frames / frames, static_cast<double>(iterations) / frames, touching,
                        haptic * frames / std::max(t_haptic, 1e-12), fmax));
  const hssbem::Vec3 F = scene.obstacle_forces()[0]; /* the last frame's, to compare with the command line */
  PetscCall(PetscPrintf(comm, "contact_instrument: last frame, force on the tool (%.10e, %.10e, %.10e)\n", F[0], F[1], F[2]));
  return 0;
}

int main(int argc, char **argv)
{
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(HssbemInitializePackage());
  int rc = 0;
  try {
    rc = Run(PETSC_COMM_WORLD);
  } catch (const std::exception &e) {
    std::fprintf(stderr, "contact_instrument: %s\n", e.what());
    rc = 1;
  }
  PetscCall(PetscFinalize());
  return rc;
}
