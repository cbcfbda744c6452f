/* One batch solve, from problem file to result file: what the hssbem driver runs. */
#pragma once

#include "hssbem/petsc/compat.h"

#include "hssbem/bem/quadrature.hpp"
#include "hssbem/petsc/dense.h"
#include "hssbem/petsc/system.h"
#include "hssbem/problem/setup.hpp"

#include <petscsys.h>
#include <map>
#include <string>
#include <vector>

/* Set up, build the operator (mat_type: HSSBEM_MAT_HSS, HSSBEM_MAT_H2 or HSSBEM_MAT_DENSE), solve, post-process
   and write. Input errors throw std::exception (same on every rank, since every rank reads the
   same files); PETSc failures return an error code. */
PetscErrorCode HssbemRun(MPI_Comm comm, const std::string &problem_file, const hssbem::ProblemOverrides &overrides, const hssbem::QuadratureOptions &quad, const char *mat_type);

/* Build the system of a prepared problem as mat_type and solve it; x_out receives the unknowns (3 per dof
   node) on rank 0, or on every rank with to_all. Phase times are added to seconds when given. */
PetscErrorCode HssbemSolveSetup(MPI_Comm comm, const hssbem::ProblemSetup &s, const hssbem::BemOperator &op, const char *mat_type, PetscBool to_all, std::vector<double> *x_out, HssbemSolveInfo *info,
                                std::map<std::string, double> *seconds);
