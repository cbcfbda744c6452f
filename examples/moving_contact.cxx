/* moving_contact: how a simulator drives hssbem's scene API (session/scene.hpp) in its frame loop.

   A body is clamped on its bottom 10 % (by height); an instrument presses a broad patch of the
   surface (the `fraction` of the vertices nearest to the contact point) and slides around the
   body's middle. Per frame the program tells the scene which vertices are in contact (pattern)
   and how far they are pushed (values), solves, and reads the displacement of the whole surface;
   a haptic loop then asks only for the contact forces, several times per frame. It prints the
   frame rates it measured.

   Usage: moving_contact -mesh FILE [-E 3000] [-nu 0.49] [-fraction 0.2] [-frames 60] [-step_deg 6]
                         [-depth 0.03] [-haptic_per_frame 10]                                      */

static const char help[] = "moving_contact: a contact patch sliding around a body, re-solved every frame with hssbem::Scene\n";

#include "hssbem/mesh/mesh.hpp"
#include "hssbem/petsc/log.h"
#include "hssbem/session/scene.hpp"

#include <petscsys.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

/* hssbem::Vec3 is a std::array: its arithmetic lives in namespace hssbem, where argument-dependent
   lookup does not look, so name it. */
using hssbem::operator+;
using hssbem::operator-;
using hssbem::operator*;

using Clock = std::chrono::steady_clock;
static double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

/* The instrument at angle phi: per vertex, whether it is in contact and how far it is pushed
   (deepest at the centre, along -(cos phi, sin phi, 0)). */
static void Contact(const hssbem::SurfaceMesh &mesh, double fraction, double depth, double phi, hssbem::Scene::Pattern &pattern, std::vector<hssbem::Vec3> &values,
                    const std::vector<bool> &clamped)
{
  hssbem::Vec3 lo = mesh.vertices[0], hi = mesh.vertices[0];
  for (const hssbem::Vec3 &v : mesh.vertices)
    for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], v[c]), hi[c] = std::max(hi[c], v[c]);
  const double       size = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  const hssbem::Vec3 dir{std::cos(phi), std::sin(phi), 0.0};
  const hssbem::Vec3 far{0.5 * (lo[0] + hi[0]) + 10 * size * dir[0], 0.5 * (lo[1] + hi[1]) + 10 * size * dir[1], 0.5 * (lo[2] + hi[2])};
  const int          nv = mesh.num_vertices();
  int                c  = 0;
  for (int v = 1; v < nv; ++v)
    if (hssbem::norm(mesh.vertices[v] - far) < hssbem::norm(mesh.vertices[c] - far)) c = v;
  std::vector<std::pair<double, int>> d(nv);
  for (int v = 0; v < nv; ++v) d[v] = {hssbem::norm(mesh.vertices[v] - mesh.vertices[c]), v};
  const int np = std::max(1, (int)std::lround(fraction * nv));
  std::partial_sort(d.begin(), d.begin() + np, d.end());
  const double R = 1.05 * std::max(d[np - 1].first, 1e-12);
  for (int v = 0; v < nv; ++v) {
    pattern[v] = {clamped[v], clamped[v], clamped[v]};
    values[v]  = {0, 0, 0}; /* clamped: u = 0; elsewhere traction-free */
  }
  for (int p = 0; p < np; ++p) {
    const int    v = d[p].second;
    const double w = 1 - (d[p].first / R) * (d[p].first / R);
    if (clamped[v]) continue;
    pattern[v] = {true, true, true};
    values[v]  = {-depth * size * w * dir[0], -depth * size * w * dir[1], 0.0};
  }
}

static int Run(MPI_Comm comm)
{
  char      file[PETSC_MAX_PATH_LEN] = "";
  PetscReal E = 3000, nu = 0.49, fraction = 0.2, step_deg = 6, depth = 0.03;
  PetscInt  frames = 60, haptic = 10;
  PetscBool has_mesh;

  PetscOptionsBegin(comm, NULL, "moving_contact options", NULL);
  PetscCall(PetscOptionsString("-mesh", "Surface mesh (.msh, .stl, .off, .obj)", NULL, file, file, sizeof(file), &has_mesh));
  PetscCall(PetscOptionsReal("-E", "Young's modulus (Pa)", NULL, E, &E, NULL));
  PetscCall(PetscOptionsReal("-nu", "Poisson's ratio", NULL, nu, &nu, NULL));
  PetscCall(PetscOptionsReal("-fraction", "Share of the vertices in contact", NULL, fraction, &fraction, NULL));
  PetscCall(PetscOptionsInt("-frames", "Frames of the sliding contact", NULL, frames, &frames, NULL));
  PetscCall(PetscOptionsReal("-step_deg", "Degrees the contact slides per frame", NULL, step_deg, &step_deg, NULL));
  PetscCall(PetscOptionsReal("-depth", "Indentation, relative to the body's size", NULL, depth, &depth, NULL));
  PetscCall(PetscOptionsInt("-haptic_per_frame", "Contact-force queries per frame (the haptic loop)", NULL, haptic, &haptic, NULL));
  PetscOptionsEnd();
  PetscCheck(has_mesh, comm, PETSC_ERR_USER_INPUT, "give -mesh FILE");

  hssbem::SurfaceMesh      mesh = hssbem::read_mesh(file);
  std::vector<std::string> notices;
  hssbem::validate_and_orient(mesh, notices);
  double zmin = INFINITY, zmax = -INFINITY;
  for (const hssbem::Vec3 &v : mesh.vertices) zmin = std::min(zmin, v[2]), zmax = std::max(zmax, v[2]);
  std::vector<bool>      clamped(mesh.vertices.size());
  hssbem::Scene::Pattern reference(mesh.vertices.size());
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    clamped[v]   = mesh.vertices[v][2] < zmin + 0.1 * (zmax - zmin);
    reference[v] = {clamped[v], clamped[v], clamped[v]};
  }

  /* Set-up, once: the reference pattern (clamped bottom, the rest free) is factored here. */
  const Clock::time_point t0 = Clock::now();
  hssbem::Scene           scene(mesh, hssbem::Material::from_young(E, nu), reference);
  const double            t_setup = since(t0);

  hssbem::Scene::Pattern    pattern(mesh.vertices.size());
  std::vector<hssbem::Vec3> values(mesh.vertices.size());
  double                    t_moving = 0, t_values = 0, t_haptic = 0, umax = 0, fmax = 0;
  for (PetscInt f = 0; f < frames; ++f) { /* the instrument slides: the contact pattern changes */
    Contact(mesh, fraction, depth, f * step_deg * M_PI / 180, pattern, values, clamped);
    Clock::time_point t = Clock::now();
    scene.set_pattern(pattern);
    scene.set_values(values);
    scene.solve();
    t_moving += since(t);
    for (const hssbem::Vec3 &u : scene.displacement()) umax = std::max(umax, hssbem::norm(u));
    for (int q = 0; q < 4; ++q) { /* then it presses deeper in place: values only */
      for (auto &v : values) v = 1.1 * v;
      t = Clock::now();
      scene.set_values(values);
      scene.solve();
      t_values += since(t);
    }
    for (PetscInt h = 0; h < haptic; ++h) { /* the haptic loop: contact forces alone */
      t = Clock::now();
      const std::vector<hssbem::Scene::VertexForce> forces = scene.contact_forces();
      t_haptic += since(t);
      hssbem::Vec3 total{0, 0, 0};
      for (const auto &vf : forces) total = total + vf.force;
      fmax = std::max(fmax, hssbem::norm(total));
    }
  }
  PetscCall(PetscPrintf(comm, "moving_contact: %d unknowns, set-up %.2f s; moving contact %.0f Hz, values only %.0f Hz, contact forces %.0f Hz; max |u| = %.4e, max |F| = %.4e\n",
                        3 * scene.discretization().num_nodes(), t_setup, frames / t_moving, 4 * frames / t_values, haptic * frames / std::max(t_haptic, 1e-12), umax, fmax));
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
    std::fprintf(stderr, "moving_contact: %s\n", e.what());
    rc = 1;
  }
  PetscCall(PetscFinalize());
  return rc;
}
