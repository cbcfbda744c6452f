#include "hssbem/app/run.hpp"
#include "hssbem/bem/post.hpp"
#include "hssbem/bem/rigid_modes.hpp"
#include "hssbem/io/hdf5_output.hpp"
#include "hssbem/petsc/dense.h"
#include "hssbem/petsc/log.h"
#include "hssbem/app/options.hpp"
#include "hssbem/petsc/system.h"

#include "hssbem/core/timer.hpp"

#include <map>
#include <string>

namespace {

hssbem::ProblemSetup SetUp(MPI_Comm comm, const std::string &file, const hssbem::ProblemOverrides &ov)
{
  PetscCallAbort(comm, PetscLogEventBegin(BEM_Mesh, 0, 0, 0, 0));
  try {
    hssbem::ProblemSetup s = hssbem::setup_problem(file, ov);
    if (!s.output.empty()) hssbem::check_output_path(s.output);
    PetscCallAbort(comm, PetscLogEventEnd(BEM_Mesh, 0, 0, 0, 0));
    return s;
  } catch (...) {
    PetscCallAbort(comm, PetscLogEventEnd(BEM_Mesh, 0, 0, 0, 0));
    throw;
  }
}

void CheckInteriorPoints(const hssbem::BemOperator &op, const hssbem::ProblemSpec &spec)
{
  for (std::size_t p = 0; p < spec.interior_points.size(); ++p) {
    const double c = hssbem::inside_indicator(op, spec.interior_points[p]);
    if (std::abs(c - 1.0) > 0.05) {
      const auto &x = spec.interior_points[p];
      throw hssbem::ProblemError(spec.file + ": interior_points[" + std::to_string(p) + "] = (" + std::to_string(x[0]) + ", " + std::to_string(x[1]) + ", " + std::to_string(x[2]) +
                                 ") is not inside the body (or too close to its surface)");
    }
  }
}

/* The whole solution vector on rank 0 (empty elsewhere), or on every rank. */
PetscErrorCode Gather(Vec x, PetscBool to_all, std::vector<double> *out)
{
  VecScatter         sc;
  Vec                x0;
  PetscInt           n;
  const PetscScalar *a;

  PetscFunctionBegin;
  if (to_all) PetscCall(VecScatterCreateToAll(x, &sc, &x0));
  else PetscCall(VecScatterCreateToZero(x, &sc, &x0));
  PetscCall(VecScatterBegin(sc, x, x0, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(sc, x, x0, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecGetLocalSize(x0, &n));
  PetscCall(VecGetArrayRead(x0, &a));
  out->assign(a, a + n);
  PetscCall(VecRestoreArrayRead(x0, &a));
  PetscCall(VecScatterDestroy(&sc));
  PetscCall(VecDestroy(&x0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

void FillResult(const hssbem::ProblemSetup &s, const hssbem::BemOperator &op, const std::vector<double> &x, hssbem::ResultData &r)
{
  using namespace hssbem;
  const Discretization &disc = *s.disc;
  NodalSolution sol = split_unknowns(s.selection, x);
  if (s.pure_traction) remove_rigid_motion(disc, sol.u);
  r.vertices = s.mesh->vertices;
  r.triangles = s.mesh->triangles;
  r.triangle_region = s.mesh->triangle_region;
  r.displacement = vertex_average(disc, sol.u);
  r.traction = vertex_average(disc, sol.t);
  r.traction_corner = corner_values(disc, sol.t);
  r.displacement_prescribed = s.vertex_displacement_prescribed;
  r.sharp_vertex.resize(s.mesh->vertices.size());
  for (int v = 0; v < s.mesh->num_vertices(); ++v) r.sharp_vertex[v] = disc.node_count(v) > 1;
  r.reactions = reactions(disc, sol.t);
  r.interior_points = s.spec.interior_points;
  PetscCallAbort(PETSC_COMM_SELF, PetscLogEventBegin(BEM_Interior, 0, 0, 0, 0));
  r.interior_displacement = interior_displacement(op, sol, s.spec.interior_points);
  PetscCallAbort(PETSC_COMM_SELF, PetscLogEventEnd(BEM_Interior, 0, 0, 0, 0));
}

void Describe(const hssbem::ProblemSetup &s, const HssbemSolveInfo &info, const char *mat_type, PetscMPIInt size, hssbem::ResultData &r)
{
  r.attributes_real = {{"E", s.material.E}, {"nu", s.material.nu}, {"lambda", s.material.lambda()}, {"mu", s.material.mu()},
                       {"residual", info.residual}, {"feature_angle_deg", s.disc->feature_angle_deg()}};
  r.attributes_int = {{"iterations", info.iterations}, {"ranks", size}, {"num_dofs", 3 * s.disc->num_nodes()},
                      {"num_nodes", s.disc->num_nodes()}, {"num_sharp_vertices", s.disc->num_sharp_vertices()},
                      {"pure_traction", (long long)s.pure_traction}};
  char petsc_version[128];
  PetscCallAbort(PETSC_COMM_SELF, PetscGetVersion(petsc_version, sizeof(petsc_version)));
  r.attributes_str = {{"solver", mat_type}, {"mat_type", mat_type}, {"ksp_type", info.ksp_type}, {"pc_type", info.pc_type}, {"mat_solver_type", info.solver_type},
                      {"converged_reason", KSPConvergedReasons[info.reason]}, {"version", HSSBEM_VERSION}, {"petsc_version", petsc_version},
                      {"problem_file", s.spec.file}, {"mesh_file", s.spec.mesh_path}};
}

} // namespace

/*@C
  HssbemSolveSetup - Builds (dense, HSS or H²) and solves the system of a prepared problem; the unknowns
  (3 per dof node, node order) come back on rank 0, or on every rank with to_all.

  Level: intermediate
@*/
PetscErrorCode HssbemSolveSetup(MPI_Comm comm, const hssbem::ProblemSetup &s, const hssbem::BemOperator &op, const char *mat_type, PetscBool to_all, std::vector<double> *x_out, HssbemSolveInfo *info,
                                std::map<std::string, double> *seconds)
{
  std::map<std::string, double> phase_seconds;
  hssbem::Timer                 timer;
  KSP                           ksp;
  Mat                           A;
  Vec                           b, x;

  PetscFunctionBegin;
  PetscCall(HssbemKSPCreate(comm, mat_type, &ksp));
  PetscCall(HssbemCheckUnusedOptions(comm, PETSC_TRUE));
  timer.restart();
  std::vector<double> modes;
  if (s.pure_traction) modes = hssbem::orthonormal_rigid_modes(*s.disc);
  PetscCall(HssbemCreateSystem(comm, op, s.selection, s.pure_traction ? &modes : nullptr, mat_type, &A, &b));
  PetscCall(MatViewFromOptions(A, NULL, "-bem_mat_view"));
  phase_seconds["assembly"] += timer.seconds();
  timer.restart();
  PetscCall(VecDuplicate(b, &x));
  PetscCall(HssbemSolveSystem(ksp, &A, b, x, info));
  phase_seconds["solve"] += timer.seconds();
  PetscCall(Gather(x, to_all, x_out));
  PetscCall(KSPDestroy(&ksp));
  PetscCall(MatDestroy(&A));
  PetscCall(VecDestroy(&b));
  PetscCall(VecDestroy(&x));
  if (seconds)
    for (const auto &[k, v] : phase_seconds) (*seconds)[k] += v;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemRun - Solves one problem file end to end on comm: set up (mesh, material, boundary
  conditions), build the collocation system (dense, HSS or H²), solve with KSP, post-process and write.

  Level: beginner
@*/
PetscErrorCode HssbemRun(MPI_Comm comm, const std::string &problem_file, const hssbem::ProblemOverrides &overrides, const hssbem::QuadratureOptions &quad, const char *mat_type)
{
  std::map<std::string, double> seconds; /* per phase, for the result file */
  hssbem::Timer                 timer;
  PetscMPIInt                   rank, size;
  HssbemSolveInfo               info;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Comm_size(comm, &size));
  hssbem::ProblemSetup s = SetUp(comm, problem_file, overrides);
  for (const auto &n : s.notices) PetscCall(PetscPrintf(comm, "hssbem: notice: %s\n", n.c_str()));
  hssbem::BemOperator op(*s.disc, s.material, quad);
  CheckInteriorPoints(op, s.spec);
  seconds["setup"] += timer.seconds();
  PetscCall(PetscPrintf(comm, "hssbem: %s: %d vertices, %d triangles, %d dof nodes (%d sharp vertices), %d unknowns, %d ranks, %s operator\n", s.spec.mesh_path.c_str(), s.mesh->num_vertices(),
                        s.mesh->num_triangles(), s.disc->num_nodes(), s.disc->num_sharp_vertices(), 3 * s.disc->num_nodes(), size, mat_type));
  std::vector<double> xall;
  PetscCall(HssbemSolveSetup(comm, s, op, mat_type, PETSC_FALSE, &xall, &info, &seconds));
  PetscCall(PetscPrintf(comm, "hssbem: solved with %s/%s%s%s: %" PetscInt_FMT " iterations, relative residual %.3e\n", info.ksp_type.c_str(), info.pc_type.c_str(),
                        info.solver_type.empty() ? "" : "/", info.solver_type.c_str(), info.iterations, (double)info.residual));
  PetscCall(HssbemCheckUnusedOptions(comm, PETSC_FALSE));
  int failed = 0;
  std::string message;
  if (rank == 0) {
    try {
      hssbem::ResultData r;
      timer.restart();
      PetscCall(PetscLogEventBegin(BEM_Post, 0, 0, 0, 0));
      FillResult(s, op, xall, r);
      PetscCall(PetscLogEventEnd(BEM_Post, 0, 0, 0, 0));
      seconds["post"] += timer.seconds();
      Describe(s, info, mat_type, size, r);
      r.timings = seconds;
      if (!s.output.empty()) {
        PetscCall(PetscLogEventBegin(BEM_Output, 0, 0, 0, 0));
        hssbem::write_result(s.output, r);
        PetscCall(PetscLogEventEnd(BEM_Output, 0, 0, 0, 0));
        PetscCall(PetscPrintf(PETSC_COMM_SELF, "hssbem: wrote %s\n", s.output.c_str()));
      }
    } catch (const std::exception &e) {
      failed = 1;
      message = e.what();
    }
  }
  PetscCallMPI(MPI_Bcast(&failed, 1, MPI_INT, 0, comm));
  if (failed) throw std::runtime_error(rank == 0 ? message : std::string("output failed on rank 0"));
  PetscFunctionReturn(PETSC_SUCCESS);
}
