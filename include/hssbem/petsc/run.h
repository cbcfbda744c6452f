/* One batch solve, from problem file to result file: what the hssbem driver runs. */
#pragma once

#include "hssbem/bem/quadrature.hpp"
#include "hssbem/problem/setup.hpp"

#include <petscsys.h>
#include <string>

/* Set up, assemble, solve, post-process and write. Input errors throw std::exception (same on
   every rank, since every rank reads the same files); PETSc failures return an error code. */
PetscErrorCode HssbemRun(MPI_Comm comm, const std::string &problem_file, const hssbem::ProblemOverrides &overrides, const hssbem::QuadratureOptions &quad);
