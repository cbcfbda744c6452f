/// \file options.hpp
/// The hssbem driver's own options, read from the PETSc options database (the KSP/PC options
/// belong to the solver objects, the -mat_hss_* and -mat_h2_* ones to the system builder of
/// petsc/system.h), and the check that every option given was used.
#pragma once

#include "hssbem/bem/quadrature.hpp"
#include "hssbem/core/operator_type.hpp"
#include "hssbem/problem/setup.hpp"

#include <mpi.h>

#include <string>

namespace hssbem {

/// Everything the command line can set besides the solver's options.
struct AppOptions {
  std::string problem;                            ///< -problem: the problem file (required unless -help)
  ProblemOverrides overrides;                     ///< -mesh, -o, -E, -nu, -bem_feature_angle: they win over the problem file
  OperatorType operator_type = OperatorType::Hss; ///< -bem_mat_type: hss, h2 or dense
  QuadratureOptions quad;                         ///< -mat_bem_*
  bool help = false;                              ///< -help: list the options (PETSc prints each as it is read)
};

/// Read -problem, -mesh, -E, -nu, -o, -bem_feature_angle, -bem_mat_type and -mat_bem_*, and check
/// the -mat_hss_* (or -mat_h2_*) options of the operator type, which the system builder reads
/// again. Throws PetscFailure (app/petsc_call.hpp) for a value out of range, with PETSc's
/// message printed.
AppOptions read_app_options(MPI_Comm comm);

/// Error out on options nobody used, naming them: typos must not pass silently. With
/// before_solve, options that are read only during or after the solve (viewers, converged
/// reason, sub-solvers, factorization packages) are let through; the check after the solve
/// catches everything. Throws PetscFailure (PETSC_ERR_ARG_WRONG), with PETSc's message printed.
void check_unused_options(MPI_Comm comm, bool before_solve);

} // namespace hssbem
