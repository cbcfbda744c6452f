/// \file options.hpp
/// The hssbem driver's own options, read from the PETSc options database (the KSP/PC options
/// belong to the solver objects, the -mat_hss_* and -mat_h2_* ones to the system builder of
/// petsc/system.h), and the check that every option given was used.
#pragma once

#include "hssbem/post/interior_stress.hpp"
#include "hssbem/post/near_surface.hpp"
#include "hssbem/bem/quadrature.hpp"
#include "hssbem/interior/interior_evaluation.hpp"
#include "hssbem/core/operator_type.hpp"
#include "hssbem/core/size_limits.hpp"
#include "hssbem/problem/setup.hpp"
#include "hssbem/scene/dense_scene.hpp"

#include <mpi.h>

#include <optional>
#include <string>

namespace hssbem {

/// The options of a scene (a problem file with "frames"), -scene_*.
struct SceneRunOptions {
  SceneStrategy strategy = SceneStrategy::Auto; ///< -scene_strategy
  int refresh_every = 32;                       ///< -scene_refresh: capacitance updates between rebuilds
  double krylov_rtol = 1e-10;                   ///< -scene_krylov_rtol
  int single_from = 1024;                       ///< -scene_single_from: single-precision capacitance from this many switched unknowns
  int single_fields_from = 1024;                ///< -scene_single_fields_from: single-precision W(:, J) for the fields from this many
  bool monitor = false;                         ///< -scene_monitor: one line per frame
  bool keep_partial = false;                    ///< -scene_keep_partial: a failed frame commits the frames solved before it (still an error)
};

/// Displacement and stress inside the body (interior points and grids), -bem_interior_*.
struct InteriorRunOptions {
  InteriorQuadrature quad;        ///< -bem_interior_near_ratio, -bem_interior_max_depth
  InteriorPlanOptions plan;       ///< -bem_interior_band
  InteriorEvaluationOptions fast; ///< -bem_interior_equivalent_points, _source_leaf, _target_leaf, _direct
};

/// The options of a contact problem (a problem file with "contact"), -contact_*.
struct ContactRunOptions {
  double tol = 1e-10;   ///< -contact_tol: relative tolerance of the gaps and of friction's Newton residual
  int max_it = 50;      ///< -contact_max_it: iterations per frame before it is an error
  double reach = 0;     ///< -contact_reach: candidates within this gap (0: 5 % of the mesh's size)
  double depth = 0;     ///< -contact_depth: a vertex deeper than this behind an open mesh obstacle is not in contact with it (0: the reach)
  bool monitor = false; ///< -contact_monitor: one line per iteration
  double h2_rtol = 1e-10;      ///< -contact_h2_rtol: on the H² path, GMRES tolerance (true residual) of the reference's accurate solves
  double h2_factor_tol = 2e-3; ///< -contact_h2_factor_tol: on the H² path, the tolerance of the reference's H² factorization
};

/// Everything the command line can set besides the solver's options.
struct AppOptions {
  std::string problem;                            ///< -problem: the problem file (required unless -help)
  ProblemOverrides overrides;                     ///< -mesh, -o, -E, -nu, -bem_feature_angle: they win over the problem file
  std::optional<OperatorType> operator_type;      ///< -bem_mat_type: hss, h2 or dense; none: auto (the default, see choose_operator())
  QuadratureOptions quad;                         ///< -mat_bem_*
  SceneRunOptions scene;                          ///< -scene_*
  InteriorRunOptions interior;                    ///< -bem_interior_*
  ContactRunOptions contact;                      ///< -contact_*
  bool help = false;                              ///< -help: list the options (PETSc prints each as it is read)
};

/// -bem_mat_type auto picks the dense operator below this many unknowns and the H² operator
/// (with its default solver, GMRES + PC h2) from it on. Measured with benchmarks/bench_h2_factor
/// at the driver's H² defaults (tol 1e-5, single-precision blocks, leaf 64, eta 0; PC h2 at 3e-3,
/// rtol 1e-8) beside dense assembly + LU in the same run, 1 process, 2 threads, sphere meshes:
/// dense faster at 3 036 and 4 983 unknowns (2.3x, 1.2x), H² faster at 6 990 (1.4x) and 9 030
/// (1.9x): benchmarks/results/2026-11-23-h2-defaults.md (docs/performance.md).
inline constexpr long long k_auto_dense_max_unknowns = 6000;

/// The operator -bem_mat_type auto takes for `unknowns` unknowns on this machine: dense below
/// k_auto_dense_max_unknowns when the dense operator fits (size_refusal()), else H².
OperatorType choose_operator(long long unknowns, const MachineLimits &limits);

/// Read -problem, -mesh, -E, -nu, -o, -bem_feature_angle, -bem_mat_type and -mat_bem_*, and check
/// the -mat_hss_* (or -mat_h2_*) options of the operator type, which the system builder reads
/// again. Throws PetscFailure (app/petsc_call.hpp) for a value out of range, with PETSc's
/// message printed.
AppOptions read_app_options(MPI_Comm comm);

/// -hssbem_error_timeout: seconds the ranks wait for a rank whose error they have not joined
/// before the job is aborted (app/main.hpp); at most a day (a longer wait is a hang).
inline constexpr double k_default_error_timeout = 10, k_max_error_timeout = 86400;

/// The value of -hssbem_error_timeout (k_default_error_timeout when not given). Throws
/// PetscFailure for a value PETSc cannot parse and std::invalid_argument for one outside
/// (0, k_max_error_timeout] (NaN included): 0 or less would abort successful runs, NaN and
/// infinity would wait forever.
double read_error_timeout();

/// Error out on options nobody used, naming them: typos must not pass silently. With
/// before_solve, options that are read only during or after the solve (viewers, converged
/// reason, sub-solvers, factorization packages) are let through; the check after the solve
/// catches everything. Throws PetscFailure (PETSC_ERR_ARG_WRONG), with PETSc's message printed.
void check_unused_options(MPI_Comm comm, bool before_solve);

} // namespace hssbem
