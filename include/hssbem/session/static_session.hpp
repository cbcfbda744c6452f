/// \file static_session.hpp
/// A static solve, whatever face asked for it (the driver, a program, the Python module): the
/// operator chosen (dense, H², HSS; auto by the size and the machine), the main KSP with the
/// operator's defaults and PETSc's options (-ksp_*, -pc_*), the system assembled or compressed,
/// the solve, and the result's fields. Collective on its communicator: every rank takes every
/// step, and a failure on any rank ends the step on every rank (run_collectively, HssbemGuard).
///
///   StaticSession session(comm, problem, options);
///   session.create_solver(); // option errors surface here, before the expensive part
///   session.assemble();      // the precomputation: the operator (and, in the solve, its PC's factors)
///   session.solve();
///   write_result(comm, path, session.result());
#pragma once

#include "hssbem/io/hdf5_output.hpp"
#include "hssbem/petsc/system.h"
#include "hssbem/session/choice.hpp"
#include "hssbem/session/fingerprint.hpp"
#include "hssbem/session/options.hpp"
#include "hssbem/session/problem.hpp"

#include <mpi.h>

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace hssbem {

struct LoadedH2Part;

class StaticSession {
public:
  /// Chooses the operator (the machine's limits measured on comm). `problem` is kept.
  StaticSession(MPI_Comm comm, std::shared_ptr<const SessionProblem> problem, const SessionOptions &options);
  ~StaticSession();
  StaticSession(const StaticSession &) = delete;
  StaticSession &operator=(const StaticSession &) = delete;

  OperatorType operator_type() const { return m_choice.type; }
  /// Why auto chose it (" (auto: below 6000 unknowns)"); empty when it was asked for.
  const std::string &choice_reason() const { return m_choice.why; }

  /// The main KSP: the operator's defaults, then PETSc's options database.
  void create_solver();
  /// The system A x = b on every rank: assembled (dense) or compressed (H², HSS), after the size
  /// check (core/size_limits.hpp) with the solver's options.
  void assemble();
  /// Solves A x = b (create_solver() and assemble() first, when not done): the whole solution on
  /// every rank (3 per dof node, node order; without to_all on rank 0 only, and result() then
  /// needs it everywhere), checked finite; with pure traction the rigid motion is removed from
  /// the result's displacement. With a body force (ProblemSetup::body_force) the system and
  /// solution() are those of the homogeneous problem; result() adds the particular solution to
  /// every field. Throws PetscFailure for a failed solve.
  const HssbemSolveInfo &solve(bool to_all = true);
  const std::vector<double> &solution() const { return m_x; }

  /// The result file's data on every rank (collective: the interior points are shared out):
  /// the problem's base, the surface fields, the stress, the interior points, the solver's
  /// attributes, the options used (/options) and the timings so far.
  ResultData result();

  /// The options this solve used: the session's and those of the KSP and its PC.
  OptionValues options_used() const;
  /// Seconds per phase ("assembly", "solve", "post", "stress", "interior"; a face may add its own).
  std::map<std::string, double> &timings() { return m_seconds; }
  /// What the precomputation depends on.
  Fingerprint fingerprint() const;

  /// After solve() on the H² operator with PC h2 (the default path): saves the precomputation —
  /// the H² matrix and PC h2's factors, every rank its part (session/h2_file.hpp) — to `path`
  /// (not over one of `inputs`). Collective; throws std::invalid_argument on another path or
  /// before the solve, std::runtime_error when a file cannot be written.
  void save(const std::string &path, const std::vector<std::string> &inputs = {}) const;
  /// Before assemble(): the precomputation saved in `path` is the operator and PC h2's factors
  /// instead of the compression and the factorization (collective). Throws std::runtime_error
  /// ("cannot load '<path>': ...", naming the first difference) for a file that is damaged or
  /// was made for another problem, options or number of ranks; std::invalid_argument when this
  /// solve does not take the H² operator.
  void load(const std::string &path);

  /// The PETSc objects (null before create_solver() or assemble()): a program's own KSP, or the
  /// Python module's petsc4py objects, may take them.
  KSP ksp() const { return m_ksp; }
  Mat matrix() const { return m_A; }
  Vec rhs() const { return m_b; }
  const SessionProblem &problem() const { return *m_problem; }

private:
  void destroy();
  /// The loaded parts as the system's matrix (so.h2_source) and as PC h2's factors.
  void use_loaded(HssbemSystemOptions &so);

  MPI_Comm m_comm;
  std::shared_ptr<const SessionProblem> m_problem;
  SessionOptions m_options;
  MachineLimits m_limits;
  OperatorChoice m_choice;
  KSP m_ksp = nullptr;
  Mat m_A = nullptr;
  Vec m_b = nullptr;
  HssbemSolveInfo m_info;
  std::vector<double> m_x;
  std::map<std::string, double> m_seconds;
  std::shared_ptr<LoadedH2Part> m_loaded; ///< load(): the parts read, unpacked by assemble() and the PC's set-up
};

/// A prepared problem solved with the operator `type` and the options of the options database
/// (as the driver reads them), the unknowns (3 per dof node, node order) on every rank, or on
/// rank 0 only (empty elsewhere) without to_all. Fills info when given, and adds the seconds of
/// the assembly and the solve to `seconds`.
std::vector<double> solve_problem(MPI_Comm comm, const ProblemSetup &s, const BemOperator &op, OperatorType type, bool to_all, HssbemSolveInfo *info = nullptr,
                                  std::map<std::string, double> *seconds = nullptr);

/// The options the options database gives for `jobs` (those of the driver and of the system
/// builder, core/option_table.def), typed and checked: session_options() of what is given.
/// Throws PetscFailure for a value PETSc cannot parse, std::invalid_argument for one out of range.
SessionOptions session_options_from_database(MPI_Comm comm, unsigned jobs);

} // namespace hssbem
