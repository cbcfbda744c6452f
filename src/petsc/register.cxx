#include "hssbem/petsc/log.h"
#include "hssbem/petsc/options.h"
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

/* Every log event, in the order -log_view lists them (sub-events with a leading space). */
static const struct {
  const char    *name;
  PetscLogEvent *event;
} Events_Private[] = {
  {"BEMMesh", &BEM_Mesh}, {"BEMAssembly", &BEM_Assembly}, {" BEMPartition", &BEM_Partition}, {"BEMSolve", &BEM_Solve}, {"BEMPost", &BEM_Post}, {" BEMStress", &BEM_Stress},
  {" BEMInterior", &BEM_Interior}, {"BEMOutput", &BEM_Output},
  {"HSSTree", &HSS_Tree}, {"HSSCompress", &HSS_Compress}, {"HSSNearField", &HSS_NearField}, {"HSSTruncate", &HSS_Truncate}, {"HSSFactor", &HSS_Factor},
  {"HSSSolve", &HSS_Solve}, {"HSSMatMult", &HSS_MatMult}, {" HSSFactorTop", &HSS_FactorTop}, {" HSSSolveTop", &HSS_SolveTop},
  {"H2Tree", &H2_Tree}, {"H2Compress", &H2_Compress}, {"H2NearField", &H2_NearField}, {"H2MatMult", &H2_MatMult},
  {"H2Factor", &H2F_Factor}, {" H2FactorSketch", &H2F_Sketch}, {" H2FactorLevels", &H2F_Eliminate}, {" H2FactorMerge", &H2F_Merge}, {" H2FactorTop", &H2F_Top},
  {"H2FactorSolve", &H2F_Solve},
  {"SceneSetup", &SCN_Setup}, {"SceneFrame", &SCN_Frame}, {" SceneUpdate", &SCN_Update}, {" SceneApply", &SCN_Apply}, {" SceneRefactor", &SCN_Refactor},
  {" SceneKrylov", &SCN_Krylov},
  {"ContactSetup", &CNT_Setup}, {" ContactDetect", &CNT_Detect}, {" ContactSolve", &CNT_Solve}, {" ContactFields", &CNT_Fields}, {" ContactCorrect", &CNT_Correct}
};

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
static double    ProgressAfter            = hssbem::option_default::hssbem_progress_after;

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
  const hssbem::OptionRow *on_row, *after_row;
  hssbem::OptionValue      on, after;
  PetscBool                set;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(PETSC_COMM_WORLD, &rank));
  PetscCall(HssbemOptionRow("hssbem_progress", &on_row));
  PetscCall(HssbemOptionRow("hssbem_progress_after", &after_row));
  on    = hssbem::OptionValue::of(*on_row, isatty(STDERR_FILENO) ? 1.0 : 0.0); /* the table's default is "a terminal" */
  after = hssbem::OptionValue::default_of(*after_row);
  PetscCall(HssbemOptionsGetValue(PETSC_COMM_WORLD, NULL, *on_row, &on, &set));
  PetscCall(HssbemOptionsGetValue(PETSC_COMM_WORLD, NULL, *after_row, &after, &set));
  ProgressAfter      = after.number;
  ProgressOnTerminal = isatty(STDERR_FILENO) != 0;
  hssbem::set_progress_hook(rank == 0 && on.number != 0 ? ProgressHook_Private : nullptr);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Test-only fault injection (core/fault.hpp), from options that -help does not list: -hssbem_fault
   <site>, _kind, _rank, _seconds and _count (the sites and kinds: docs/reliability.md, "Checks"). */
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
  for (const auto &e : Events_Private) PetscCall(PetscLogEventRegister(e.name, HSSBEM_CLASSID, e.event));
  hssbem::set_phase_hook(PhaseHook_Private);
  PetscCall(PCRegister(PCHSS, PCCreate_HSS));
  PetscCall(PCRegister(PCH2, PCCreate_H2));
  PetscCall(ArmFaultFromOptions_Private());
  PetscCall(ProgressFromOptions_Private());
  PetscCall(PetscRegisterFinalize(HssbemFinalizePackage));
  PetscFunctionReturn(PETSC_SUCCESS);
}
