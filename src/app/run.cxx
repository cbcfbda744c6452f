// The hssbem driver: the command line, the problem file, the job's session, the result file (see run.hpp).
#include "hssbem/app/run.hpp"

#include "hssbem/core/fault.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/io/hdf5_output.hpp"
#include "hssbem/io/temp_files.hpp"
#include "hssbem/petsc/log.h"
#include "hssbem/session/petsc_call.hpp"
#include "hssbem/session/result_fields.hpp"
#include "hssbem/session/static_session.hpp"

#include <optional>
#include <stdexcept>

namespace hssbem {

namespace {

/// Every rank reads the problem and the mesh (they need the geometry); rank 0 alone checks the
/// output path, since rank 0 alone creates and renames it. A failure on any rank (files that
/// differ between nodes, say) ends every rank with the same message.
std::shared_ptr<const ProblemSetup> set_up(MPI_Comm comm, const std::string &file, const ProblemOverrides &ov)
{
  const EventScope              event(BEM_Mesh);
  std::shared_ptr<ProblemSetup> s;
  PetscMPIInt                   rank;

  HssbemCallMPIThrow(MPI_Comm_rank(comm, &rank));
  run_collectively(comm, [&] {
    s = std::make_shared<ProblemSetup>(setup_problem(file, ov));
    check_interior_points(*s);
    if (rank == 0 && !s->output.empty()) check_output_path(s->output, s->input_files);
  });
  return s;
}

/// -hssbem_load: the H² operator and PC h2's factors of the file instead of the compression and
/// the factorization (read and checked here; unpacked by the assembly and the PC's set-up).
void load_static(MPI_Comm comm, StaticSession &session, const std::string &path)
{
  const Timer timer;
  session.load(path);
  session.assemble();
  HssbemCallThrow(PetscPrintf(comm, "hssbem: static: loaded the H2 operator from %s in %.2f s\n", path.c_str(), timer.seconds()));
}

/// -hssbem_save: after the solve (its factors are PC h2's set-up), every rank its part.
void save_static(MPI_Comm comm, const StaticSession &session, const std::string &path, const std::vector<std::string> &inputs)
{
  const Timer timer;
  session.save(path, inputs);
  HssbemCallThrow(PetscPrintf(comm, "hssbem: static: saved the precomputation to %s in %.2f s\n", path.c_str(), timer.seconds()));
}

/// The OptionJob bit of a job.
unsigned job_bit(JobKind job) { return job == JobKind::Static ? kStatic : job == JobKind::Scene ? kScene : kContact; }

} // namespace

void check_save_load(const DriverOptions &o, const std::string &output)
{
  if (!o.save.empty() && o.save == output) throw std::invalid_argument("-hssbem_save: '" + o.save + "' is the result file");
  if (!o.save.empty() && o.save == o.load) throw std::invalid_argument("-hssbem_save: '" + o.save + "' is the file -hssbem_load reads");
}

std::vector<std::string> save_load_inputs(const DriverOptions &o, const ProblemSetup &s)
{
  std::vector<std::string> inputs = s.input_files;
  if (!o.load.empty()) inputs.push_back(o.load);
  if (!o.save.empty()) check_not_an_input(o.save, inputs); // before the set-up it would save
  return inputs;
}

void print_summary(MPI_Comm comm, const SessionProblem &p, const std::string &tail)
{
  PetscMPIInt size;
  HssbemCallMPIThrow(MPI_Comm_size(comm, &size));
  const ProblemSetup &s = p.setup();
  HssbemCallThrow(PetscPrintf(comm, "hssbem: %s: %d vertices, %d triangles, %d dof nodes (%d sharp vertices), %lld unknowns, %d ranks%s\n", s.spec.mesh_path.c_str(),
                              s.mesh->num_vertices(), s.mesh->num_triangles(), s.disc->num_nodes(), s.disc->num_sharp_vertices(), p.unknowns(), size, tail.c_str()));
}

void run_static(MPI_Comm comm, const DriverOptions &o, std::shared_ptr<const SessionProblem> problem, std::map<std::string, double> seconds)
{
  StaticSession session(comm, problem, o.session);
  session.timings() = std::move(seconds);
  print_summary(comm, *problem, ", " + std::string(operator_type_name(session.operator_type())) + " operator" + session.choice_reason());
  fault_point("Driver"); /* tests: an error no guard makes collective (the last resort of app/main.hpp) */
  session.create_solver();
  check_unused_options(comm, true);
  check_save_load(o, problem->setup().output);
  const std::vector<std::string> inputs = save_load_inputs(o, problem->setup());
  if (!o.load.empty()) load_static(comm, session, o.load);
  const HssbemSolveInfo &info = session.solve();
  HssbemCallThrow(PetscPrintf(comm, "hssbem: solved with %s/%s%s%s: %" PetscInt_FMT " iterations, relative residual %.3e\n", info.ksp_type.c_str(), info.pc_type.c_str(),
                              info.solver_type.empty() ? "" : "/", info.solver_type.c_str(), info.iterations, (double)info.residual));
  if (!o.save.empty()) save_static(comm, session, o.save, inputs);
  check_unused_options(comm, false);
  const ResultData r = session.result();
  const std::string &output = problem->setup().output;
  if (output.empty()) return;
  {
    const EventScope event(BEM_Output);
    write_result(comm, output, r);
  }
  HssbemCallThrow(PetscPrintf(comm, "hssbem: wrote %s\n", output.c_str()));
}

void run_problem(MPI_Comm comm, const DriverOptions &o)
{
  std::map<std::string, double> seconds; // per phase, for the result file
  const Timer                   timer;

  const std::shared_ptr<const ProblemSetup> s = set_up(comm, o.problem, o.overrides);
  for (const auto &n : s->notices) HssbemCallThrow(PetscPrintf(comm, "hssbem: notice: %s\n", n.c_str()));
  std::shared_ptr<const SessionProblem> problem; // every rank builds the operator: a failure on one must stop them all
  run_collectively(comm, [&] {
    fault_point("Operator");
    problem = std::make_shared<SessionProblem>(s, o.session.quad);
  });
  seconds["setup"] += timer.seconds();
  if (o.help) print_help(comm, job_bit(problem->job()));
  switch (problem->job()) {
  case JobKind::Static: run_static(comm, o, problem, std::move(seconds)); break;
  case JobKind::Scene: run_scene(comm, o, problem, std::move(seconds)); break;
  case JobKind::Contact: run_contact(comm, o, problem, std::move(seconds)); break;
  }
}

void run_driver(MPI_Comm comm)
{
  const DriverOptions o = read_driver_options(comm);
  if (!o.problem.empty()) {
    run_problem(comm, o);
    return;
  }
  if (!o.help) throw std::runtime_error("no problem file; give -problem FILE.json (-help lists the options)");
  print_help(comm, kEvery);
  HssbemCallThrow(PetscPrintf(comm, "\nPETSc's own options of the main solve follow, as PETSc lists them for the default solver of the H2 operator:\n"));
  KSP ksp;
  HssbemCallThrow(HssbemKSPCreate(comm, operator_type_name(OperatorType::H2), &ksp)); /* GMRES + PC h2: PETSc lists their options */
  HssbemCallThrow(KSPDestroy(&ksp));
}

} // namespace hssbem
