/* PC "hss": ULV factorization of the BEM system matrix from an HSS compression, as a direct
   solver (-ksp_type preonly) or a preconditioner at a loose tolerance (see pc_hss.h). */
#include "hssbem/petsc/pc_hss.h"
#include "hssbem/petsc/options.h"
#include "hssbem/petsc/system.h"
#include "hssbem/core/timer.hpp"
#include "hssbem/hss/truncate.hpp"
#include "hssbem/hss/ulv.hpp"

#include "mat_compressed.hpp"
#include "pc_compressed.hpp"

#include <petsc/private/pcimpl.h>

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

struct PC_HSS : PC_Compressed {
  PetscReal rel_tol   = hssbem::option_default::pc_hss_rel_tol;   /* <= 0: the matrix's tolerance (see CompressionOptions_Private) */
  PetscInt  leaf_size = hssbem::option_default::pc_hss_leaf_size; /* <= 0: the matrix's leaf size */
  PetscInt  max_rank  = hssbem::option_default::pc_hss_max_rank;  /* -1: the matrix's cap (none on a dense matrix) */
  /* set up: the compression (every rank its part) and its factors */
  Source                                              source = Source::None;
  hssbem::HssOptions                                  used;
  std::shared_ptr<const hssbem::HssDistributedSystem> dsys;
  std::unique_ptr<hssbem::UlvFactorization>           factors;

  PC_HSS() : PC_Compressed("PC hss") {}
  const hssbem::DistributedBemSystem &Factor(const HssbemSystemContext &p, const HssbemLayout &L) override;
  void Solve(const double *b, double *out) const override
  {
    std::copy(b, b + 3 * (std::size_t)dsys->num_points(), out);
    factors->solve(out);
  }
  void Drop() override
  {
    factors.reset();
    dsys.reset();
    source = Source::None;
  }
};

/* The compression the PC factors: the matrix's options, then the PC's. */
hssbem::HssOptions CompressionOptions_Private(const PC_HSS *hss, const HssbemSystemContext &p)
{
  const bool         on_hss = p.type == hssbem::OperatorType::Hss;
  hssbem::HssOptions o      = on_hss ? p.hss_options : hssbem::HssOptions{};
  /* on a dense matrix -mat_hss_rel_tol's default; on H², a preconditioner for GMRES around the accurate product (docs/hss.md) */
  if (p.type == hssbem::OperatorType::H2) o.rel_tol = hssbem::option_default::pc_hss_rel_tol_on_h2;
  o.pressure_columns = false; /* the factorization needs H and G only */
  if (hss->rel_tol > 0) o.rel_tol = hss->rel_tol;
  if (hss->leaf_size > 0) o.leaf_size = (int)hss->leaf_size;
  if (hss->max_rank > 0) o.max_rank = (int)hss->max_rank; /* else the matrix's cap (none on a dense matrix) */
  return o;
}

/* Where the PC's compression comes from: the matrix's own HSS compression when it will do, or
   its truncation (a looser tolerance or a tighter cap, the same tree), else a compression anew. */
Source ChooseSource_Private(const hssbem::HssOptions &o, const HssbemSystemContext &p)
{
  const bool same_tree = p.hss && o.leaf_size == p.hss_options.leaf_size;
  if (same_tree && o.rel_tol == p.hss_options.rel_tol && o.max_rank == p.hss_options.max_rank) return Source::Matrix;
  if (same_tree && o.rel_tol >= p.hss_options.rel_tol && (p.hss_options.max_rank < 0 || (o.max_rank > 0 && o.max_rank <= p.hss_options.max_rank))) return Source::Truncated;
  return Source::Compressed;
}

/* The set-up's work (collective): the compression on the layout (the matrix's own, truncated
   from it, or anew on the layout's partition), then its factors; a breakdown in `failure` on
   every rank. */
const hssbem::DistributedBemSystem &PC_HSS::Factor(const HssbemSystemContext &p, const HssbemLayout &L)
{
  const hssbem::RankComm &comm = *L.comm;
  const hssbem::HssOptions o   = CompressionOptions_Private(this, p);
  factors.reset();
  used = o;
  hssbem::Timer timer;
  source = ChooseSource_Private(o, p);
  if (source == Source::Matrix) dsys = p.hss;
  else if (source == Source::Truncated) dsys = hssbem::make_shared_collectively<hssbem::HssDistributedSystem>(comm, *p.op, hssbem::truncate_hss(p.hss->matrix(), o.rel_tol, o.max_rank, comm), comm);
  else dsys = hssbem::make_shared_collectively<hssbem::HssDistributedSystem>(comm, *p.op, o, L.node_part, comm);
  seconds_compress = timer.seconds();
  timer.restart();
  try {
    factors = dsys->factor(p.sel, p.modes.empty() ? nullptr : &p.modes);
  } catch (const hssbem::HssBreakdown &e) { /* thrown on every rank */
    failure = e.what();
  }
  seconds_factor = timer.seconds();
  return *dsys;
}

PetscErrorCode PCSetFromOptions_HSS(PC pc, PetscOptionItems *PetscOptionsObject)
{
  PC_HSS   *hss = PCCompressedData<PC_HSS>(pc);
  PetscReal tol = hss->rel_tol;
  PetscInt  leaf = hss->leaf_size, rank = hss->max_rank;

  PetscFunctionBegin;
  PetscOptionsHeadBegin(PetscOptionsObject, "HSS factorization options");
  PetscCall(HssbemOptionsRealItem(PetscOptionsObject, "pc_hss_rel_tol", "PCHSSSetRelTol", &tol));
  PetscCall(HssbemOptionsIntItem(PetscOptionsObject, "pc_hss_leaf_size", "PCHSSSetLeafSize", &leaf));
  PetscCall(HssbemOptionsIntItem(PetscOptionsObject, "pc_hss_max_rank", "PCHSSSetMaxRank", &rank));
  PetscOptionsHeadEnd();
  PetscCall(PCHSSSetRelTol(pc, tol)); /* the setters check the values */
  PetscCall(PCHSSSetLeafSize(pc, leaf));
  PetscCall(PCHSSSetMaxRank(pc, rank));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The distributed factorization's figures (collective): memory per rank and the top, rank 0's. */
PetscErrorCode ViewDistributed_Private(PC pc, PetscViewer viewer)
{
  PC_HSS                 *hss     = PCCompressedData<PC_HSS>(pc);
  const hssbem::RankComm &comm    = hss->dsys->comm();
  const hssbem::HssStats &st      = hss->dsys->matrix().stats();
  const double            mine[2] = {(double)hss->dsys->memory_bytes(), hss->factors ? (double)hss->factors->memory_bytes() : 0.0};
  double                  all[2]  = {mine[0], mine[1]}, most[2];

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
  PC_HSS   *hss = PCCompressedData<PC_HSS>(pc);
  PetscBool ascii;
  char      tol[32], leaf[32], cap[32];

  PetscFunctionBegin;
  PetscCall(PetscObjectTypeCompare((PetscObject)viewer, PETSCVIEWERASCII, &ascii));
  if (!ascii) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscSNPrintf(tol, sizeof(tol), hss->rel_tol > 0 ? "%g" : "the matrix's", (double)hss->rel_tol));
  PetscCall(PetscSNPrintf(leaf, sizeof(leaf), hss->leaf_size > 0 ? "%d" : "the matrix's", (int)hss->leaf_size));
  PetscCall(PetscSNPrintf(cap, sizeof(cap), hss->max_rank > 0 ? "%d" : "the matrix's", (int)hss->max_rank));
  PetscCall(PetscViewerASCIIPrintf(viewer, "  HSS ULV factorization: relative tolerance %s, leaf size %s, rank cap %s\n", tol, leaf, cap));
  if (!hss->dsys) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscViewerASCIIPrintf(viewer, "  compression at %g (leaf size %d): %s, %.2f s; factorization %.2f s\n", hss->used.rel_tol, hss->used.leaf_size, SourceName(hss->source), hss->seconds_compress,
                                   hss->seconds_factor));
  PetscCall(ViewDistributed_Private(pc, viewer));
  PetscCall(PetscViewerASCIIPushTab(viewer));
  PetscCall(PetscViewerASCIIPushTab(viewer));
  PetscCall(HssbemViewHssMatrix_Private(viewer, hss->dsys->matrix()));
  if (hss->factors) PetscCall(PetscViewerASCIIPrintf(viewer, "factors on rank 0: %.1f MB, largest dense front %d\n", hss->factors->memory_bytes() / 1048576.0, hss->factors->max_front()));
  else PetscCall(PCCompressedViewFailure(viewer, *hss));
  PetscCall(PetscViewerASCIIPopTab(viewer));
  PetscCall(PetscViewerASCIIPopTab(viewer));
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
  preconditioner for GMRES around the H² product). The compression and the ULV factorization
  are distributed like the matrix, one rank being one part: each rank factors its part's
  subtree, rank 0 the top from the parts' roots' reduced blocks, and each application sends the
  parts' reduced right-hand sides to rank 0 and the unknowns back. On a dense matrix the PC
  partitions the surface for itself and scatters its vectors to and from the matrix's rows. A
  breakdown on any rank sets PC_FACTOR_NUMERIC_ZEROPIVOT on every rank.

  Level: beginner
M*/
PETSC_EXTERN PetscErrorCode PCCreate_HSS(PC pc)
{
  PC_HSS *hss;

  PetscFunctionBegin;
  PetscCallCXX(hss = new PC_HSS);
  PetscCall(PCCompressedCreate(pc, hss, PCSetFromOptions_HSS, PCView_HSS));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@
  PCHSSSetRelTol - Sets the tolerance of the compression that PCHSS factors, in [0, 1) (0: the
  matrix's).

  Logically Collective

  Level: intermediate
@*/
PetscErrorCode PCHSSSetRelTol(PC pc, PetscReal tol)
{
  PetscFunctionBegin;
  PetscCall(HssbemOptionCheck(PetscObjectComm((PetscObject)pc), "pc_hss_rel_tol", (double)tol));
  PetscCall(PCCompressedSet<PC_HSS>(pc, PCHSS, [&](PC_HSS &h) { h.rel_tol = tol; }));
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
  PetscCall(HssbemOptionCheck(PetscObjectComm((PetscObject)pc), "pc_hss_leaf_size", (double)n));
  PetscCall(PCCompressedSet<PC_HSS>(pc, PCHSS, [&](PC_HSS &h) { h.leaf_size = n; }));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@
  PCHSSSetMaxRank - Caps the skeletons of the compression that PCHSS factors (-1: the matrix's).

  Logically Collective

  Level: intermediate
@*/
PetscErrorCode PCHSSSetMaxRank(PC pc, PetscInt k)
{
  PetscFunctionBegin;
  PetscCall(HssbemOptionCheck(PetscObjectComm((PetscObject)pc), "pc_hss_max_rank", (double)k));
  PetscCall(PCCompressedSet<PC_HSS>(pc, PCHSS, [&](PC_HSS &h) { h.max_rank = k; }));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemPCHSSGetOptionValues - The option values a PC hss holds (-pc_hss_*), as the table names
  them; nothing when pc is not a PC hss.

  Not Collective

  Level: developer
@*/
PetscErrorCode HssbemPCHSSGetOptionValues(PC pc, hssbem::OptionValues *values)
{
  PetscBool match;

  PetscFunctionBegin;
  PetscCall(PetscObjectTypeCompare((PetscObject)pc, PCHSS, &match));
  if (!match) PetscFunctionReturn(PETSC_SUCCESS);
  const PC_HSS *hss = PCCompressedData<PC_HSS>(pc);
  PetscCall(HssbemOptionValuePut(values, "pc_hss_rel_tol", (double)hss->rel_tol));
  PetscCall(HssbemOptionValuePut(values, "pc_hss_leaf_size", (double)hss->leaf_size));
  PetscCall(HssbemOptionValuePut(values, "pc_hss_max_rank", (double)hss->max_rank));
  PetscFunctionReturn(PETSC_SUCCESS);
}
