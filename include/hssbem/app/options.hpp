/* Application options of the hssbem driver, read from the PETSc options database. */
#pragma once

#include "hssbem/petsc/compat.h"

#include "hssbem/bem/quadrature.hpp"
#include "hssbem/core/operator_type.hpp"

#include <petscsys.h>
#include <string>

/* Everything the command line can set besides the KSP/PC options; unset optionals mean "take the
   problem file's value". */
struct HssbemAppOptions {
  std::string problem, mesh, output;
  PetscBool   has_E = PETSC_FALSE, has_nu = PETSC_FALSE;
  PetscReal   E = 0, nu = 0;
  PetscReal   feature_angle = 40.0;   /* degrees: dihedral angle above which an edge is sharp */
  hssbem::OperatorType operator_type = hssbem::OperatorType::Hss; /* -bem_mat_type: hss, h2 or dense */
  hssbem::QuadratureOptions quad;    /* -mat_bem_* */
  PetscBool   help = PETSC_FALSE;
};

/* Read -problem, -mesh, -E, -nu, -o, -bem_feature_angle, -bem_mat_type, -mat_bem_*, and check
   -mat_hss_* (read again where the matrix is made); -help lists them. */
PetscErrorCode HssbemProcessOptions(MPI_Comm comm, HssbemAppOptions *opts);

/* Error out (PETSC_ERR_ARG_WRONG) on options nobody used, naming them: typos must not pass silently.
   With before_solve, options that are only read during or after the solve (viewers, converged
   reason) are let through; the final check after the solve catches everything. */
PetscErrorCode HssbemCheckUnusedOptions(MPI_Comm comm, PetscBool before_solve);
