// The stress in a result file: surface fields, interior points and grids (see stress_post.hpp).
#include "stress_post.hpp"

#include "hssbem/app/petsc_call.hpp"
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

StressFields surface_stress_fields(const ProblemSetup &s, const NodalSolution &sol, std::vector<NodeStress> &nodes, bool corners)
{
  nodes = node_stresses(*s.disc, s.material, sol.u, sol.t);
  StressFields f;
  f.stress = vertex_stress(*s.disc, nodes);
  f.von_mises = von_mises_of(f.stress);
  f.principal = principal_of(f.stress);
  if (corners) f.corner = corner_stress(*s.disc, nodes);
  return f;
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
    store_fields(s.spec, is, is.plan->finish(values, corner_u, corner_stress(*s.disc, nodes)), r);
  });
  seconds["interior"] += timer.seconds();
}

/* Reads the -bem_interior_* options into o.

  Options Database Keys:
+ -bem_interior_band <h>              - points closer to the surface than this many element sizes are interpolated between the surface and two points at that depth (0: integrated where they are)
. -bem_interior_near_ratio <r>        - split a triangle while the point is closer than r of its diameters
. -bem_interior_max_depth <n>         - levels of splits at most
. -bem_interior_equivalent_points <n> - points per equivalent sphere of the fast evaluation
. -bem_interior_inner_points <n>      - points of each source leaf's inner forces, used near the leaf instead of its particles (0: none)
. -bem_interior_source_leaf <n>       - triangles per source leaf
. -bem_interior_target_leaf <n>       - points per target leaf
- -bem_interior_direct                - every point against every triangle (no fast evaluation; the reference)
*/
PetscErrorCode InteriorOptionsFromDatabase_Private(MPI_Comm comm, InteriorRunOptions *o)
{
  PetscBool direct = o->fast.direct ? PETSC_TRUE : PETSC_FALSE;
  PetscInt  depth = o->quad.max_depth, pe = o->fast.equivalent_points, ip = o->fast.inner_points, sl = o->fast.source_leaf, tl = o->fast.target_leaf;

  PetscFunctionBegin;
  PetscOptionsBegin(comm, NULL, "hssbem: displacement and stress inside the body (interior points and grids)", "hssbem");
  PetscCall(PetscOptionsReal("-bem_interior_band", "Points closer to the surface than this many element sizes are interpolated along the normal (0: integrated where they are)", "", o->plan.band, &o->plan.band, NULL));
  PetscCall(PetscOptionsReal("-bem_interior_near_ratio", "Split a triangle while the point is closer than this many of its diameters", "", o->quad.near_ratio, &o->quad.near_ratio, NULL));
  PetscCall(PetscOptionsInt("-bem_interior_max_depth", "Levels of 1:4 splits at most", "", depth, &depth, NULL));
  PetscCall(PetscOptionsInt("-bem_interior_equivalent_points", "Points on each equivalent sphere of the fast evaluation", "", pe, &pe, NULL));
  PetscCall(PetscOptionsInt("-bem_interior_inner_points", "Points of each source leaf's inner forces, taken near the leaf instead of its particles (0: none)", "", ip, &ip, NULL));
  PetscCall(PetscOptionsInt("-bem_interior_source_leaf", "Triangles per source leaf of the fast evaluation", "", sl, &sl, NULL));
  PetscCall(PetscOptionsInt("-bem_interior_target_leaf", "Points per target leaf of the fast evaluation", "", tl, &tl, NULL));
  PetscCall(PetscOptionsBool("-bem_interior_direct", "Every point against every triangle (the reference; no fast evaluation)", "", direct, &direct, NULL));
  PetscOptionsEnd();
  PetscCheck(o->plan.band >= 0 && o->plan.band <= 10, comm, PETSC_ERR_ARG_OUTOFRANGE, "-bem_interior_band must lie in [0, 10]");
  PetscCheck(o->quad.near_ratio >= 1 && o->quad.near_ratio <= 20, comm, PETSC_ERR_ARG_OUTOFRANGE, "-bem_interior_near_ratio must lie in [1, 20]");
  PetscCheck(depth >= 0 && depth <= 20, comm, PETSC_ERR_ARG_OUTOFRANGE, "-bem_interior_max_depth must lie in [0, 20]");
  PetscCheck(pe >= 16 && pe <= 2000, comm, PETSC_ERR_ARG_OUTOFRANGE, "-bem_interior_equivalent_points must lie in [16, 2000]");
  PetscCheck(ip == 0 || (ip >= 16 && ip <= 2000), comm, PETSC_ERR_ARG_OUTOFRANGE, "-bem_interior_inner_points must be 0 or lie in [16, 2000]");
  PetscCheck(sl >= 1 && tl >= 1, comm, PETSC_ERR_ARG_OUTOFRANGE, "-bem_interior_source_leaf and -bem_interior_target_leaf must be at least 1");
  o->quad.max_depth = (int)depth;
  o->fast.equivalent_points = (int)pe;
  o->fast.inner_points = (int)ip;
  o->fast.source_leaf = (int)sl;
  o->fast.target_leaf = (int)tl;
  o->fast.direct = direct == PETSC_TRUE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

} // namespace hssbem
