// The one builder of a solution's fields (see result_fields.hpp).
#include "hssbem/session/result_fields.hpp"

#include "hssbem/session/petsc_call.hpp"
#include "hssbem/post/interior_stress.hpp"
#include "hssbem/post/near_surface.hpp"
#include "hssbem/mesh/surface_locator.hpp"
#include "hssbem/interior/interior_evaluation.hpp"
#include "hssbem/core/fault.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/petsc/log.h"

#include <optional>
#include <sstream>

namespace hssbem {

namespace {

/// Every point to evaluate: the explicit ones, then the grid's.
std::vector<Vec3> all_interior_points(const ProblemSpec &spec)
{
  std::vector<Vec3> pts = spec.interior_points;
  if (spec.interior_grid) {
    const std::vector<Vec3> g = spec.interior_grid->points();
    pts.insert(pts.end(), g.begin(), g.end());
  }
  return pts;
}

std::string point_text(const Vec3 &x)
{
  std::ostringstream out;
  out.precision(6);
  out << "(" << x[0] << ", " << x[1] << ", " << x[2] << ")";
  return out.str();
}

/// The evaluation's state on every rank: plan (which points to integrate) and sources.
struct InteriorSetup {
  std::vector<Vec3> points;
  std::optional<SurfaceLocator> locator;
  std::optional<InteriorPlan> plan;
  std::optional<SomiglianaSources> sources;
  std::optional<InteriorEvaluator> evaluator;
};

/// The particular solution of `force` added at every point inside (NaN outside stays NaN).
std::vector<FieldValue> add_particular(const UniformBodyForce &force, const InteriorSetup &is, std::vector<FieldValue> v)
{
  if (force.zero()) return v;
  for (std::size_t p = 0; p < v.size(); ++p) {
    if (is.plan->kind(p) == PointKind::Outside) continue;
    const Vec3 u = force.displacement(is.points[p]);
    const Voigt st = force.stress(is.points[p]);
    for (int c = 0; c < 3; ++c) v[p][c] += u[c];
    for (int k = 0; k < 6; ++k) v[p][3 + k] += st[k];
  }
  return v;
}

/// The fields of the points into r: the explicit points first, then the grid.
void store_fields(const ProblemSpec &spec, const InteriorSetup &is, const std::vector<FieldValue> &v, ResultData &r)
{
  const std::size_t m = spec.interior_points.size();
  r.interior_points = spec.interior_points;
  for (std::size_t p = 0; p < m; ++p) {
    r.interior_displacement.push_back({v[p][0], v[p][1], v[p][2]});
    r.interior_stress.push_back({v[p][3], v[p][4], v[p][5], v[p][6], v[p][7], v[p][8]});
  }
  r.interior_von_mises = von_mises_of(r.interior_stress);
  if (!spec.interior_grid) return;
  const InteriorGrid &g = *spec.interior_grid;
  InteriorGridData &d = r.interior_grid;
  d.origin = g.lo;
  d.spacing = g.spacing();
  d.points = g.points_per_axis();
  for (std::size_t p = m; p < v.size(); ++p) {
    d.displacement.push_back({v[p][0], v[p][1], v[p][2]});
    d.stress.push_back({v[p][3], v[p][4], v[p][5], v[p][6], v[p][7], v[p][8]});
    d.inside.push_back(is.plan->kind(p) != PointKind::Outside);
  }
  d.von_mises = von_mises_of(d.stress);
}

} // namespace

SurfaceFields surface_fields(const ProblemSetup &s, const NodalSolution &sol, const UniformBodyForce &force, const std::vector<std::array<bool, 3>> &prescribed,
                             unsigned parts, std::map<std::string, double> *seconds)
{
  const Discretization &disc = *s.disc;
  SurfaceFields f;
  const NodalSolution whole = with_particular(sol, disc, force);
  if (parts & kMotion) {
    f.displacement = vertex_average(disc, whole.u);
    f.traction = vertex_average(disc, whole.t);
  }
  if (parts & kPrescribed) f.displacement_prescribed = prescribed;
  if (parts & kWhole) {
    f.traction_corner = corner_values(disc, whole.t);
    f.reactions = reactions(disc, whole.t);
  }
  if (!(parts & kStress)) return f;
  const Timer timer;
  const EventScope event(BEM_Stress);
  f.nodes = node_stresses(disc, s.material, sol.u, sol.t);
  const std::vector<NodeStress> nodes = with_particular(f.nodes, disc, force);
  f.stress.stress = vertex_stress(disc, nodes);
  f.stress.von_mises = von_mises_of(f.stress.stress);
  f.stress.principal = principal_of(f.stress.stress);
  if (parts & kWhole) f.stress.corner = corner_stress(disc, nodes);
  if (seconds) (*seconds)["stress"] += timer.seconds();
  return f;
}

void put_fields(SurfaceFields &&f, ResultData &r)
{
  r.displacement = std::move(f.displacement);
  r.traction = std::move(f.traction);
  r.traction_corner = std::move(f.traction_corner);
  r.displacement_prescribed = std::move(f.displacement_prescribed);
  r.reactions = std::move(f.reactions);
  r.stress = std::move(f.stress);
}

void put_fields(SurfaceFields &&f, FrameData &frame)
{
  frame.displacement = std::move(f.displacement);
  frame.traction = std::move(f.traction);
  frame.displacement_prescribed = std::move(f.displacement_prescribed);
  frame.stress = std::move(f.stress);
}

ResultData result_base(const ProblemSetup &s, int ranks)
{
  ResultData r;
  r.vertices = s.mesh->vertices;
  r.triangles = s.mesh->triangles;
  r.triangle_region = s.mesh->triangle_region;
  r.sharp_vertex.resize(s.mesh->vertices.size());
  for (int v = 0; v < s.mesh->num_vertices(); ++v) r.sharp_vertex[v] = s.disc->node_count(v) > 1;
  r.attributes_real = {{"E", s.material.E}, {"nu", s.material.nu}, {"lambda", s.material.lambda()}, {"mu", s.material.mu()}, {"feature_angle_deg", s.disc->feature_angle_deg()}};
  if (s.spec.density) r.attributes_real["density"] = *s.spec.density;
  if (s.spec.gravity)
    for (int c = 0; c < 3; ++c) r.attributes_real[std::string("gravity_") + "xyz"[c]] = (*s.spec.gravity)[c];
  r.attributes_int = {{"ranks", ranks}, {"num_dofs", 3 * s.disc->num_nodes()}, {"num_nodes", s.disc->num_nodes()}, {"num_sharp_vertices", s.disc->num_sharp_vertices()}};
  char petsc_version[128];
  HssbemCallThrow(PetscGetVersion(petsc_version, sizeof(petsc_version)));
  r.attributes_str = {{"version", HSSBEM_VERSION}, {"petsc_version", petsc_version}, {"problem_file", s.spec.file}, {"mesh_file", s.spec.mesh_path}};
  r.input_files = s.input_files;
  return r;
}

void put_options(const OptionValues &values, ResultData &r)
{
  for (const auto &[name, v] : values) {
    switch (v.kind) {
    case OptionKind::Real: r.options_real[name] = v.number; break;
    case OptionKind::Int:
    case OptionKind::Bool: r.options_int[name] = static_cast<long long>(v.number); break;
    case OptionKind::Text:
    case OptionKind::Choice: r.options_str[name] = v.text; break;
    }
  }
}

ContactData contact_data(const ContactEngine &engine, const ContactSolution &sol, const ContactFrameReport &rep, bool bodies)
{
  ContactData c;
  c.pressure = sol.pressure;
  c.gap = sol.gap;
  c.status = sol.status;
  for (int o = 0; o < engine.num_obstacles(); ++o) c.forces[engine.obstacle_name(o)] = sol.obstacle_force[o];
  if (bodies)
    for (int b = 0; b < engine.bodies().count; ++b) c.forces["body_" + std::to_string(b)] = sol.body_force[b];
  for (int b : engine.floating_bodies()) c.body_motion[b] = {sol.body_translation[b], sol.body_rotation[b]};
  c.iterations = rep.iterations;
  c.active_vertices = rep.active_vertices;
  return c;
}

void check_interior_points(const ProblemSetup &s)
{
  if (s.spec.interior_points.empty()) return;
  const SurfaceLocator locator(*s.mesh);
  const double on = InteriorPlanOptions{}.on_surface * locator.size();
  for (std::size_t p = 0; p < s.spec.interior_points.size(); ++p) {
    const Vec3 &x = s.spec.interior_points[p];
    if (locator.nearest(x, on * (1 + 1e-12)).triangle < 0 && !locator.inside(x))
      throw ProblemError(s.spec.file + ": interior_points[" + std::to_string(p) + "] = " + point_text(x) + " is not inside the body");
  }
}

void interior_fields(MPI_Comm comm, const ProblemSetup &s, const NodalSolution &sol, const std::vector<NodeStress> &nodes, const InteriorRunOptions &o,
                     ResultData &r, std::map<std::string, double> &seconds)
{
  if (s.spec.interior_points.empty() && !s.spec.interior_grid) return;
  const EventScope event(BEM_Interior);
  const Timer      timer;
  PetscMPIInt      rank, size;
  HssbemCallMPIThrow(MPI_Comm_rank(comm, &rank));
  HssbemCallMPIThrow(MPI_Comm_size(comm, &size));
  InteriorSetup is;
  run_collectively(comm, [&] { // every rank: the plan and the sources' far field (upward pass)
    fault_point("Interior");
    is.points = all_interior_points(s.spec);
    is.locator.emplace(*s.mesh);
    std::vector<signed char> inside(s.spec.interior_points.size(), -1); // explicit points: the winding number
    if (s.spec.interior_grid) {
      const InteriorGrid &g = *s.spec.interior_grid;
      const std::vector<signed char> grid = grid_inside(*is.locator, g.lo, g.spacing(), g.points_per_axis(), InteriorPlan::search_reach(*is.locator, *s.mesh, o.plan));
      inside.insert(inside.end(), grid.begin(), grid.end());
    }
    is.plan.emplace(*is.locator, *s.mesh, is.points, o.plan, &inside);
    is.sources.emplace(*s.disc, s.material, sol.u, corner_tractions(*s.disc, s.selection, sol), o.quad);
    is.evaluator.emplace(*is.sources, o.fast);
  });
  std::vector<double> values;
  run_collectively(comm, [&] { values = is.evaluator->evaluate(is.plan->evaluation_points(), rank, size); });
  if (size > 1) HssbemCallMPIThrow(MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_DOUBLE, MPI_SUM, comm));
  run_collectively(comm, [&] {
    const SurfaceMesh &mesh = *s.mesh;
    std::vector<std::array<Vec3, 3>> corner_u(mesh.triangles.size());
    for (int e = 0; e < mesh.num_triangles(); ++e)
      for (int c = 0; c < 3; ++c) corner_u[e][c] = sol.u[s.disc->element_node(e, c)];
    store_fields(s.spec, is, add_particular(s.body_force, is, is.plan->finish(values, corner_u, corner_stress(*s.disc, nodes))), r);
  });
  seconds["interior"] += timer.seconds();
}

} // namespace hssbem
