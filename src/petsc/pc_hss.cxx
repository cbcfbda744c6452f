/* PC "hss": ULV factorization of the BEM system matrix from an HSS compression, as a direct
   solver (-ksp_type preonly) or a preconditioner at a loose tolerance (see pc_hss.h). */
#include "hssbem/petsc/pc_hss.h"
#include "hssbem/core/fault.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/hss/truncate.hpp"
#include "hssbem/hss/hss_system.hpp"
#include "hssbem/hss/ulv.hpp"

#include "mat_compressed.hpp"

#include <petsc/private/pcimpl.h>

#include <exception>
#include <stdexcept>
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
  /* set up */
  Source             source = Source::None;
  hssbem::HssOptions used;
  /* on one rank, or a dense matrix on several: the compression and the factors on rank 0 */
  std::shared_ptr<const hssbem::HssBemSystem> sys;
  /* a distributed matrix (HSS or H²) on several ranks: every rank its part of both */
  std::shared_ptr<const hssbem::HssDistributedSystem> dsys;
  std::vector<int>                                    from_matrix; /* local point k of dsys's tree is the matrix's local point from_matrix[k]; empty: the same */
  std::unique_ptr<hssbem::UlvFactorization>           factors;
  std::string                                         failure;
  double                                              seconds_compress = 0, seconds_factor = 0;
  std::unique_ptr<HssbemRootExchange>                 ex;
};

/* The compression the PC factors: the matrix's options, then the PC's. */
hssbem::HssOptions CompressionOptions_Private(const PC_HSS *hss, const HssbemSystemContext &p)
{
  const bool         on_hss = p.type == hssbem::OperatorType::Hss;
  hssbem::HssOptions o      = on_hss ? p.hss_options : hssbem::HssOptions{};
  if (!on_hss) o.rel_tol = p.type == hssbem::OperatorType::H2 ? 1e-3 : 1e-8; /* on H², a preconditioner for GMRES around the accurate product (DESIGN §6) */
  o.pressure_columns = false; /* the factorization needs H and G only */
  if (hss->rel_tol > 0) o.rel_tol = hss->rel_tol;
  if (hss->leaf_size > 0) o.leaf_size = (int)hss->leaf_size;
  if (hss->max_rank > 0) o.max_rank = (int)hss->max_rank; /* else the matrix's cap (none on a dense matrix) */
  return o;
}

/* Where the PC's compression comes from; has_matrix: the matrix's own HSS compression is at hand. */
Source ChooseSource_Private(const hssbem::HssOptions &o, const HssbemSystemContext &p, bool has_matrix)
{
  const bool same_tree = p.type == hssbem::OperatorType::Hss && has_matrix && o.leaf_size == p.hss_options.leaf_size;
  if (same_tree && o.rel_tol == p.hss_options.rel_tol && o.max_rank == p.hss_options.max_rank) return Source::Matrix;
  if (same_tree && o.rel_tol >= p.hss_options.rel_tol && (p.hss_options.max_rank < 0 || (o.max_rank > 0 && o.max_rank <= p.hss_options.max_rank))) return Source::Truncated;
  return Source::Compressed;
}

/* The factors of hss->sys or hss->dsys; a breakdown in hss->failure, other errors as exceptions.
   An injected breakdown (-hssbem_fault Breakdown) is agreed on by every rank of a distributed
   factorization, so that none waits for the others. */
template <class System>
void Factor_Private(PC_HSS *hss, const HssbemSystemContext &p, const System &sys, const hssbem::RankComm *comm)
{
  hssbem::Timer timer;
  try {
    const bool injected = comm ? comm->any(hssbem::fault_armed("Breakdown")) : hssbem::fault_armed("Breakdown");
    if (injected) throw hssbem::HssBreakdown("HSS factorization broke down (injected fault at Breakdown)");
    hss->factors = sys.factor(p.sel, p.modes.empty() ? nullptr : &p.modes);
  } catch (const hssbem::HssBreakdown &e) {
    hss->failure = e.what();
  }
  hss->seconds_factor = timer.seconds();
}

/* Rank 0: the compression at the PC's options, then the factors. */
void FactorOnRoot(PC_HSS *hss, const HssbemSystemContext &p)
{
  const hssbem::HssOptions o = CompressionOptions_Private(hss, p);
  hss->used                  = o;
  hssbem::Timer timer;
  hss->source = ChooseSource_Private(o, p, p.hss != nullptr);
  if (hss->source == Source::Matrix) hss->sys = p.hss;
  else if (hss->source == Source::Truncated) hss->sys = std::make_shared<hssbem::HssBemSystem>(*p.op, hssbem::truncate_hss(p.hss->matrix(), o.rel_tol, o.max_rank));
  else hss->sys = std::make_shared<hssbem::HssBemSystem>(*p.op, o);
  hss->seconds_compress = timer.seconds();
  Factor_Private(hss, p, *hss->sys, nullptr);
}

/* Every rank (collective): the PC's compression distributed like the matrix (its own, truncated
   from it, or compressed anew on the matrix's METIS partition), then the distributed factors. */
void FactorDistributed(PC_HSS *hss, const HssbemSystemContext &p)
{
  const hssbem::HssOptions o = CompressionOptions_Private(hss, p);
  hss->used                  = o;
  hssbem::Timer timer;
  hss->source = ChooseSource_Private(o, p, p.hssdist != nullptr);
  if (hss->source == Source::Matrix) hss->dsys = p.hssdist;
  else if (hss->source == Source::Truncated) hss->dsys = hssbem::make_shared_collectively<hssbem::HssDistributedSystem>(*p.comm, *p.op, hssbem::truncate_hss(p.hssdist->matrix(), o.rel_tol, o.max_rank, *p.comm), *p.comm);
  else hss->dsys = hssbem::make_shared_collectively<hssbem::HssDistributedSystem>(*p.comm, *p.op, o, p.node_part, *p.comm);
  hss->seconds_compress = timer.seconds();
  /* The same part, so the same points on this rank, perhaps in another order (another leaf size);
     checked on every rank before the factorization's collective steps. */
  hssbem::collectively(*p.comm, [&] {
    const hssbem::DistributedBemSystem &A = *p.distributed();
    const hssbem::ClusterTree          &t = hss->dsys->tree();
    const int                           n = hss->dsys->num_points(), first = hss->dsys->first_point();
    if (n != A.num_points() || first != A.first_point()) throw std::logic_error("PC hss: its compression's rows on this rank are not the matrix's");
    hss->from_matrix.clear();
    if (t.perm() == A.tree().perm()) return; /* the same order: the matrix's tree or a copy of it (truncated) */
    hss->from_matrix.resize((std::size_t)n);
    for (int k = 0; k < n; ++k) {
      const int at = A.tree().iperm()[t.perm()[first + k]] - A.first_point();
      if (at < 0 || at >= n) throw std::logic_error("PC hss: a point of its compression is another rank's in the matrix");
      hss->from_matrix[(std::size_t)k] = at;
    }
  });
  Factor_Private(hss, p, *hss->dsys, p.comm.get());
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
  hss->dsys.reset();
  hss->failure.clear();
  if (p->distributed()) {
    guard.Run([&] {
      /* every step is collective: a fault here must be agreed on first */
      hssbem::collectively(*p->comm, [] { hssbem::fault_point("PCSetUp"); });
      FactorDistributed(hss, *p);
    });
    hssbem::fault_end("PCSetUp");
    PetscCall(guard.Check(comm, "PC hss set-up"));
    breakdown = !hss->failure.empty();
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &breakdown, 1, MPI_INT, MPI_MAX, comm));
  } else {
    guard.Run("PCSetUp", [&] {
      hss->ex = std::make_unique<HssbemRootExchange>(p->system_of_dof);
      if (rank == 0) FactorOnRoot(hss, *p); /* on a dense matrix on several ranks, the compression lives on rank 0 */
    });
    hssbem::fault_end("PCSetUp");
    PetscCall(guard.Check(comm, "PC hss set-up"));
    breakdown = rank == 0 && !hss->failure.empty();
    PetscCallMPI(MPI_Bcast(&breakdown, 1, MPI_INT, 0, comm));
  }
  if (breakdown) {
    PetscCall(PetscInfo(pc, "HSS factorization broke down: %s\n", !hss->failure.empty() ? hss->failure.c_str() : "on another rank"));
    PetscCall(PCSetFailedReason(pc, PC_FACTOR_NUMERIC_ZEROPIVOT));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* y = A⁻¹ x by the distributed factors, x and y in the matrix's rows on this rank (collective). */
PetscErrorCode ApplyDistributed_Private(PC pc, const HssbemSystemContext &p, Vec x, Vec y)
{
  PC_HSS            *hss = (PC_HSS *)pc->data;
  HssbemGuard        guard;
  const PetscScalar *xa;
  PetscScalar       *ya;

  PetscFunctionBegin;
  PetscCall(VecGetArrayRead(x, &xa));
  PetscCall(VecGetArrayWrite(y, &ya));
  guard.Run([&] {
    hssbem::collectively(*p.comm, [] { hssbem::fault_point("PCApply"); }); /* the ranks meet in the solve's exchanges */
    const std::vector<int> &from = hss->from_matrix;
    const std::size_t       n    = 3 * (std::size_t)hss->dsys->num_points();
    std::vector<double>     b(n);
    for (std::size_t i = 0; i < n; ++i) b[i] = from.empty() ? xa[i] : xa[3 * (std::size_t)from[i / 3] + i % 3];
    hss->factors->solve(b.data());
    for (std::size_t i = 0; i < n; ++i) (from.empty() ? ya[i] : ya[3 * (std::size_t)from[i / 3] + i % 3]) = b[i];
  });
  PetscCall(VecRestoreArrayRead(x, &xa));
  PetscCall(VecRestoreArrayWrite(y, &ya));
  PetscCall(guard.Check(PetscObjectComm((PetscObject)pc), "PC hss"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCApply_HSS(PC pc, Vec x, Vec y)
{
  PC_HSS              *hss = (PC_HSS *)pc->data;
  HssbemSystemContext *p;
  HssbemGuard          guard;
  const PetscScalar   *xa;
  PetscScalar         *ya;
  PCFailedReason       reason;

  PetscFunctionBegin;
  PetscCall(PCGetFailedReason(pc, &reason));
  if (reason) { /* a failed factorization: tell the Krylov method, do not crash */
    PetscCall(VecSetInf(y));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PetscCall(HssbemMatGetSystemContext(pc->pmat, &p));
  if (hss->dsys) {
    PetscCall(ApplyDistributed_Private(pc, *p, x, y));
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
  hss->dsys.reset();
  hss->from_matrix.clear();
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

/* The distributed factorization's figures (collective): memory per rank and the top, rank 0's. */
PetscErrorCode ViewDistributed_Private(PC pc, PetscViewer viewer)
{
  PC_HSS                  *hss = (PC_HSS *)pc->data;
  const hssbem::RankComm  &comm = hss->dsys->comm();
  const hssbem::HssStats  &st   = hss->dsys->matrix().stats();
  const double             mine[2] = {(double)hss->dsys->memory_bytes(), hss->factors ? (double)hss->factors->memory_bytes() : 0.0};
  double                   all[2] = {mine[0], mine[1]}, most[2];

  PetscFunctionBegin;
  PetscCallCXX(comm.sum(all, 2));
  PetscCallCXX(most[0] = comm.max(mine[0]));
  PetscCallCXX(most[1] = comm.max(mine[1]));
  PetscCall(PetscViewerASCIIPrintf(viewer, "  distributed over %d ranks: compression %.1f MB in all, %.1f MB on the largest rank; factors %.1f MB in all, %.1f MB on the largest rank\n", comm.size(),
                                   all[0] / 1048576.0, most[0] / 1048576.0, all[1] / 1048576.0, most[1] / 1048576.0));
  if (hss->factors)
    PetscCall(PetscViewerASCIIPrintf(viewer, "  top (rank 0): %d clusters above the parts, %.2f MB of generators; factored from the parts' roots' skeletons into a root block of %d unknowns, %.2f MB of factors\n",
                                     st.top_clusters, st.top_bytes / 1048576.0, hss->factors->root_size(), hss->factors->top_bytes() / 1048576.0));
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
  if (hss->sys || hss->dsys) {
    PetscCall(PetscViewerASCIIPrintf(viewer, "  compression at %g (leaf size %d): %s, %.2f s; factorization %.2f s\n", hss->used.rel_tol, hss->used.leaf_size, SourceName(hss->source), hss->seconds_compress,
                                     hss->seconds_factor));
    if (hss->dsys) PetscCall(ViewDistributed_Private(pc, viewer));
    PetscCall(PetscViewerASCIIPushTab(viewer));
    PetscCall(PetscViewerASCIIPushTab(viewer));
    PetscCall(HssbemViewHssMatrix_Private(viewer, hss->sys ? hss->sys->matrix() : hss->dsys->matrix()));
    if (hss->factors)
      PetscCall(PetscViewerASCIIPrintf(viewer, "factors%s: %.1f MB, largest dense front %d\n", hss->dsys ? " on rank 0" : "", hss->factors->memory_bytes() / 1048576.0, hss->factors->max_front()));
    else PetscCall(PetscViewerASCIIPrintf(viewer, "factorization failed: %s\n", hss->failure.empty() ? "on another rank" : hss->failure.c_str()));
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
  preconditioner for GMRES around the H² product). A breakdown sets PC_FACTOR_NUMERIC_ZEROPIVOT,
  on every rank whichever rank it happened on.
  On a distributed matrix (HSS, or H² on several ranks) the compression (truncation, or a new one
  on the matrix's METIS partition) and the ULV factorization are distributed: each rank factors
  its part's subtree, rank 0 the top from the parts' roots' reduced blocks, and each application
  sends the parts' reduced right-hand sides to rank 0 and the unknowns back. On a dense matrix on
  several ranks everything lives on rank 0, which gathers each vector.

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
