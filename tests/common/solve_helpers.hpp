// Solve a problem given in code through the library's dense path, for verification tests.
#pragma once

#include "hssbem/mesh/mesh.hpp"
#include "hssbem/post/post.hpp"
#include "hssbem/bem/rigid_modes.hpp"
#include "hssbem/session/static_session.hpp"
#include "hssbem/problem/setup.hpp"
#include "test_paths.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace hssbem::test {

struct Solved {
  ProblemSetup setup;
  NodalSolution sol;
};

inline std::string mesh_file(const std::string &name) { return std::string(HSSBEM_MESHES) + "/" + name; }

/// Two bodies in one mesh: the shipped unit cube and a copy of it `gap` above (z from 1 + gap
/// to 2 + gap), validated and oriented.
inline SurfaceMesh stacked_cubes(double gap)
{
  SurfaceMesh two = read_mesh(mesh_file("cube_l0.msh"));
  const SurfaceMesh one = two;
  for (const Vec3 &v : one.vertices) two.vertices.push_back(v + Vec3{0, 0, 1 + gap});
  for (const auto &t : one.triangles) two.triangles.push_back({t[0] + one.num_vertices(), t[1] + one.num_vertices(), t[2] + one.num_vertices()});
  two.triangle_region.insert(two.triangle_region.end(), one.triangle_region.begin(), one.triangle_region.end());
  std::vector<std::string> notices;
  validate_and_orient(two, notices);
  return two;
}

inline BoundaryRule rule(BoundaryRule::Kind kind, Selector where, std::vector<Vec3> rows)
{
  BoundaryRule r;
  r.kind = kind;
  r.where = std::move(where);
  r.rows = std::move(rows);
  return r;
}

inline Selector all_vertices() { return Selector{}; }

inline Selector region(const std::string &name)
{
  Selector s;
  s.kind = Selector::Kind::Region;
  s.region_name = name;
  return s;
}

inline Selector vertices(std::vector<int> v)
{
  Selector s;
  s.kind = Selector::Kind::Vertices;
  s.vertices = std::move(v);
  return s;
}

inline ProblemSpec spec_for(const std::string &mesh, double E, double nu)
{
  ProblemSpec spec;
  spec.file = "test:" + mesh;
  spec.mesh_path = mesh_file(mesh);
  spec.E = E;
  spec.nu = nu;
  return spec;
}

/// Uniform pressure p on every vertex of `mesh` (a pure-traction problem).
inline ProblemSpec pressure_spec(const std::string &mesh, double E, double nu, double p)
{
  ProblemSpec spec = spec_for(mesh, E, nu);
  BoundaryRule r;
  r.kind = BoundaryRule::Kind::Pressure;
  r.pressure = {p};
  spec.rules = {r};
  return spec;
}

/// Mixed problem for Kelvin's solution k on a sphere mesh: traction (with the exact sphere
/// normal) on every vertex, then displacement on the vertices with z >= 0.
template <class Field>
ProblemSpec kelvin_mixed_spec(const std::string &mesh, const Field &k)
{
  const SurfaceMesh m = read_mesh(mesh_file(mesh));
  ProblemSpec spec = spec_for(mesh, k.mat.E, k.mat.nu);
  std::vector<Vec3> t_rows, u_rows;
  std::vector<int> upper;
  for (int v = 0; v < m.num_vertices(); ++v) {
    t_rows.push_back(k.traction(m.vertices[v], normalized(m.vertices[v])));
    if (m.vertices[v][2] >= 0) upper.push_back(v), u_rows.push_back(k.displacement(m.vertices[v]));
  }
  spec.rules = {rule(BoundaryRule::Kind::Traction, all_vertices(), t_rows), rule(BoundaryRule::Kind::Displacement, vertices(upper), u_rows)};
  return spec;
}

/// Solve on PETSC_COMM_WORLD; rigid motion removed when the problem was pinned.
inline Solved solve(ProblemSpec spec, const QuadratureOptions &quad = {})
{
  Solved out{setup_problem(std::move(spec), ProblemOverrides{}), {}};
  BemOperator op(*out.setup.disc, out.setup.material, quad);
  const std::vector<double> x = solve_problem(PETSC_COMM_WORLD, out.setup, op, OperatorType::Dense, true);
  out.sol = split_unknowns(out.setup.selection, x);
  if (out.setup.pure_traction) remove_rigid_motion(*out.setup.disc, out.sol.u);
  return out;
}

/// Relative L2 difference after removing the least-squares rigid motion of (a - b) (for
/// pure-traction problems, whose answer is defined up to a rigid motion).
inline double rel_error_modulo_rigid(const Discretization &disc, std::vector<Vec3> a, const std::vector<Vec3> &b)
{
  for (std::size_t i = 0; i < a.size(); ++i) a[i] = a[i] - b[i];
  remove_rigid_motion(disc, a);
  double num = 0, den = 0;
  for (std::size_t i = 0; i < a.size(); ++i) num += dot(a[i], a[i]), den += dot(b[i], b[i]);
  return std::sqrt(num / den);
}

} // namespace hssbem::test
