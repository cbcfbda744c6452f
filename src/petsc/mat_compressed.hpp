/* Private to the PETSc layer: the MatShell over a compressed K (HSS or H²). */
#pragma once

#include "system_context.hpp"

#include <petscviewer.h>

/* The MatShell of the system ctx (of type HSS or H², with its hss_options or h2_options set) and
   its right-hand side b: the surface partitioned by METIS (ctx->layout; one rank: one part) and
   each rank compressing its part (ctx->hss or ctx->h2); rows in cluster order
   (ctx->system_of_dof). The Mat's context is ctx (composed with it by the caller). */
PetscErrorCode HssbemMatCreateCompressed_Private(MPI_Comm comm, HssbemSystemContext *ctx, Mat *A, Vec *b);

/* Ranks per level, memory, entries and phase times of an HSS matrix, to an ASCII viewer. */
PetscErrorCode HssbemViewHssMatrix_Private(PetscViewer viewer, const hssbem::HssMatrix &K);

/* The same for an H² matrix, with block counts and memory by part. */
PetscErrorCode HssbemViewH2Matrix_Private(PetscViewer viewer, const hssbem::H2Matrix &K);
