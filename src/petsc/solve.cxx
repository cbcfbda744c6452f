/* The main solve: the KSP with the defaults of the operator type, and A x = b with whatever
   format conversion the factorization needs (see system.h). */
#include "hssbem/petsc/system.h"
#include "hssbem/petsc/log.h"
#include "hssbem/petsc/options.h"
#include "hssbem/petsc/pc_h2.h"
#include "hssbem/petsc/pc_hss.h"

#include "system_context.hpp"

#include "hssbem/core/progress.hpp"
#include "hssbem/core/timer.hpp"

#include <algorithm>

#include <cmath>
#include <string>

/* The format the factorization needs: MATDENSE LU works on one rank only, parallel dense LU is
   ScaLAPACK's, and MUMPS takes AIJ. Krylov methods with point preconditioners keep MATDENSE. */
static PetscErrorCode FactorMatType_Private(KSP ksp, Mat A, MatType *type)
{
  char        solver[64] = "";
  PetscBool   set;
  PetscMPIInt size;
  PC          pc;
  PCType      pctype;

  PetscFunctionBegin;
  *type = NULL;
  PetscCallMPI(MPI_Comm_size(PetscObjectComm((PetscObject)A), &size));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PCGetType(pc, &pctype));
  PetscCall(PetscOptionsGetString(NULL, NULL, "-pc_factor_mat_solver_type", solver, sizeof(solver), &set));
  const std::string pct(pctype ? pctype : ""), st(solver);
  if (pct != PCLU && pct != PCCHOLESKY && pct != PCILU) PetscFunctionReturn(PETSC_SUCCESS);
  {
    PetscBool compressed;
    PetscCall(HssbemMatIsCompressed(A, &compressed));
    PetscCheck(!compressed, PetscObjectComm((PetscObject)A), PETSC_ERR_ARG_INCOMP, "the compressed (HSS or H2) matrix has no entries for -pc_type %s: use -pc_type hss, or -bem_mat_type dense", pct.c_str());
  }
  if (st == "mumps" || st == "superlu_dist") *type = MATAIJ;
  else if (st == "scalapack" || (st.empty() && size > 1)) *type = MATSCALAPACK;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Solve with vectors in the operator's layout (ScaLAPACK picks its own), copying in and out;
   the relative residual ||b - A x|| / ||b|| is measured there too. */
static PetscErrorCode KSPSolveInLayout_Private(KSP ksp, Mat op, Vec b, Vec x, PetscReal *residual)
{
  Vec       bo, xo, r;
  PetscReal bnorm, rnorm;

  PetscFunctionBegin;
  PetscCall(MatCreateVecs(op, &xo, &bo));
  PetscCall(HssbemRowScatterOnce(b, bo, {}, SCATTER_FORWARD)); /* the same rows in another layout */
  PetscCall(KSPSolve(ksp, bo, xo));
  PetscCall(HssbemRowScatterOnce(xo, x, {}, SCATTER_FORWARD));
  PetscCall(VecDuplicate(bo, &r));
  PetscCall(MatMult(op, xo, r));
  PetscCall(VecAYPX(r, -1.0, bo));
  PetscCall(VecNorm(r, NORM_2, &rnorm));
  PetscCall(VecNorm(bo, NORM_2, &bnorm));
  *residual = bnorm > 0 ? rnorm / bnorm : rnorm;
  PetscCall(VecDestroy(&r));
  PetscCall(VecDestroy(&bo));
  PetscCall(VecDestroy(&xo));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The main solve's progress (core/progress.hpp): the share of the way from the first residual
   to the tolerance, on a logarithmic scale. */
struct KSPProgress_Private {
  hssbem::Timer timer;
  PetscReal     r0 = 0;
};

static PetscErrorCode KSPMonitorProgress_Private(KSP ksp, PetscInt it, PetscReal rnorm, void *ctx)
{
  KSPProgress_Private *p    = (KSPProgress_Private *)ctx;
  hssbem::ProgressHook hook = hssbem::progress_hook();
  PetscReal            rtol;
  KSPConvergedReason   reason;
  KSPType              type;

  PetscFunctionBegin;
  if (!hook) PetscFunctionReturn(PETSC_SUCCESS);
  if (it == 0) {
    p->timer.restart();
    p->r0 = rnorm;
  }
  PetscCall(KSPGetTolerances(ksp, &rtol, NULL, NULL, NULL));
  PetscCall(KSPGetConvergedReason(ksp, &reason));
  PetscCall(KSPGetType(ksp, &type));
  const double done = p->r0 > 0 && rnorm > 0 && rtol < 1 ? std::log(p->r0 / rnorm) / std::log(1 / rtol) : 0;
  PetscCallCXX(hook(type, reason != KSP_CONVERGED_ITERATING ? 1.0 : std::min(std::max(done, 0.0), 0.999), p->timer.seconds())); /* a host's hook may throw to stop the solve (Python: Ctrl-C) */
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode KSPProgressDestroy_Private(void **ctx)
{
  PetscFunctionBegin;
  delete (KSPProgress_Private *)*ctx;
  *ctx = NULL;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -hssbem_residual_max: the largest true relative residual ||b - A x|| / ||b|| that counts as a
   solution, whatever the KSP (preonly included: a loose preconditioner applied once is no solve). */
static PetscErrorCode ResidualMax_Private(MPI_Comm comm, PetscReal *bound)
{
  const hssbem::OptionRow *row;
  hssbem::OptionValue      v;
  PetscBool                set;

  PetscFunctionBegin;
  PetscCall(HssbemOptionRow("hssbem_residual_max", &row));
  v = hssbem::OptionValue::default_of(*row);
  PetscCall(HssbemOptionsGetValue(comm, NULL, *row, &v, &set));
  *bound = (PetscReal)v.number;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemKSPCreate - Creates the main solver (no prefix) with the defaults of the matrix type
  (-ksp_type preonly with -pc_type hss on the HSS matrix; GMRES, right-preconditioned so that
  -ksp_rtol bounds the true residual, on the H² one, with -pc_type h2 (the H² factorization
  at its default tolerance, distributed like the matrix: on 2 ranks 22.3 s against 24.9 s with
  Jacobi on an 80k sphere, 6.2-6.3 s against 6.3 s on a 20k disk organ with nu = 0.49, and 6
  iterations against 52-71); -pc_type lu on the dense one) and applies
  the options database, before there is a matrix, so that option errors surface before the
  expensive assembly.

  Level: intermediate
@*/
PetscErrorCode HssbemKSPCreate(MPI_Comm comm, const char *mat_type, KSP *ksp)
{
  PC                   pc;
  hssbem::OperatorType type;
  KSPProgress_Private *progress;

  PetscFunctionBegin;
  PetscCall(HssbemOperatorTypeFromName(comm, mat_type, &type));
  const bool h2 = type == hssbem::OperatorType::H2;
  PetscCall(KSPCreate(comm, ksp));
  PetscCall(KSPSetType(*ksp, h2 ? std::string(hssbem::option_default::ksp_type).c_str() : KSPPREONLY));
  if (h2) { /* the table's defaults on the H² operator (core/option_table.def) */
    PetscCall(KSPGMRESSetRestart(*ksp, hssbem::option_default::ksp_gmres_restart));
    PetscCall(KSPSetTolerances(*ksp, hssbem::option_default::ksp_rtol, PETSC_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT));
    PetscCall(KSPSetPCSide(*ksp, PC_RIGHT));
  }
  PetscCall(KSPGetPC(*ksp, &pc));
  PetscCall(PCSetType(pc, HssbemDefaultPCType(type)));
  PetscCallCXX(progress = new KSPProgress_Private);
  PetscCall(KSPMonitorSet(*ksp, KSPMonitorProgress_Private, progress, KSPProgressDestroy_Private));
  PetscCall(KSPSetFromOptions(*ksp));
  {
    PetscReal bound; /* read here too, so that -help lists it and a bad value stops the run early */
    PetscCall(ResidualMax_Private(comm, &bound));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemSolveSystem - Solves A x = b with a KSP from HssbemKSPCreate(); a dense A is converted in
  place to the format its factorization needs (so no second copy stays alive). A diverged solve
  is an error, and so is one whose true relative residual ||b - A x|| / ||b|| (A's own product)
  is not finite or exceeds -hssbem_residual_max (default: the table's), whatever the KSP:
  with -ksp_type preonly KSP reports convergence after one application of the PC, however loose.

  Options Database Key:
. -hssbem_residual_max <r> - largest true relative residual accepted as a solution

  Level: intermediate
@*/
PetscErrorCode HssbemSolveSystem(KSP ksp, Mat *A, Vec b, Vec x, HssbemSolveInfo *info)
{
  PC            pc;
  MatType       ftype;
  MatSolverType st = NULL;
  PetscReal     bound;

  PetscFunctionBegin;
  PetscCall(ResidualMax_Private(PetscObjectComm((PetscObject)ksp), &bound));
  PetscCall(PetscLogEventBegin(BEM_Solve, 0, 0, 0, 0));
  PetscCall(FactorMatType_Private(ksp, *A, &ftype));
  if (ftype) PetscCall(MatConvert(*A, ftype, MAT_INPLACE_MATRIX, A));
  PetscCall(KSPSetOperators(ksp, *A, *A));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(KSPSolveInLayout_Private(ksp, *A, b, x, &info->residual));
  PetscCall(KSPGetConvergedReason(ksp, &info->reason));
  PetscCall(KSPGetIterationNumber(ksp, &info->iterations));
  {
    KSPType kt;
    PCType  pt;
    PetscCall(KSPGetType(ksp, &kt));
    PetscCall(PCGetType(pc, &pt));
    PetscCallCXX(info->ksp_type = kt);
    PetscCallCXX(info->pc_type = pt);
  }
  PetscCall(PCFactorGetMatSolverType(pc, &st));
  PetscCallCXX(info->solver_type = st ? st : "");
  PetscCall(PetscLogEventEnd(BEM_Solve, 0, 0, 0, 0));
  PetscCheck(info->reason > 0, PetscObjectComm((PetscObject)*A), PETSC_ERR_NOT_CONVERGED, "the linear solve failed: %s after %" PetscInt_FMT " iterations", KSPConvergedReasons[info->reason], info->iterations);
  PetscCheck(std::isfinite((double)info->residual) && info->residual <= bound, PetscObjectComm((PetscObject)*A), PETSC_ERR_NOT_CONVERGED,
             "the linear solve gave no solution: its true relative residual ||b - A x||/||b|| is %.3g, above -hssbem_residual_max %g (%s + %s, %s after %" PetscInt_FMT " iterations)", (double)info->residual, (double)bound,
             info->ksp_type.c_str(), info->pc_type.c_str(), KSPConvergedReasons[info->reason], info->iterations);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemKSPGetSizeOptions - What the size model needs of the solver of a KSP from HssbemKSPCreate()
  (after KSPSetFromOptions): the Krylov method's vectors and, with PC h2, its options.

  Not Collective

  Level: developer
@*/
PetscErrorCode HssbemKSPGetSizeOptions(KSP ksp, hssbem::SizeOptions *o)
{
  PC                      pc;
  PetscBool               preonly, gmres, is_h2;
  PetscInt                restart = hssbem::option_default::ksp_gmres_restart;
  hssbem::H2FactorOptions f;

  PetscFunctionBegin;
  PetscCall(PetscObjectTypeCompare((PetscObject)ksp, KSPPREONLY, &preonly));
  PetscCall(PetscObjectTypeCompare((PetscObject)ksp, KSPGMRES, &gmres));
  if (gmres) PetscCall(KSPGMRESGetRestart(ksp, &restart));
  o->krylov_vectors = preonly ? 0 : (int)restart + 1;
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(HssbemPCH2GetFactorOptions(pc, &f, &is_h2));
  o->h2_factored = is_h2 == PETSC_TRUE;
  if (!is_h2) PetscFunctionReturn(PETSC_SUCCESS);
  o->pc_h2_rel_tol    = f.rel_tol;
  o->pc_h2_top_size   = f.top_size;
  o->pc_h2_mixed_top  = f.single_top_from;
  o->pc_h2_spread_top = f.spread_top;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemKSPGetOptionValues - The options a KSP from HssbemKSPCreate() and its PC use, named as in
  hssbem's table of options.

  Not Collective

  Level: developer
@*/
PetscErrorCode HssbemKSPGetOptionValues(KSP ksp, hssbem::OptionValues *values)
{
  PC        pc;
  KSPType   kt;
  PCType    pt;
  PetscBool gmres;
  PetscReal rtol;
  PetscInt  restart;

  PetscFunctionBegin;
  PetscCall(KSPGetType(ksp, &kt));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PCGetType(pc, &pt));
  PetscCallCXX((*values)["ksp_type"] = hssbem::OptionValue::of(*hssbem::find_option("ksp_type"), std::string(kt)));
  PetscCallCXX((*values)["pc_type"] = hssbem::OptionValue::of(*hssbem::find_option("pc_type"), std::string(pt)));
  PetscCall(PetscObjectTypeCompare((PetscObject)ksp, KSPGMRES, &gmres));
  if (gmres) {
    PetscCall(KSPGetTolerances(ksp, &rtol, NULL, NULL, NULL));
    PetscCall(KSPGMRESGetRestart(ksp, &restart));
    PetscCallCXX((*values)["ksp_rtol"] = hssbem::OptionValue::of(*hssbem::find_option("ksp_rtol"), (double)rtol));
    PetscCallCXX((*values)["ksp_gmres_restart"] = hssbem::OptionValue::of(*hssbem::find_option("ksp_gmres_restart"), (double)restart));
  }
  PetscCall(HssbemPCH2GetOptionValues(pc, values));
  PetscCall(HssbemPCHSSGetOptionValues(pc, values));
  PetscFunctionReturn(PETSC_SUCCESS);
}
