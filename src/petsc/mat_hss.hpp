/* Private to the PETSc layer: the HSS-backed MatShell. */
#pragma once

#include "problem_context.hpp"

#include <petscviewer.h>

/* The MatShell of problem (whose hss_options, or h2_options when is_h2, are set) and b;
   compresses on rank 0. */
PetscErrorCode HssbemMatCreateHss_Private(MPI_Comm comm, HssbemProblem *problem, Mat *A, Vec *b);

/* Ranks per level, memory, entries and phase times of an HSS matrix, to an ASCII viewer. */
PetscErrorCode HssbemViewHssMatrix_Private(PetscViewer viewer, const hssbem::HssMatrix &K);

/* The same for an H² matrix, with block counts and memory by part. */
PetscErrorCode HssbemViewH2Matrix_Private(PetscViewer viewer, const hssbem::H2Matrix &K);
