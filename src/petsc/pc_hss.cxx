/* PC "hss": ULV factorization of the BEM system matrix from an HSS compression, as a direct
   solver (-ksp_type preonly) or a preconditioner at a loose tolerance (see pc_hss.h). */
#include "hssbem/petsc/pc_hss.h"
#include "hssbem/core/fault.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/hss/truncate.hpp"
#include "hssbem/hss/ulv.hpp"

#include "mat_compressed.hpp"

#include <petsc/private/pcimpl.h>

#include <exception>
#include <memory>
#include <string>

namespace {

/* Where the PC's compression came from. */
enum class Source { None, Matrix, Truncated, Compressed };
const char *SourceName(Source s)
{
  switch (s) {
  case Source::Matrix: return "the matrix's own compression";
  case Source::Truncated: return "truncated from the matrix's compression (no kernel entries evaluated)";
  case Source::Compressed: return "compressed from the operator";
  default: return "not set up";
  }
}

struct PC_HSS {
  PetscReal rel_tol   = 0;  /* <= 0: the matrix's tolerance (1e-8 on a dense matrix, 1e-3 on an H² one) */
  PetscInt  leaf_size = 0;  /* <= 0: the matrix's leaf size (256 on a dense matrix) */
  PetscInt  max_rank  = -1; /* -1: the matrix's cap (none on a dense matrix) */
  /* set up (rank 0) */
  Source                                        source = Source::None;
  hssbem::HssOptions                            used;
  std::shared_ptr<const hssbem::HssBemSystem>   sys;
  std::unique_ptr<hssbem::UlvFactorization>     factors;
  std::string                                   failure;
  double                                        seconds_compress = 0, seconds_factor = 0;
  std::unique_ptr<HssbemRootExchange>           ex;
};

/* Rank 0: the compression at the PC's options, then the factors; returns a breakdown in
   hss->failure, other errors as exceptions. */
void FactorOnRoot(PC_HSS *hss, const HssbemSystemContext &p)
{
  const bool         on_hss = p.type == hssbem::OperatorType::Hss;
  hssbem::HssOptions o      = on_hss ? p.hss_options : hssbem::HssOptions{};
  if (!on_hss) o.rel_tol = p.type == hssbem::OperatorType::H2 ? 1e-3 : 1e-8; /* on H², a preconditioner for GMRES around the accurate product (DESIGN §6) */
  o.pressure_columns = false; /* the factorization needs H and G only */
  if (hss->rel_tol > 0) o.rel_tol = hss->rel_tol;
  if (hss->leaf_size > 0) o.leaf_size = (int)hss->leaf_size;
  if (hss->max_rank > 0) o.max_rank = (int)hss->max_rank; /* else the matrix's cap (none on a dense matrix) */
  hss->used = o;
  hssbem::Timer timer;
  const bool    same_tree = on_hss && p.hss && o.leaf_size == p.hss_options.leaf_size;
  if (same_tree && o.rel_tol == p.hss_options.rel_tol && o.max_rank == p.hss_options.max_rank) {
    hss->sys    = p.hss;
    hss->source = Source::Matrix;
  } else if (same_tree && o.rel_tol >= p.hss_options.rel_tol && (p.hss_options.max_rank < 0 || (o.max_rank > 0 && o.max_rank <= p.hss_options.max_rank))) {
    hss->sys    = std::make_shared<hssbem::HssBemSystem>(*p.op, hssbem::truncate_hss(p.hss->matrix(), o.rel_tol, o.max_rank));
    hss->source = Source::Truncated;
  } else {
    hss->sys    = std::make_shared<hssbem::HssBemSystem>(*p.op, o);
    hss->source = Source::Compressed;
  }
  hss->seconds_compress = timer.seconds();
  timer.restart();
  try {
    if (hssbem::fault_armed("Breakdown")) throw hssbem::HssBreakdown("HSS factorization broke down (injected fault at Breakdown)");
    hss->factors = hss->sys->factor(p.sel, p.modes.empty() ? nullptr : &p.modes);
  } catch (const hssbem::HssBreakdown &e) {
    hss->failure = e.what();
  }
  hss->seconds_factor = timer.seconds();
}

PetscErrorCode PCSetUp_HSS(PC pc)
{
  PC_HSS              *hss = (PC_HSS *)pc->data;
  HssbemSystemContext *p;
  MPI_Comm             comm = PetscObjectComm((PetscObject)pc);
  PetscMPIInt          rank;
  HssbemGuard          guard;
  int                  breakdown = 0;

  PetscFunctionBegin;
  PetscCall(HssbemMatGetSystemContext(pc->pmat, &p));
  PetscCheck(p, comm, PETSC_ERR_ARG_WRONG, "PC hss factors BEM system matrices only: build the matrix with HssbemCreateSystem() (the hssbem driver does)");
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  hss->factors.reset();
  hss->sys.reset();
  hss->failure.clear();
  guard.Run("PCSetUp", [&] {
    if (rank == 0) FactorOnRoot(hss, *p); /* the compression lives on rank 0 */
  });
  PetscCall(guard.Check(comm, "PC hss set-up"));
  breakdown = rank == 0 && !hss->failure.empty();
  PetscCallMPI(MPI_Bcast(&breakdown, 1, MPI_INT, 0, comm));
  if (breakdown) {
    PetscCall(PetscInfo(pc, "HSS factorization broke down: %s\n", rank == 0 ? hss->failure.c_str() : "on rank 0"));
    PetscCall(PCSetFailedReason(pc, PC_FACTOR_NUMERIC_ZEROPIVOT));
  }
  PetscCallCXX(hss->ex = std::make_unique<HssbemRootExchange>(p->system_of_dof));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCApply_HSS(PC pc, Vec x, Vec y)
{
  PC_HSS            *hss = (PC_HSS *)pc->data;
  HssbemGuard        guard;
  const PetscScalar *xa;
  PetscScalar       *ya;
  PCFailedReason     reason;

  PetscFunctionBegin;
  PetscCall(PCGetFailedReason(pc, &reason));
  if (reason) { /* a failed factorization: tell the Krylov method, do not crash */
    PetscCall(VecSetInf(y));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PetscCall(hss->ex->SetUp(x));
  PetscCall(hss->ex->Gather(x, &xa));
  PetscCall(hss->ex->GetOut(&ya));
  guard.Run("PCApply", [&] {
    if (!hss->factors) return; /* rank 0 holds them */
    const std::vector<double> b(xa, xa + 3 * hss->sys->op().num_nodes());
    const std::vector<double> z = hss->sys->solve(*hss->factors, b);
    std::copy(z.begin(), z.end(), ya);
  });
  PetscCall(hss->ex->RestoreGather(&xa));
  PetscCall(hss->ex->ScatterOut(&ya, y));
  PetscCall(guard.Check(PetscObjectComm((PetscObject)pc), "PC hss"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCReset_HSS(PC pc)
{
  PC_HSS *hss = (PC_HSS *)pc->data;

  PetscFunctionBegin;
  hss->factors.reset();
  hss->sys.reset();
  hss->ex.reset();
  hss->source = Source::None;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCDestroy_HSS(PC pc)
{
  PetscFunctionBegin;
  PetscCall(PCReset_HSS(pc));
  delete (PC_HSS *)pc->data;
  pc->data = NULL;
  PetscCall(PetscObjectComposeFunction((PetscObject)pc, "PCHSSSetRelTol_C", NULL));
  PetscCall(PetscObjectComposeFunction((PetscObject)pc, "PCHSSSetLeafSize_C", NULL));
  PetscCall(PetscObjectComposeFunction((PetscObject)pc, "PCHSSSetMaxRank_C", NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCSetFromOptions_HSS(PC pc, PetscOptionItems *PetscOptionsObject)
{
  PC_HSS *hss = (PC_HSS *)pc->data;

  PetscFunctionBegin;
  PetscOptionsHeadBegin(PetscOptionsObject, "HSS factorization options");
  PetscCall(PetscOptionsReal("-pc_hss_rel_tol", "Relative tolerance of the compression factored (0: the matrix's; 1e-8 on a dense matrix, 1e-3 on an H2 one)", "PCHSSSetRelTol", hss->rel_tol, &hss->rel_tol, NULL));
  PetscCall(PetscOptionsInt("-pc_hss_leaf_size", "Dof nodes per leaf cluster (0: the matrix's; 256 on a dense matrix)", "PCHSSSetLeafSize", hss->leaf_size, &hss->leaf_size, NULL));
  PetscCall(PetscOptionsInt("-pc_hss_max_rank", "Cap on each skeleton (-1: the matrix's; none on a dense matrix)", "PCHSSSetMaxRank", hss->max_rank, &hss->max_rank, NULL));
  PetscOptionsHeadEnd();
  PetscCheck(hss->rel_tol >= 0 && hss->rel_tol < 1, PetscObjectComm((PetscObject)pc), PETSC_ERR_ARG_OUTOFRANGE, "-pc_hss_rel_tol must lie in [0, 1)");
  PetscCheck(hss->leaf_size >= 0, PetscObjectComm((PetscObject)pc), PETSC_ERR_ARG_OUTOFRANGE, "-pc_hss_leaf_size must be 0 (the matrix's) or positive");
  PetscCheck(hss->max_rank == -1 || hss->max_rank > 0, PetscObjectComm((PetscObject)pc), PETSC_ERR_ARG_OUTOFRANGE, "-pc_hss_max_rank must be positive, or -1 for no cap");
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCView_HSS(PC pc, PetscViewer viewer)
{
  PC_HSS   *hss = (PC_HSS *)pc->data;
  PetscBool ascii;

  PetscFunctionBegin;
  PetscCall(PetscObjectTypeCompare((PetscObject)viewer, PETSCVIEWERASCII, &ascii));
  if (!ascii) PetscFunctionReturn(PETSC_SUCCESS);
  char tol[32], leaf[32], cap[32];
  PetscCall(PetscSNPrintf(tol, sizeof(tol), hss->rel_tol > 0 ? "%g" : "the matrix's", (double)hss->rel_tol));
  PetscCall(PetscSNPrintf(leaf, sizeof(leaf), hss->leaf_size > 0 ? "%d" : "the matrix's", (int)hss->leaf_size));
  PetscCall(PetscSNPrintf(cap, sizeof(cap), hss->max_rank > 0 ? "%d" : "the matrix's", (int)hss->max_rank));
  PetscCall(PetscViewerASCIIPrintf(viewer, "  HSS ULV factorization: relative tolerance %s, leaf size %s, rank cap %s\n", tol, leaf, cap));
  if (hss->sys) {
    PetscCall(PetscViewerASCIIPrintf(viewer, "  compression at %g (leaf size %d): %s, %.2f s; factorization %.2f s\n", hss->used.rel_tol, hss->used.leaf_size, SourceName(hss->source), hss->seconds_compress,
                                     hss->seconds_factor));
    PetscCall(PetscViewerASCIIPushTab(viewer));
    PetscCall(PetscViewerASCIIPushTab(viewer));
    PetscCall(HssbemViewHssMatrix_Private(viewer, hss->sys->matrix()));
    if (hss->factors)
      PetscCall(PetscViewerASCIIPrintf(viewer, "factors: %.1f MB, largest dense front %d\n", hss->factors->memory_bytes() / 1048576.0, hss->factors->max_front()));
    else PetscCall(PetscViewerASCIIPrintf(viewer, "factorization failed: %s\n", hss->failure.c_str()));
    PetscCall(PetscViewerASCIIPopTab(viewer));
    PetscCall(PetscViewerASCIIPopTab(viewer));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCHSSSetRelTol_HSS(PC pc, PetscReal tol)
{
  PetscFunctionBegin;
  PetscCheck(tol >= 0 && tol < 1, PetscObjectComm((PetscObject)pc), PETSC_ERR_ARG_OUTOFRANGE, "the relative tolerance must lie in [0, 1)");
  ((PC_HSS *)pc->data)->rel_tol = tol;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCHSSSetLeafSize_HSS(PC pc, PetscInt n)
{
  PetscFunctionBegin;
  PetscCheck(n >= 0, PetscObjectComm((PetscObject)pc), PETSC_ERR_ARG_OUTOFRANGE, "the leaf size must be 0 (the matrix's) or positive");
  ((PC_HSS *)pc->data)->leaf_size = n;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCHSSSetMaxRank_HSS(PC pc, PetscInt k)
{
  PetscFunctionBegin;
  PetscCheck(k == -1 || k > 0, PetscObjectComm((PetscObject)pc), PETSC_ERR_ARG_OUTOFRANGE, "the rank cap must be positive, or -1 for none");
  ((PC_HSS *)pc->data)->max_rank = k;
  PetscFunctionReturn(PETSC_SUCCESS);
}

} // namespace

/*MC
  PCHSS - ULV factorization of the BEM system matrix from an HSS compression (hssbem).

  Options Database Keys:
+ -pc_hss_rel_tol <tol>   - tolerance of the compression factored (0: the matrix's, a direct solve)
. -pc_hss_leaf_size <n>   - dof nodes per leaf (0: the matrix's)
- -pc_hss_max_rank <k>    - cap on each skeleton (-1: the matrix's cap; none on a dense matrix)

  Notes:
  With -ksp_type preonly this is a direct solver accurate to about the tolerance; with GMRES and a
  loose tolerance (1e-2 .. 1e-4) a preconditioner. On the HSS matrix a looser tolerance truncates
  the matrix's compression (no kernel entry evaluated); on a dense or H² matrix, or at a tighter
  tolerance, the operator is compressed anew (at 1e-3 by default on an H² matrix, a
  preconditioner for GMRES around the H² product). A breakdown sets PC_FACTOR_NUMERIC_ZEROPIVOT.

  Level: beginner
M*/
PETSC_EXTERN PetscErrorCode PCCreate_HSS(PC pc)
{
  PetscFunctionBegin;
  PetscCallCXX(pc->data = new PC_HSS);
  pc->ops->setup           = PCSetUp_HSS;
  pc->ops->apply           = PCApply_HSS;
  pc->ops->reset           = PCReset_HSS;
  pc->ops->destroy         = PCDestroy_HSS;
  pc->ops->setfromoptions  = PCSetFromOptions_HSS;
  pc->ops->view            = PCView_HSS;
  PetscCall(PetscObjectComposeFunction((PetscObject)pc, "PCHSSSetRelTol_C", PCHSSSetRelTol_HSS));
  PetscCall(PetscObjectComposeFunction((PetscObject)pc, "PCHSSSetLeafSize_C", PCHSSSetLeafSize_HSS));
  PetscCall(PetscObjectComposeFunction((PetscObject)pc, "PCHSSSetMaxRank_C", PCHSSSetMaxRank_HSS));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@
  PCHSSSetRelTol - Sets the tolerance of the compression that PCHSS factors (0: the matrix's).

  Logically Collective

  Level: intermediate
@*/
PetscErrorCode PCHSSSetRelTol(PC pc, PetscReal tol)
{
  PetscFunctionBegin;
  PetscTryMethod(pc, "PCHSSSetRelTol_C", (PC, PetscReal), (pc, tol));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@
  PCHSSSetLeafSize - Sets the leaf size of the compression that PCHSS factors (0: the matrix's).

  Logically Collective

  Level: intermediate
@*/
PetscErrorCode PCHSSSetLeafSize(PC pc, PetscInt n)
{
  PetscFunctionBegin;
  PetscTryMethod(pc, "PCHSSSetLeafSize_C", (PC, PetscInt), (pc, n));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@
  PCHSSSetMaxRank - Caps the skeletons of the compression that PCHSS factors (-1: none).

  Logically Collective

  Level: intermediate
@*/
PetscErrorCode PCHSSSetMaxRank(PC pc, PetscInt k)
{
  PetscFunctionBegin;
  PetscTryMethod(pc, "PCHSSSetMaxRank_C", (PC, PetscInt), (pc, k));
  PetscFunctionReturn(PETSC_SUCCESS);
}
