/* Log events and class id of hssbem, and the PC type "hss", registered by HssbemInitializePackage(). */
#pragma once

#include "hssbem/petsc/compat.h"

#include <petscsys.h>

PETSC_EXTERN PetscClassId  HSSBEM_CLASSID;
PETSC_EXTERN PetscLogEvent BEM_Mesh, BEM_Assembly, BEM_Partition, BEM_Solve, BEM_Post, BEM_Stress, BEM_Interior, BEM_Output;
/* Phases of the engines (hssbem::Phase), reported through their phase hook, each event named after
   the format that does the work (what each times: docs/running.md, "Log events"). */
PETSC_EXTERN PetscLogEvent HSS_Tree, HSS_Compress, HSS_NearField, HSS_Truncate, HSS_Factor, HSS_Solve, HSS_MatMult, HSS_FactorTop, HSS_SolveTop;
PETSC_EXTERN PetscLogEvent H2_Tree, H2_Compress, H2_NearField, H2_MatMult, H2F_Factor, H2F_Sketch, H2F_Eliminate, H2F_Merge, H2F_Top, H2F_Solve;
/* Phases of a scene (frames): set-up, capacitance update, Woodbury/LU solve, refactorization, Krylov; and one whole frame. */
PETSC_EXTERN PetscLogEvent SCN_Setup, SCN_Update, SCN_Apply, SCN_Refactor, SCN_Krylov, SCN_Frame;
/* Phases of contact (contact/): the set-up (reference factorization, columns of W), and per frame the detection, the solve, the fields. */
PETSC_EXTERN PetscLogEvent CNT_Setup, CNT_Detect, CNT_Solve, CNT_Fields, CNT_Correct;

PETSC_EXTERN PetscErrorCode HssbemInitializePackage(void);
PETSC_EXTERN PetscErrorCode HssbemFinalizePackage(void);
