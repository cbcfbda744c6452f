// The hssbem application: problem file → operator → solve → post-processing → result file (see run.hpp).
#include "hssbem/app/run.hpp"
#include "result_base.hpp"
#include "stress_post.hpp"

#include "hssbem/app/options.hpp"
#include "hssbem/app/petsc_call.hpp"
#include "hssbem/post/post.hpp"
#include "hssbem/bem/rigid_modes.hpp"
#include "hssbem/core/fault.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/io/hdf5_output.hpp"
#include "hssbem/petsc/log.h"

#include <cmath>
#include <exception>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>

namespace hssbem {

namespace {

/// Every rank reads the problem and the mesh (they need the geometry); rank 0 alone checks the
/// output path, since rank 0 alone creates and renames it. A failure on any rank (files that differ between
/// nodes, say) ends every rank with the same message.
ProblemSetup set_up(MPI_Comm comm, const std::string &file, const ProblemOverrides &ov)
{
  const EventScope            event(BEM_Mesh);
  std::optional<ProblemSetup> s;
  PetscMPIInt                 rank;

  HssbemCallMPIThrow(MPI_Comm_rank(comm, &rank));
  run_collectively(comm, [&] {
    s.emplace(setup_problem(file, ov));
    check_interior_points(*s);
    if (rank == 0 && !s->output.empty()) check_output_path(s->output, s->input_files);
  });
  return std::move(*s);
}

/// No result without a solution: a NaN or an infinity in it is an error, named before anything is
/// written (the result writer refuses non-finite fields too). The bound on the true residual
/// ‖b − A x‖/‖b‖, for any KSP, is HssbemSolveSystem's (-hssbem_residual_max, petsc/solve.cxx).
void check_solution(const std::vector<double> &x, const HssbemSolveInfo &info)
{
  for (std::size_t i = 0; i < x.size(); ++i)
    if (!std::isfinite(x[i]))
      throw std::runtime_error("the solution is not finite (unknown " + std::to_string(i) + " is " + std::to_string(x[i]) + ", relative residual " +
                               std::to_string((double)info.residual) + " with " + info.ksp_type + "/" + info.pc_type + "); nothing was written");
}

/// The whole solution vector on rank 0 (empty elsewhere), or on every rank.
std::vector<double> gather(Vec x, bool to_all)
{
  VecScatter         sc;
  Vec                x0;
  PetscInt           n;
  const PetscScalar *a;

  std::vector<double> out;
  if (to_all) HssbemCallThrow(VecScatterCreateToAll(x, &sc, &x0));
  else HssbemCallThrow(VecScatterCreateToZero(x, &sc, &x0));
  HssbemCallThrow(VecScatterBegin(sc, x, x0, INSERT_VALUES, SCATTER_FORWARD));
  HssbemCallThrow(VecScatterEnd(sc, x, x0, INSERT_VALUES, SCATTER_FORWARD));
  HssbemCallThrow(VecGetLocalSize(x0, &n));
  HssbemCallThrow(VecGetArrayRead(x0, &a));
  run_collectively(PetscObjectComm((PetscObject)x), [&] { // the copy may not fit on rank 0 alone
    fault_point("Gather");
    out.assign(a, a + n);
  });
  HssbemCallThrow(VecRestoreArrayRead(x0, &a));
  HssbemCallThrow(VecScatterDestroy(&sc));
  HssbemCallThrow(VecDestroy(&x0));
  return out;
}

/// The surface's fields of the solution x; returns the solution per dof node.
NodalSolution fill_result(const ProblemSetup &s, const std::vector<double> &x, ResultData &r)
{
  const Discretization &disc = *s.disc;
  fault_point("Post");
  NodalSolution         sol  = split_unknowns(s.selection, x);
  if (s.pure_traction) remove_rigid_motion(disc, sol.u);
  r.displacement            = vertex_average(disc, sol.u);
  r.traction                = vertex_average(disc, sol.t);
  r.traction_corner         = corner_values(disc, sol.t);
  r.displacement_prescribed = s.vertex_displacement_prescribed;
  r.reactions       = reactions(disc, sol.t);
  return sol;
}

/// The solve's part of the root attributes, added to result_base()'s.
void describe(const ProblemSetup &s, const HssbemSolveInfo &info, OperatorType type, ResultData &r)
{
  const char *mat_type = operator_type_name(type);
  r.attributes_real["residual"]      = info.residual;
  r.attributes_int["iterations"]     = info.iterations;
  r.attributes_int["pure_traction"]  = s.pure_traction;
  r.attributes_str["solver"]          = mat_type;
  r.attributes_str["mat_type"]        = mat_type;
  r.attributes_str["ksp_type"]        = info.ksp_type;
  r.attributes_str["pc_type"]         = info.pc_type;
  r.attributes_str["mat_solver_type"] = info.solver_type;
  r.attributes_str["converged_reason"] = KSPConvergedReasons[info.reason];
}

/// Every rank post-processes the whole solution (cheap beside the solve) and the ranks write the
/// result file together, each its rows (write_result); a failure on any rank is raised on every rank.
void write_collectively(MPI_Comm comm, const ProblemSetup &s, const std::vector<double> &xall, const HssbemSolveInfo &info, OperatorType type,
                        const InteriorRunOptions &interior, std::map<std::string, double> seconds)
{
  PetscMPIInt             size;
  ResultData              r;
  NodalSolution           sol;
  std::vector<NodeStress> nodes;

  HssbemCallMPIThrow(MPI_Comm_size(comm, &size));
  run_collectively(comm, [&] {
    r = result_base(s, size);
    const Timer      timer;
    const EventScope event(BEM_Post);
    sol = fill_result(s, xall, r);
    seconds["post"] += timer.seconds();
    const Timer      stress_timer;
    const EventScope stress_event(BEM_Stress);
    r.stress = surface_stress_fields(s, sol, nodes, true);
    seconds["stress"] += stress_timer.seconds();
  });
  interior_fields(comm, s, sol, nodes, interior, r, seconds);
  describe(s, info, type, r);
  r.timings = seconds; // rank 0's are written
  if (s.output.empty()) return;
  {
    const EventScope event(BEM_Output);
    write_result(comm, s.output, r);
  }
  HssbemCallThrow(PetscPrintf(comm, "hssbem: wrote %s\n", s.output.c_str()));
}

} // namespace

ResultData result_base(const ProblemSetup &s, PetscMPIInt size)
{
  ResultData r;
  r.vertices        = s.mesh->vertices;
  r.triangles       = s.mesh->triangles;
  r.triangle_region = s.mesh->triangle_region;
  r.sharp_vertex.resize(s.mesh->vertices.size());
  for (int v = 0; v < s.mesh->num_vertices(); ++v) r.sharp_vertex[v] = s.disc->node_count(v) > 1;
  r.attributes_real = {{"E", s.material.E}, {"nu", s.material.nu}, {"lambda", s.material.lambda()}, {"mu", s.material.mu()}, {"feature_angle_deg", s.disc->feature_angle_deg()}};
  r.attributes_int  = {{"ranks", size}, {"num_dofs", 3 * s.disc->num_nodes()}, {"num_nodes", s.disc->num_nodes()}, {"num_sharp_vertices", s.disc->num_sharp_vertices()}};
  char petsc_version[128];
  HssbemCallThrow(PetscGetVersion(petsc_version, sizeof(petsc_version)));
  r.attributes_str = {{"version", HSSBEM_VERSION}, {"petsc_version", petsc_version}, {"problem_file", s.spec.file}, {"mesh_file", s.spec.mesh_path}};
  r.input_files    = s.input_files;
  return r;
}

std::vector<double> solve_problem(MPI_Comm comm, const ProblemSetup &s, const BemOperator &op, OperatorType type, bool to_all, HssbemSolveInfo *info,
                                  std::map<std::string, double> *seconds)
{
  const char     *mat_type = operator_type_name(type);
  HssbemSolveInfo local;
  KSP             ksp;
  Mat             A;
  Vec             b, x;

  if (!info) info = &local;
  HssbemCallThrow(HssbemKSPCreate(comm, mat_type, &ksp));
  check_unused_options(comm, true);
  Timer               timer;
  std::vector<double> modes;
  run_collectively(comm, [&] {
    fault_point("RigidModes");
    if (s.pure_traction) modes = orthonormal_rigid_modes(*s.disc);
  });
  HssbemCallThrow(HssbemCreateSystem(comm, op, s.selection, s.pure_traction ? &modes : nullptr, mat_type, &A, &b));
  HssbemCallThrow(MatViewFromOptions(A, NULL, "-bem_mat_view"));
  const double t_assembly = timer.seconds();
  timer.restart();
  HssbemCallThrow(VecDuplicate(b, &x));
  HssbemCallThrow(HssbemSolveSystem(ksp, &A, b, x, info));
  const double              t_solve = timer.seconds();
  Vec xmesh; // the solution in mesh order (the distributed H² system's rows are in cluster order)
  HssbemCallThrow(HssbemMatCreateMeshOrderVec(A, &xmesh));
  HssbemCallThrow(HssbemVecToMeshOrder(A, x, xmesh));
  const std::vector<double> xall = gather(xmesh, to_all);
  HssbemCallThrow(VecDestroy(&xmesh));
  HssbemCallThrow(KSPDestroy(&ksp));
  HssbemCallThrow(MatDestroy(&A));
  HssbemCallThrow(VecDestroy(&b));
  HssbemCallThrow(VecDestroy(&x));
  if (seconds) {
    (*seconds)["assembly"] += t_assembly;
    (*seconds)["solve"] += t_solve;
  }
  return xall;
}

/// The operator of the run: the one asked for, or auto's choice with the reason for the log line.
OperatorType resolve_operator(MPI_Comm comm, std::optional<OperatorType> asked, long long unknowns, std::string *why)
{
  if (asked) return *asked;
  MachineLimits limits;
  HssbemCallThrow(HssbemMachineLimits(comm, &limits));
  const OperatorType type = choose_operator(unknowns, limits);
  if (type == OperatorType::Dense) *why = " (auto: below " + std::to_string(k_auto_dense_max_unknowns) + " unknowns)";
  else if (unknowns < k_auto_dense_max_unknowns) *why = " (auto: the dense operator does not fit this machine)";
  else *why = " (auto: from " + std::to_string(k_auto_dense_max_unknowns) + " unknowns on)";
  return type;
}

void run_problem(MPI_Comm comm, const std::string &problem_file, const ProblemOverrides &overrides, const QuadratureOptions &quad, std::optional<OperatorType> asked,
                 const SceneRunOptions &scene, const InteriorRunOptions &interior, const ContactRunOptions &contact)
{
  std::map<std::string, double> seconds; // per phase, for the result file
  const Timer                   timer;
  PetscMPIInt                   size;
  HssbemSolveInfo               info;
  std::string                   why;

  HssbemCallMPIThrow(MPI_Comm_size(comm, &size));
  const ProblemSetup s = set_up(comm, problem_file, overrides);
  for (const auto &n : s.notices) HssbemCallThrow(PetscPrintf(comm, "hssbem: notice: %s\n", n.c_str()));
  std::optional<BemOperator> built; // every rank builds it: a failure on one must stop them all
  run_collectively(comm, [&] {
    fault_point("Operator");
    built.emplace(*s.disc, s.material, quad);
  });
  const BemOperator &op = *built;
  seconds["setup"] += timer.seconds();
  if (s.spec.contact.present) {
    HssbemCallThrow(PetscPrintf(comm, "hssbem: %s: %d vertices, %d triangles, %d dof nodes (%d sharp vertices), %d unknowns, %d ranks\n", s.spec.mesh_path.c_str(), s.mesh->num_vertices(),
                                s.mesh->num_triangles(), s.disc->num_nodes(), s.disc->num_sharp_vertices(), 3 * s.disc->num_nodes(), size));
    check_unused_options(comm, false);
    run_contact(comm, s, op, asked, contact, interior, seconds);
    return;
  }
  if (!s.spec.frames.empty()) {
    HssbemCallThrow(PetscPrintf(comm, "hssbem: %s: %d vertices, %d triangles, %d dof nodes (%d sharp vertices), %d unknowns, %d ranks\n", s.spec.mesh_path.c_str(), s.mesh->num_vertices(),
                                s.mesh->num_triangles(), s.disc->num_nodes(), s.disc->num_sharp_vertices(), 3 * s.disc->num_nodes(), size));
    check_unused_options(comm, false);
    run_scene(comm, s, op, asked, scene, seconds);
    return;
  }
  const OperatorType type = resolve_operator(comm, asked, 3LL * s.disc->num_nodes(), &why);
  HssbemCallThrow(PetscPrintf(comm, "hssbem: %s: %d vertices, %d triangles, %d dof nodes (%d sharp vertices), %d unknowns, %d ranks, %s operator%s\n", s.spec.mesh_path.c_str(),
                              s.mesh->num_vertices(), s.mesh->num_triangles(), s.disc->num_nodes(), s.disc->num_sharp_vertices(), 3 * s.disc->num_nodes(), size,
                              operator_type_name(type), why.c_str()));
  fault_point("Driver"); /* tests: an error no guard makes collective (the last resort of app/main.hpp) */
  const std::vector<double> xall = solve_problem(comm, s, op, type, true, &info, &seconds);
  check_solution(xall, info); // every rank holds the whole solution: they all agree
  HssbemCallThrow(PetscPrintf(comm, "hssbem: solved with %s/%s%s%s: %" PetscInt_FMT " iterations, relative residual %.3e\n", info.ksp_type.c_str(), info.pc_type.c_str(),
                              info.solver_type.empty() ? "" : "/", info.solver_type.c_str(), info.iterations, (double)info.residual));
  check_unused_options(comm, false);
  write_collectively(comm, s, xall, info, type, interior, seconds);
}

void run_driver(MPI_Comm comm)
{
  const AppOptions opts = read_app_options(comm);
  if (!opts.problem.empty()) {
    run_problem(comm, opts.problem, opts.overrides, opts.quad, opts.operator_type, opts.scene, opts.interior, opts.contact);
    return;
  }
  if (!opts.help) throw std::runtime_error("no problem file; give -problem FILE.json (-help lists the options)");
  KSP ksp; // -help without a problem: list the solver's options too
  HssbemCallThrow(HssbemKSPCreate(comm, operator_type_name(opts.operator_type.value_or(OperatorType::Hss)), &ksp)); /* hss: lists PC hss's options too */
  HssbemCallThrow(KSPDestroy(&ksp));
}

} // namespace hssbem
