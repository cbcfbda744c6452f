#include "hssbem/petsc/log.h"
#include "hssbem/petsc/pc_h2.h"
#include "hssbem/petsc/pc_hss.h"
#include "hssbem/core/fault.hpp"
#include "hssbem/core/phase.hpp"
#include "hssbem/core/progress.hpp"

#include <petscksp.h>

#include <cmath>
#include <cstdio>
#include <unistd.h>

PetscClassId  HSSBEM_CLASSID;
PetscLogEvent BEM_Mesh, BEM_Assembly, BEM_Partition, BEM_Solve, BEM_Post, BEM_Stress, BEM_Interior, BEM_Output;
PetscLogEvent HSS_Tree, HSS_Compress, HSS_NearField, HSS_Truncate, HSS_Factor, HSS_Solve, HSS_MatMult, HSS_FactorTop, HSS_SolveTop;
PetscLogEvent H2_Tree, H2_Compress, H2_NearField, H2_MatMult, H2F_Factor, H2F_Sketch, H2F_Eliminate, H2F_Merge, H2F_Top, H2F_Solve;
PetscLogEvent SCN_Setup, SCN_Update, SCN_Apply, SCN_Refactor, SCN_Krylov, SCN_Frame;
PetscLogEvent CNT_Setup, CNT_Detect, CNT_Solve, CNT_Fields, CNT_Correct;

/* The engine's phases as log events (engine phases open and close on the calling thread). */
static void PhaseHook_Private(hssbem::Phase phase, bool begin)
{
  static const PetscLogEvent *event[] = {&HSS_Tree, &HSS_Compress, &HSS_NearField, &HSS_Truncate, &HSS_Factor, &HSS_Solve, &HSS_MatMult, &HSS_FactorTop, &HSS_SolveTop,
                                        &H2_Tree,    &H2_Compress, &H2_NearField, &H2_MatMult,
                                        &H2F_Factor, &H2F_Sketch, &H2F_Eliminate, &H2F_Merge, &H2F_Top, &H2F_Solve,
                                        &SCN_Setup,  &SCN_Update, &SCN_Apply,     &SCN_Refactor, &SCN_Krylov, &CNT_Detect,   &CNT_Solve, &CNT_Fields, &CNT_Correct};
  static_assert(sizeof(event) / sizeof(event[0]) == static_cast<int>(hssbem::Phase::Count), "one log event per phase");
  const PetscLogEvent e = *event[static_cast<int>(phase)];
  if (begin) (void)PetscLogEventBegin(e, 0, 0, 0, 0);
  else (void)PetscLogEventEnd(e, 0, 0, 0, 0);
}

static PetscBool HssbemPackageInitialized = PETSC_FALSE;
static bool      ProgressOnTerminal       = false;
static double    ProgressAfter            = 2;

/* Progress of long work on rank 0's standard error (-hssbem_progress): one updating line on a
   terminal, plain lines otherwise (at most one per phase every 5 s); a phase shorter than
   -hssbem_progress_after seconds (2) says nothing. Never in the result file. */
static void ProgressHook_Private(const char *phase, double done, double seconds)
{
  static const char *shown = nullptr;
  static double      last  = 0;
  const bool         end   = done >= 1;
  if (seconds < ProgressAfter || (!end && shown == phase && seconds - last < (ProgressOnTerminal ? 0.25 : 5))) return;
  shown = phase;
  last  = seconds;
  char left[48] = "";
  if (!end && done > 0.02) std::snprintf(left, sizeof left, ", about %.0f s left", seconds * (1 - done) / done);
  std::fprintf(stderr, "%s%s: %.0f%% done, %.1f s elapsed%s%s", ProgressOnTerminal ? "\r\033[K" : "", phase, 100 * done, seconds, left, end || !ProgressOnTerminal ? "\n" : "");
  std::fflush(stderr);
}

/* -hssbem_progress: on by default when rank 0's standard error is a terminal. */
static PetscErrorCode ProgressFromOptions_Private(void)
{
  PetscMPIInt rank;
  PetscBool   on = isatty(STDERR_FILENO) ? PETSC_TRUE : PETSC_FALSE;
  PetscReal   after = 2;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(PETSC_COMM_WORLD, &rank));
  PetscOptionsBegin(PETSC_COMM_WORLD, NULL, "Progress of long work (hssbem)", NULL);
  PetscCall(PetscOptionsBool("-hssbem_progress", "Report the progress of long phases on rank 0's standard error (default: when it is a terminal)", NULL, on, &on, NULL));
  PetscCall(PetscOptionsReal("-hssbem_progress_after", "Seconds a phase runs before -hssbem_progress reports it", NULL, after, &after, NULL));
  PetscOptionsEnd();
  PetscCheck(after >= 0 && std::isfinite((double)after), PETSC_COMM_WORLD, PETSC_ERR_ARG_OUTOFRANGE, "-hssbem_progress_after must be non-negative and finite, got %g", (double)after);
  ProgressAfter      = (double)after;
  ProgressOnTerminal = isatty(STDERR_FILENO) != 0;
  hssbem::set_progress_hook(rank == 0 && on ? ProgressHook_Private : nullptr);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Test-only fault injection (core/fault.hpp), from options that -help does not list:
   -hssbem_fault <site>           a fault point: MeshRead, Setup, Operator, RigidModes (the set-up,
                                  every rank), MatMult, MatGetDiagonal, PCSetUp, PCApply,
                                  Compression, HssSkeletons, HssCouplings, HssTruncate,
                                  UlvSubtree (every rank's part of the distributed HSS steps),
                                  UlvTop (rank 0's top of the distributed factorization),
                                  DenseAssembly, Breakdown, Gather (the solve),
                                  Post, Write, Commit, SceneSetup, Frame (rank 0's work), Driver
                                  (unguarded: the last resort of app/main.hpp)
   -hssbem_fault_kind <kind>      error (default), oom (std::bad_alloc), pause, unreadable
                                  (MeshRead: the mesh file cannot be opened), or alloc (the
                                  -hssbem_fault_count'th large allocation from the fault point to
                                  the site's end fails; needs the test shim tests/mpi/fail_new.cpp
                                  preloaded; sites PCSetUp of PC h2 and PC hss)
   -hssbem_fault_rank <r>         only on rank r of PETSC_COMM_WORLD (default: every rank)
   -hssbem_fault_seconds <s>      how long a pause lasts (default 60)
   -hssbem_fault_count <n>        alloc: which large allocation fails (0: none, only counted)
   Further sites: Partition (every rank's part of the METIS partition), Exchange (the allocation
   of what arrives in an exchange of records), SpreadTopBreakdown (a spread top's trial solve
   counts as failed on that rank). */
static PetscErrorCode ArmFaultFromOptions_Private(void)
{
  char              site[64] = "", kind[16] = "error";
  PetscInt          rank    = -1, count = 0;
  PetscReal         seconds = 60;
  PetscBool         set;
  PetscMPIInt       me;
  hssbem::FaultPlan plan;

  PetscFunctionBegin;
  PetscCall(PetscOptionsGetString(NULL, NULL, "-hssbem_fault", site, sizeof(site), &set));
  if (!set) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscOptionsGetString(NULL, NULL, "-hssbem_fault_kind", kind, sizeof(kind), NULL));
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-hssbem_fault_rank", &rank, NULL));
  PetscCall(PetscOptionsGetReal(NULL, NULL, "-hssbem_fault_seconds", &seconds, NULL));
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-hssbem_fault_count", &count, NULL));
  PetscCheck(hssbem::parse_fault_kind(kind, &plan.kind), PETSC_COMM_WORLD, PETSC_ERR_ARG_UNKNOWN_TYPE, "-hssbem_fault_kind %s: use error, oom, pause, unreadable or alloc", kind);
  PetscCallMPI(MPI_Comm_rank(PETSC_COMM_WORLD, &me));
  PetscCallCXX(plan.site = site);
  plan.rank    = (int)rank;
  plan.seconds = (double)seconds;
  plan.count   = (long)count;
  PetscCallCXX(hssbem::arm_fault(plan, me));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemFinalizePackage - Resets the package state so HssbemInitializePackage() can run again.

  Level: developer
@*/
PetscErrorCode HssbemFinalizePackage(void)
{
  PetscFunctionBegin;
  HssbemPackageInitialized = PETSC_FALSE;
  hssbem::set_phase_hook(nullptr);
  hssbem::set_progress_hook(nullptr);
  hssbem::arm_fault(hssbem::FaultPlan{}, 0);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemInitializePackage - Registers the class id and the log events of hssbem (one per phase,
  so -log_view shows where the time goes; the compression engines' phases through their phase
  hook) and the PC types "hss" (PCHSS) and "h2" (PCH2). Called once after PetscInitialize(); later calls do
  nothing.

  Level: beginner
@*/
PetscErrorCode HssbemInitializePackage(void)
{
  PetscFunctionBegin;
  if (HssbemPackageInitialized) PetscFunctionReturn(PETSC_SUCCESS);
  HssbemPackageInitialized = PETSC_TRUE;
  PetscCall(PetscClassIdRegister("hssbem", &HSSBEM_CLASSID));
  PetscCall(PetscLogEventRegister("BEMMesh", HSSBEM_CLASSID, &BEM_Mesh));
  PetscCall(PetscLogEventRegister("BEMAssembly", HSSBEM_CLASSID, &BEM_Assembly));
  PetscCall(PetscLogEventRegister(" BEMPartition", HSSBEM_CLASSID, &BEM_Partition));
  PetscCall(PetscLogEventRegister("BEMSolve", HSSBEM_CLASSID, &BEM_Solve));
  PetscCall(PetscLogEventRegister("BEMPost", HSSBEM_CLASSID, &BEM_Post));
  PetscCall(PetscLogEventRegister(" BEMStress", HSSBEM_CLASSID, &BEM_Stress));
  PetscCall(PetscLogEventRegister(" BEMInterior", HSSBEM_CLASSID, &BEM_Interior));
  PetscCall(PetscLogEventRegister("BEMOutput", HSSBEM_CLASSID, &BEM_Output));
  PetscCall(PetscLogEventRegister("HSSTree", HSSBEM_CLASSID, &HSS_Tree));
  PetscCall(PetscLogEventRegister("HSSCompress", HSSBEM_CLASSID, &HSS_Compress));
  PetscCall(PetscLogEventRegister("HSSNearField", HSSBEM_CLASSID, &HSS_NearField));
  PetscCall(PetscLogEventRegister("HSSTruncate", HSSBEM_CLASSID, &HSS_Truncate));
  PetscCall(PetscLogEventRegister("HSSFactor", HSSBEM_CLASSID, &HSS_Factor));
  PetscCall(PetscLogEventRegister("HSSSolve", HSSBEM_CLASSID, &HSS_Solve));
  PetscCall(PetscLogEventRegister("HSSMatMult", HSSBEM_CLASSID, &HSS_MatMult));
  PetscCall(PetscLogEventRegister(" HSSFactorTop", HSSBEM_CLASSID, &HSS_FactorTop));
  PetscCall(PetscLogEventRegister(" HSSSolveTop", HSSBEM_CLASSID, &HSS_SolveTop));
  PetscCall(PetscLogEventRegister("H2Tree", HSSBEM_CLASSID, &H2_Tree));
  PetscCall(PetscLogEventRegister("H2Compress", HSSBEM_CLASSID, &H2_Compress));
  PetscCall(PetscLogEventRegister("H2NearField", HSSBEM_CLASSID, &H2_NearField));
  PetscCall(PetscLogEventRegister("H2MatMult", HSSBEM_CLASSID, &H2_MatMult));
  PetscCall(PetscLogEventRegister("H2Factor", HSSBEM_CLASSID, &H2F_Factor));
  PetscCall(PetscLogEventRegister(" H2FactorSketch", HSSBEM_CLASSID, &H2F_Sketch));
  PetscCall(PetscLogEventRegister(" H2FactorLevels", HSSBEM_CLASSID, &H2F_Eliminate));
  PetscCall(PetscLogEventRegister(" H2FactorMerge", HSSBEM_CLASSID, &H2F_Merge));
  PetscCall(PetscLogEventRegister(" H2FactorTop", HSSBEM_CLASSID, &H2F_Top));
  PetscCall(PetscLogEventRegister("H2FactorSolve", HSSBEM_CLASSID, &H2F_Solve));
  PetscCall(PetscLogEventRegister("SceneSetup", HSSBEM_CLASSID, &SCN_Setup));
  PetscCall(PetscLogEventRegister("SceneFrame", HSSBEM_CLASSID, &SCN_Frame));
  PetscCall(PetscLogEventRegister(" SceneUpdate", HSSBEM_CLASSID, &SCN_Update));
  PetscCall(PetscLogEventRegister(" SceneApply", HSSBEM_CLASSID, &SCN_Apply));
  PetscCall(PetscLogEventRegister(" SceneRefactor", HSSBEM_CLASSID, &SCN_Refactor));
  PetscCall(PetscLogEventRegister(" SceneKrylov", HSSBEM_CLASSID, &SCN_Krylov));
  PetscCall(PetscLogEventRegister("ContactSetup", HSSBEM_CLASSID, &CNT_Setup));
  PetscCall(PetscLogEventRegister(" ContactDetect", HSSBEM_CLASSID, &CNT_Detect));
  PetscCall(PetscLogEventRegister(" ContactSolve", HSSBEM_CLASSID, &CNT_Solve));
  PetscCall(PetscLogEventRegister(" ContactFields", HSSBEM_CLASSID, &CNT_Fields));
  PetscCall(PetscLogEventRegister(" ContactCorrect", HSSBEM_CLASSID, &CNT_Correct));
  hssbem::set_phase_hook(PhaseHook_Private);
  PetscCall(PCRegister(PCHSS, PCCreate_HSS));
  PetscCall(PCRegister(PCH2, PCCreate_H2));
  PetscCall(ArmFaultFromOptions_Private());
  PetscCall(ProgressFromOptions_Private());
  PetscCall(PetscRegisterFinalize(HssbemFinalizePackage));
  PetscFunctionReturn(PETSC_SUCCESS);
}
