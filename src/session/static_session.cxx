// A static solve (see static_session.hpp).
#include "hssbem/session/static_session.hpp"

#include "hssbem/bem/rigid_modes.hpp"
#include "hssbem/core/fault.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/petsc/log.h"
#include "hssbem/petsc/options.h"
#include "hssbem/petsc/pc_h2.h"
#include "hssbem/session/h2_file.hpp"
#include "hssbem/session/petsc_call.hpp"
#include "hssbem/session/result_fields.hpp"

#include <cmath>
#include <stdexcept>

namespace hssbem {

namespace {

/// The whole vector x on rank 0 (empty elsewhere), or on every rank.
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

/// The solve's part of the root attributes, added to result_base()'s.
void describe(const ProblemSetup &s, const HssbemSolveInfo &info, OperatorType type, ResultData &r)
{
  const char *mat_type = operator_type_name(type);
  r.attributes_real["residual"] = info.residual;
  r.attributes_int["iterations"] = info.iterations;
  r.attributes_int["pure_traction"] = s.pure_traction;
  r.attributes_str["solver"] = mat_type;
  r.attributes_str["mat_type"] = mat_type;
  r.attributes_str["ksp_type"] = info.ksp_type;
  r.attributes_str["pc_type"] = info.pc_type;
  r.attributes_str["mat_solver_type"] = info.solver_type;
  r.attributes_str["converged_reason"] = KSPConvergedReasons[info.reason];
}

} // namespace

StaticSession::StaticSession(MPI_Comm comm, std::shared_ptr<const SessionProblem> problem, const SessionOptions &options)
    : m_comm(comm), m_problem(std::move(problem)), m_options(options)
{
  HssbemCallThrow(HssbemMachineLimits(comm, &m_limits));
  m_choice = static_operator(options.operator_type, m_problem->unknowns(), m_limits);
}

StaticSession::~StaticSession() { destroy(); }

void StaticSession::destroy()
{
  (void)KSPDestroy(&m_ksp);
  (void)MatDestroy(&m_A);
  (void)VecDestroy(&m_b);
}

void StaticSession::create_solver()
{
  if (m_ksp) return;
  HssbemCallThrow(HssbemKSPCreate(m_comm, operator_type_name(m_choice.type), &m_ksp));
}

void StaticSession::assemble()
{
  if (m_A) return;
  create_solver();
  const ProblemSetup &s = m_problem->setup();
  const Timer timer;
  std::vector<double> modes;
  run_collectively(m_comm, [&] {
    fault_point("RigidModes");
    if (s.pure_traction) modes = orthonormal_rigid_modes(*s.disc);
  });
  HssbemSystemOptions so;
  so.h2 = m_options.h2;
  so.hss = m_options.hss;
  so.limits = &m_limits;
  HssbemCallThrow(HssbemKSPGetSizeOptions(m_ksp, &so.solver));
  if (m_loaded) use_loaded(so);
  HssbemCallThrow(HssbemCreateSystemWithOptions(m_comm, m_problem->op(), s.selection, s.pure_traction ? &modes : nullptr, operator_type_name(m_choice.type), so, &m_A, &m_b));
  HssbemCallThrow(MatViewFromOptions(m_A, NULL, "-bem_mat_view"));
  m_seconds[m_loaded ? "load" : "assembly"] += timer.seconds();
}

void StaticSession::use_loaded(HssbemSystemOptions &so)
{
  const std::shared_ptr<LoadedH2Part> part = m_loaded; // its streams are freed as they are unpacked
  const BemOperator &op = m_problem->op();
  const H2Options h2 = m_options.h2;
  so.h2_source = [part, &op, h2](const std::vector<int> &node_part, const RankComm &comm) { return unpack_h2_system(*part, op, h2, node_part, comm); };
  PC pc;
  HssbemCallThrow(KSPGetPC(m_ksp, &pc));
  HssbemCallThrow(HssbemPCH2SetFactorSource(pc, [part](const H2DistributedSystem &sys) { return unpack_h2_factorization(*part, sys); }));
}

void StaticSession::load(const std::string &path)
{
  if (m_choice.type != OperatorType::H2)
    throw std::invalid_argument("-hssbem_load: a saved static precomputation is the H2 operator's and PC h2's; this solve takes the " + std::string(operator_type_name(m_choice.type)) + " operator");
  create_solver();
  const Timer timer;
  m_loaded = load_h2_precomputation(m_comm, path, h2_precomputation_fingerprint(fingerprint()));
  m_seconds["load"] += timer.seconds();
}

void StaticSession::save(const std::string &path, const std::vector<std::string> &inputs) const
{
  std::shared_ptr<const H2DistributedSystem> sys;
  std::vector<int> node_part;
  const H2Factorization *F = nullptr;
  PetscBool of_matrix = PETSC_FALSE;
  PC pc;
  if (m_A) HssbemCallThrow(HssbemMatGetH2System(m_A, &sys, &node_part));
  if (m_ksp) HssbemCallThrow(KSPGetPC(m_ksp, &pc));
  if (m_ksp) HssbemCallThrow(HssbemPCH2GetFactorization(pc, &F, &of_matrix));
  if (!sys || !F || !of_matrix)
    throw std::invalid_argument("-hssbem_save: only a static solve on the H2 operator with PC h2 factoring it is saved (-bem_mat_type h2 -pc_type h2, -pc_h2_rel_tol not below -mat_h2_rel_tol), after its solve");
  save_h2_precomputation(m_comm, path, inputs, h2_precomputation_fingerprint(fingerprint()), node_part, *sys, *F);
}

const HssbemSolveInfo &StaticSession::solve(bool to_all)
{
  assemble();
  const Timer timer;
  Vec x, xmesh; // xmesh: the solution in mesh order (the distributed H² system's rows are in cluster order)
  HssbemCallThrow(VecDuplicate(m_b, &x));
  HssbemCallThrow(HssbemSolveSystem(m_ksp, &m_A, m_b, x, &m_info));
  m_seconds["solve"] += timer.seconds();
  HssbemCallThrow(HssbemMatCreateMeshOrderVec(m_A, &xmesh));
  HssbemCallThrow(HssbemVecToMeshOrder(m_A, x, xmesh));
  m_x = gather(xmesh, to_all);
  HssbemCallThrow(VecDestroy(&xmesh));
  HssbemCallThrow(VecDestroy(&x));
  run_collectively(m_comm, [&] { check_solution(m_x, m_info); }); // rank 0 alone may hold the solution
  return m_info;
}

ResultData StaticSession::result()
{
  const ProblemSetup &s = m_problem->setup();
  PetscMPIInt size;
  HssbemCallMPIThrow(MPI_Comm_size(m_comm, &size));
  ResultData r;
  NodalSolution sol;
  SurfaceFields f;
  run_collectively(m_comm, [&] { // every rank post-processes the whole solution (cheap beside the solve)
    r = result_base(s, size);
    const Timer timer;
    const EventScope event(BEM_Post);
    fault_point("Post");
    sol = split_unknowns(s.selection, m_x);
    if (s.pure_traction) remove_whole_rigid_motion(*s.disc, s.body_force, sol.u);
    const double stress_before = m_seconds["stress"];
    f = surface_fields(s, sol, s.body_force, s.vertex_displacement_prescribed, kResultFields, &m_seconds);
    m_seconds["post"] += timer.seconds() - (m_seconds["stress"] - stress_before);
  });
  const std::vector<NodeStress> nodes = f.nodes;
  put_fields(std::move(f), r);
  interior_fields(m_comm, s, sol, nodes, m_options.interior, r, m_seconds);
  describe(s, m_info, m_choice.type, r);
  put_options(options_used(), r);
  r.timings = m_seconds; // rank 0's are written
  return r;
}

OptionValues StaticSession::options_used() const
{
  OptionValues v = option_values(m_options, kStatic);
  if (m_ksp) HssbemCallThrow(HssbemKSPGetOptionValues(m_ksp, &v));
  return v;
}

Fingerprint StaticSession::fingerprint() const
{
  PetscMPIInt size;
  HssbemCallMPIThrow(MPI_Comm_size(m_comm, &size));
  const std::vector<std::array<bool, 3>> &known = m_problem->setup().selection.displacement_known;
  std::vector<char> pattern(3 * known.size());
  for (std::size_t i = 0; i < pattern.size(); ++i) pattern[i] = known[i / 3][i % 3];
  OptionValues used = options_used();
  used["bem_mat_type"] = OptionValue::of(*find_option("bem_mat_type"), std::string(operator_type_name(m_choice.type)));
  return hssbem::fingerprint(*m_problem, pattern, {}, used, size);
}

std::vector<double> solve_problem(MPI_Comm comm, const ProblemSetup &s, const BemOperator &op, OperatorType type, bool to_all, HssbemSolveInfo *info,
                                  std::map<std::string, double> *seconds)
{
  SessionOptions o = session_options_from_database(comm, kStatic);
  o.operator_type = type;
  StaticSession session(comm, std::make_shared<SessionProblem>(s, op), o);
  const HssbemSolveInfo &done = session.solve(to_all);
  if (info) *info = done;
  if (seconds)
    for (const char *phase : {"assembly", "solve"}) (*seconds)[phase] += session.timings()[phase];
  return session.solution();
}

SessionOptions session_options_from_database(MPI_Comm comm, unsigned jobs)
{
  OptionValues given;
  HssbemCallThrow(HssbemOptionsGetValues(comm, NULL, OptionReader::Driver, jobs, &given));
  HssbemCallThrow(HssbemOptionsGetValues(comm, NULL, OptionReader::System, jobs, &given));
  return session_options(given);
}

} // namespace hssbem
