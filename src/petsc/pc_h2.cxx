/* PC "h2": the H² factorization (strong recursive skeletonization) of the BEM system matrix, as
   a preconditioner for GMRES or, at a tight tolerance, a direct solver (see pc_h2.h). */
#include "hssbem/petsc/pc_h2.h"
#include "hssbem/petsc/options.h"
#include "hssbem/petsc/system.h"
#include "hssbem/core/timer.hpp"
#include "hssbem/h2factor/h2_factorization.hpp"

#include "mat_compressed.hpp"
#include "pc_compressed.hpp"

#include <petsc/private/pcimpl.h>

#include <cstdio>
#include <memory>
#include <string>

namespace {

/* Where the factored H² matrix came from. */
enum class Source { None, Matrix, Compressed };

struct PC_H2 : PC_Compressed {
  hssbem::H2FactorOptions options;                                                     /* their defaults are the options' (core/option_table.def) */
  PetscInt                estimate_error = hssbem::option_default::pc_h2_estimate_error; /* power iterations of the ‖I − A F⁻¹‖ estimate (0: none) */
  /* set up */
  Source                                              source         = Source::None;
  double                                              compressed_tol = 0, inverse_error = -1;
  std::shared_ptr<const hssbem::H2DistributedSystem> dsys; /* the matrix factored (every rank its part) */
  std::unique_ptr<hssbem::H2FactorCache>              cache;
  std::unique_ptr<hssbem::H2Factorization>            factors;
  /* HssbemPCH2SetFactorSource(): the next set-up's factorization, loaded (empty: factor) */
  std::function<std::unique_ptr<hssbem::H2Factorization>(const hssbem::H2DistributedSystem &)> factor_source;

  PC_H2() : PC_Compressed("PC h2") {}
  const hssbem::DistributedBemSystem &Factor(const HssbemSystemContext &p, const HssbemLayout &L) override;
  void Solve(const double *b, double *out) const override { factors->solve(b, out); }
  void Drop() override
  {
    factors.reset();
    cache.reset();
    dsys.reset();
    source = Source::None;
  }
};

/* The H² matrix to factor (collective): the matrix's own when it is H² at a tolerance no tighter
   than the PC's (no kernel entry evaluated), else one compressed at the PC's tolerance on the
   layout, kept while the matrix and the tolerance stay. */
void ChooseMatrix_Private(PC_H2 *h2, const HssbemSystemContext &p, const HssbemLayout &L)
{
  if (p.h2 && h2->options.rel_tol >= p.h2_options.rel_tol) {
    if (h2->dsys != p.h2) h2->cache.reset();
    h2->dsys           = p.h2;
    h2->source         = Source::Matrix;
    h2->compressed_tol = p.h2_options.rel_tol;
    return;
  }
  if (!h2->fresh && h2->dsys && h2->source == Source::Compressed && h2->compressed_tol == h2->options.rel_tol) return;
  h2->cache.reset();
  hssbem::H2Options o = p.type == hssbem::OperatorType::H2 ? p.h2_options : hssbem::H2Options{};
  if (p.type != hssbem::OperatorType::H2) o.single_precision = false; /* its own tolerance may be a direct solve's (1e-7): single-precision blocks round at 6e-8 */
  o.rel_tol           = h2->options.rel_tol;
  o.pressure_columns  = false; /* the factorization needs H and G only */
  hssbem::Timer timer;
  h2->dsys             = hssbem::make_shared_collectively<hssbem::H2DistributedSystem>(*L.comm, *p.op, o, L.node_part, *L.comm);
  h2->seconds_compress = timer.seconds();
  h2->source           = Source::Compressed;
  h2->compressed_tol   = o.rel_tol;
}

/* The set-up's work (collective): the matrix, its factors (a breakdown in `failure` on every
   rank), the optional error estimate against the matrix factored. */
const hssbem::DistributedBemSystem &PC_H2::Factor(const HssbemSystemContext &p, const HssbemLayout &L)
{
  factors.reset();
  inverse_error = -1;
  ChooseMatrix_Private(this, p, L);
  hssbem::Timer timer;
  if (factor_source) { /* a saved factorization of the matrix's compression, loaded */
    const auto load = std::move(factor_source);
    factor_source   = nullptr;
    hssbem::collectively(*L.comm, [&] {
      if (source != Source::Matrix) throw std::invalid_argument("a saved PC h2 factorization is of the matrix's own H2 compression; this PC compresses its own (-pc_h2_rel_tol below -mat_h2_rel_tol)");
    });
    factors        = load(*dsys);
    seconds_factor = timer.seconds();
    return *dsys;
  }
  hssbem::collectively(*L.comm, [&] {
    if (!cache) cache = std::make_unique<hssbem::H2FactorCache>(dsys->product());
  });
  try {
    factors = hssbem::make_unique_collectively<hssbem::H2Factorization>(*L.comm, *cache, p.sel, options, p.modes.empty() ? nullptr : &p.modes);
  } catch (const hssbem::H2Breakdown &e) { /* thrown on every rank */
    failure = e.what();
    return *dsys;
  }
  seconds_factor = timer.seconds();
  if (estimate_error > 0) {
    const hssbem::DistributedBemSystem &A = *dsys;
    inverse_error = hssbem::estimate_inverse_error(
      *factors,
      [&](const double *x, double *y) {
        A.apply(p.sel, x, y);
        if (!p.modes.empty()) HssbemAddRegularization(A, *L.comm, p.modes, x, y);
      },
      (int)estimate_error);
  }
  return *dsys;
}

PetscErrorCode PCSetFromOptions_H2(PC pc, PetscOptionItems *PetscOptionsObject)
{
  PC_H2    *h2 = PCCompressedData<PC_H2>(pc);
  PetscReal tol = h2->options.rel_tol;
  PetscInt  leaf = h2->options.leaf_size, top = h2->options.top_size, single = h2->options.single_top_from, sketch = h2->options.sketch_columns, iterations = h2->estimate_error;
  PetscBool cheaper = h2->options.top_when_cheaper ? PETSC_TRUE : PETSC_FALSE, spread = h2->options.spread_top ? PETSC_TRUE : PETSC_FALSE;

  PetscFunctionBegin;
  PetscOptionsHeadBegin(PetscOptionsObject, "H2 factorization options");
  PetscCall(PetscOptionsDeprecated("-pc_h2_mixed_top", "-pc_h2_single_top_from", "hssbem 2026-11", NULL));
  PetscCall(HssbemOptionsRealItem(PetscOptionsObject, "pc_h2_rel_tol", "PCH2SetRelTol", &tol));
  PetscCall(HssbemOptionsIntItem(PetscOptionsObject, "pc_h2_leaf_size", "PCH2SetLeafSize", &leaf));
  PetscCall(HssbemOptionsIntItem(PetscOptionsObject, "pc_h2_top_size", "PCH2SetTopSize", &top));
  PetscCall(HssbemOptionsBoolItem(PetscOptionsObject, "pc_h2_top_when_cheaper", "PCH2SetTopWhenCheaper", &cheaper));
  PetscCall(HssbemOptionsIntItem(PetscOptionsObject, "pc_h2_single_top_from", "PCH2SetSingleTopFrom", &single));
  PetscCall(HssbemOptionsBoolItem(PetscOptionsObject, "pc_h2_spread_top", "PCH2SetSpreadTop", &spread));
  PetscCall(HssbemOptionsIntItem(PetscOptionsObject, "pc_h2_sketch_size", "PCH2SetSketchSize", &sketch));
  PetscCall(HssbemOptionsIntItem(PetscOptionsObject, "pc_h2_estimate_error", "PCH2SetEstimateError", &iterations));
  PetscOptionsHeadEnd();
  PetscCall(PCH2SetRelTol(pc, tol)); /* the setters check the values */
  PetscCall(PCH2SetLeafSize(pc, leaf));
  PetscCall(PCH2SetTopSize(pc, top));
  PetscCall(PCH2SetTopWhenCheaper(pc, cheaper));
  PetscCall(PCH2SetSingleTopFrom(pc, single));
  PetscCall(PCH2SetSpreadTop(pc, spread));
  PetscCall(PCH2SetSketchSize(pc, sketch));
  PetscCall(PCH2SetEstimateError(pc, iterations));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* How the top's LU runs, in parentheses; empty for the double LU. */
std::string TopLU_Private(const hssbem::H2Factorization &F)
{
  char trial[96];
  if (F.stats().top_mixed) return " (LU in single precision, solves refined in double)";
  if (!F.stats().top_single) return "";
  std::snprintf(trial, sizeof trial, " (LU in single precision like the panels, a trial solve off by %.1e)", F.top_trial());
  return trial;
}

/* The factorization: the top (on rank 0, or spread), then each rank's part (collective). */
PetscErrorCode ViewFactorization_Private(PetscViewer viewer, const hssbem::H2Factorization &F)
{
  const hssbem::H2FactorStats &st = F.stats();
  PetscMPIInt                  rank;
  std::size_t                  cross = 0;
  long long                    eliminated = 0;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(PetscObjectComm((PetscObject)viewer), &rank));
  if (st.parts > 1) PetscCall(PetscViewerASCIIPrintf(viewer, "each rank factors its part's subtree (%d parts, cross blocks between them), %s\n", st.parts, st.top_spread > 0 ? "all ranks the top" : "rank 0 the top"));
  if (st.top_spread > 0) PetscCall(PetscViewerASCIIPrintf(viewer, "top spread over %d ranks (ScaLAPACK): ", st.top_spread));
  else PetscCall(PetscViewerASCIIPrintf(viewer, "top on rank 0: "));
  PetscCall(PetscViewerASCIIUseTabs(viewer, PETSC_FALSE));
  PetscCall(PetscViewerASCIIPrintf(viewer, "%d unknowns of %d boxes, %.1f MB%s%s, %.2f s; sketch of %d vectors\n", st.top_size, st.top_boxes, st.top_bytes / 1048576.0, st.top_spread > 0 ? " on rank 0" : "",
                                   TopLU_Private(F).c_str(), st.time_top, st.sketch_columns));
  PetscCall(PetscViewerASCIIUseTabs(viewer, PETSC_TRUE));
  for (const hssbem::H2FactorLevelStats &l : st.levels) {
    cross = std::max(cross, l.cross_bytes);
    eliminated += l.eliminated;
  }
  PetscCall(PetscViewerASCIIPushSynchronized(viewer));
  PetscCall(PetscViewerASCIISynchronizedPrintf(viewer, "    rank %d: %lld unknowns eliminated, factors %.1f MB (%s panels), cross blocks at most %.1f MB, working blocks peaked at %.1f MB; %.2f s (sketch %.2f, first boxes %.2f, skeletons %.2f, eliminations %.2f, merges %.2f; thread-seconds for skeletons and eliminations)\n",
                                               (int)rank, eliminated, st.bytes / 1048576.0, st.single_panels ? "single-precision" : "double-precision", cross / 1048576.0, st.workspace_bytes / 1048576.0,
                                               st.seconds(), st.time_sketch, st.time_init, st.time_skeleton, st.time_eliminate, st.time_merge));
  for (const hssbem::H2FactorLevelStats &l : st.levels)
    PetscCall(PetscViewerASCIISynchronizedPrintf(viewer, "      level %d: %d boxes, %.0f unknowns per box (max %d) -> skeleton %.0f (max %d), %lld eliminated, %lld cross blocks (%.1f MB), %.1f MB, %.2f s\n", l.level, l.boxes,
                                                 l.mean_candidates, l.max_candidates, l.mean_rank, l.max_rank, l.eliminated, l.cross_blocks, l.cross_bytes / 1048576.0, l.bytes / 1048576.0, l.seconds));
  PetscCall(PetscViewerFlush(viewer));
  PetscCall(PetscViewerASCIIPopSynchronized(viewer));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCView_H2(PC pc, PetscViewer viewer)
{
  PC_H2    *h2 = PCCompressedData<PC_H2>(pc);
  PetscBool ascii;

  PetscFunctionBegin;
  PetscCall(PetscObjectTypeCompare((PetscObject)viewer, PETSCVIEWERASCII, &ascii));
  if (!ascii) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscViewerASCIIPrintf(viewer, "  H2 factorization (strong recursive skeletonization): relative tolerance %g, leaf size %s, top %d\n", (double)h2->options.rel_tol,
                                   h2->options.leaf_size > 0 ? std::to_string(h2->options.leaf_size).c_str() : "the matrix's", h2->options.top_size));
  if (!h2->dsys) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscViewerASCIIPushTab(viewer));
  PetscCall(PetscViewerASCIIPushTab(viewer));
  if (h2->source == Source::Matrix) PetscCall(PetscViewerASCIIPrintf(viewer, "of the matrix's H2 compression (at %g; no kernel entry evaluated)\n", h2->compressed_tol));
  else {
    PetscCall(PetscViewerASCIIPrintf(viewer, "of an H2 compression made at %g on the %s partition, %.2f s; its part on rank 0:\n", h2->compressed_tol, h2->own_layout ? "PC's own" : "matrix's",
                                     h2->seconds_compress));
    PetscCall(HssbemViewH2Matrix_Private(viewer, h2->dsys->matrix()));
  }
  if (h2->factors) PetscCall(ViewFactorization_Private(viewer, *h2->factors));
  else PetscCall(PCCompressedViewFailure(viewer, *h2));
  if (h2->factors && h2->inverse_error >= 0) PetscCall(PetscViewerASCIIPrintf(viewer, "||I - A F^-1|| estimated at %.3e (%d power iterations)\n", h2->inverse_error, (int)h2->estimate_error));
  PetscCall(PetscViewerASCIIPopTab(viewer));
  PetscCall(PetscViewerASCIIPopTab(viewer));
  PetscFunctionReturn(PETSC_SUCCESS);
}

} // namespace

/*MC
  PCH2 - H² factorization of the BEM system matrix by strong recursive skeletonization (hssbem).

  Options Database Keys:
+ -pc_h2_rel_tol <tol>         - relative tolerance of each skeleton (the default: a preconditioner)
. -pc_h2_leaf_size <n>         - dof nodes per box at the first level factored (0: the H² leaves; below 1e-5 their parents)
. -pc_h2_top_size <n>          - unknowns factored densely at the top
. -pc_h2_top_when_cheaper <b>  - also stop at a level whose eliminations would cost more flops than the dense top
. -pc_h2_single_top_from <n>   - from this top size on, the top's LU in single precision: with single-precision panels (tolerance 1e-5 or looser) alone, else refined in double by every solve (0: never; -pc_h2_mixed_top is its former name)
. -pc_h2_spread_top <b>        - on several ranks, spread a single-precision top's LU over the ranks, ScaLAPACK (false: on rank 0)
. -pc_h2_sketch_size <p>       - random vectors of the far-field sketch (0: from the tolerance, 48 to 320; at most 4096)
- -pc_h2_estimate_error <k>    - power iterations of the ||I - A F^-1|| estimate in -ksp_view (0: none; at most 1000)

  The defaults and ranges are those of hssbem's table of options (core/option_table.def;
  hssbem -help lists them).

  Notes:
  The factorization is distributed like the matrix, one rank being one part: each rank factors
  its part's subtree, and the top is factored on rank 0 or, in single precision, spread over the
  ranks; a solve sends only the top's unknowns between the ranks. On the H² MatShell it reads the
  matrix's own compression (no kernel entry evaluated); at a tolerance tighter than the matrix's,
  or on the HSS matrix, it compresses an H² matrix at its own tolerance on the matrix's partition
  first, and on a dense matrix on a partition of its own (its vectors scattered to and from the
  dense matrix's rows). With GMRES at the default tolerance it is a preconditioner; with
  -ksp_type preonly -pc_h2_rel_tol 1e-7 a direct solver to about that tolerance. A pivot block
  singular to working precision on any rank sets PC_FACTOR_NUMERIC_ZEROPIVOT on every rank.

  Level: beginner
M*/
PETSC_EXTERN PetscErrorCode PCCreate_H2(PC pc)
{
  PC_H2 *h2;

  PetscFunctionBegin;
  PetscCallCXX(h2 = new PC_H2);
  PetscCall(PCCompressedCreate(pc, h2, PCSetFromOptions_H2, PCView_H2));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The setters check the value on every PC, then store it on a PC h2 (on another type: nothing). */
#define PCH2_SET(field, value) PetscCall(PCCompressedSet<PC_H2>(pc, PCH2, [&](PC_H2 &h2) { h2.field = value; }))

/*@
  PCH2SetRelTol - Sets the relative tolerance of the H² factorization (of each skeleton), in (0, 1).

  Logically Collective

  Level: intermediate
@*/
PetscErrorCode PCH2SetRelTol(PC pc, PetscReal tol)
{
  PetscFunctionBegin;
  PetscCall(HssbemOptionCheck(PetscObjectComm((PetscObject)pc), "pc_h2_rel_tol", (double)tol));
  PCH2_SET(options.rel_tol, tol);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@
  PCH2SetLeafSize - Sets the dof nodes per box at the first level factored (0: the H² leaves, or
  their parents below tolerance 1e-5).

  Logically Collective

  Level: intermediate
@*/
PetscErrorCode PCH2SetLeafSize(PC pc, PetscInt n)
{
  PetscFunctionBegin;
  PetscCall(HssbemOptionCheck(PetscObjectComm((PetscObject)pc), "pc_h2_leaf_size", (double)n));
  PCH2_SET(options.leaf_size, (int)n);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@
  PCH2SetTopSize - Sets how many unknowns may remain for the dense top factorization (>= 0).

  Logically Collective

  Level: advanced
@*/
PetscErrorCode PCH2SetTopSize(PC pc, PetscInt n)
{
  PetscFunctionBegin;
  PetscCall(HssbemOptionCheck(PetscObjectComm((PetscObject)pc), "pc_h2_top_size", (double)n));
  PCH2_SET(options.top_size, (int)n);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@
  PCH2SetTopWhenCheaper - Sets whether the factorization stops at a level whose eliminations would
  cost more flops than factoring every unknown left densely (PETSC_FALSE: go on while a level has
  a far field and more than the top size of unknowns remain).

  Logically Collective

  Level: advanced
@*/
PetscErrorCode PCH2SetTopWhenCheaper(PC pc, PetscBool flg)
{
  PetscFunctionBegin;
  PCH2_SET(options.top_when_cheaper, flg == PETSC_TRUE);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@
  PCH2SetSingleTopFrom - Sets the top size from which the dense top's LU runs in single precision:
  alone with single-precision panels (a tolerance of 1e-5 or looser), else refined in double by
  every solve (as accurate as a double LU). 0 or less: always in double.

  Logically Collective

  Level: advanced
@*/
PetscErrorCode PCH2SetSingleTopFrom(PC pc, PetscInt n)
{
  PetscFunctionBegin;
  PCH2_SET(options.single_top_from, (int)n);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@
  PCH2SetSpreadTop - Sets whether, on several ranks, a single-precision top's LU is spread over
  the ranks (ScaLAPACK on a 1 x P grid, blocks of 128 columns; the default) or factored on rank 0.

  Logically Collective

  Level: advanced
@*/
PetscErrorCode PCH2SetSpreadTop(PC pc, PetscBool flg)
{
  PetscFunctionBegin;
  PCH2_SET(options.spread_top, flg == PETSC_TRUE);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@
  PCH2SetSketchSize - Sets the random vectors of the far-field sketch (0: from the tolerance; at
  most 4096).

  Logically Collective

  Level: advanced
@*/
PetscErrorCode PCH2SetSketchSize(PC pc, PetscInt n)
{
  PetscFunctionBegin;
  PetscCall(HssbemOptionCheck(PetscObjectComm((PetscObject)pc), "pc_h2_sketch_size", (double)n));
  PCH2_SET(options.sketch_columns, (int)n);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@
  PCH2SetEstimateError - Sets the power iterations of the ||I - A F^-1|| estimate (0: none; at
  most 1000).

  Logically Collective

  Level: advanced
@*/
PetscErrorCode PCH2SetEstimateError(PC pc, PetscInt n)
{
  PetscFunctionBegin;
  PetscCall(HssbemOptionCheck(PetscObjectComm((PetscObject)pc), "pc_h2_estimate_error", (double)n));
  PCH2_SET(estimate_error, n);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemPCH2GetOptionValues - The option values a PC h2 holds (-pc_h2_*), as the table names them;
  nothing when pc is not a PC h2.

  Not Collective

  Level: developer
@*/
PetscErrorCode HssbemPCH2GetOptionValues(PC pc, hssbem::OptionValues *values)
{
  PetscBool               is_h2;
  hssbem::H2FactorOptions o;

  PetscFunctionBegin;
  PetscCall(HssbemPCH2GetFactorOptions(pc, &o, &is_h2));
  if (!is_h2) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(HssbemOptionValuePut(values, "pc_h2_rel_tol", o.rel_tol));
  PetscCall(HssbemOptionValuePut(values, "pc_h2_leaf_size", o.leaf_size));
  PetscCall(HssbemOptionValuePut(values, "pc_h2_top_size", o.top_size));
  PetscCall(HssbemOptionValuePut(values, "pc_h2_top_when_cheaper", o.top_when_cheaper));
  PetscCall(HssbemOptionValuePut(values, "pc_h2_single_top_from", o.single_top_from));
  PetscCall(HssbemOptionValuePut(values, "pc_h2_spread_top", o.spread_top));
  PetscCall(HssbemOptionValuePut(values, "pc_h2_sketch_size", o.sketch_columns));
  PetscCall(HssbemOptionValuePut(values, "pc_h2_estimate_error", (double)PCCompressedData<PC_H2>(pc)->estimate_error));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemPCH2GetFactorOptions - The factorization options a PC h2 holds (for the size check); *is_h2
  says whether pc is a PC h2 (else o is left alone).

  Not Collective

  Level: developer
@*/
PetscErrorCode HssbemPCH2GetFactorOptions(PC pc, hssbem::H2FactorOptions *o, PetscBool *is_h2)
{
  PetscFunctionBegin;
  *is_h2 = PETSC_FALSE;
  PetscCall(PCCompressedSet<PC_H2>(pc, PCH2, [&](PC_H2 &h2) {
    *o     = h2.options;
    *is_h2 = PETSC_TRUE;
  }));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemPCH2GetFactorization - The factorization a PC h2 holds after its set-up, and whether it is
  of the matrix's own H² compression (what a saved precomputation keeps); NULL before the set-up,
  after a breakdown, or when pc is not a PC h2.

  Not Collective

  Level: developer
@*/
PetscErrorCode HssbemPCH2GetFactorization(PC pc, const hssbem::H2Factorization **F, PetscBool *of_matrix)
{
  PetscFunctionBegin;
  *F         = nullptr;
  *of_matrix = PETSC_FALSE;
  PetscCall(PCCompressedSet<PC_H2>(pc, PCH2, [&](PC_H2 &h2) {
    *F         = h2.factors.get();
    *of_matrix = h2.factors && h2.source == Source::Matrix ? PETSC_TRUE : PETSC_FALSE;
  }));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemPCH2SetFactorSource - At the next set-up, take the factorization `load` returns for the
  matrix's own H² compression instead of factoring it (a saved precomputation, loaded); once.

  Logically Collective

  Level: developer
@*/
PetscErrorCode HssbemPCH2SetFactorSource(PC pc, std::function<std::unique_ptr<hssbem::H2Factorization>(const hssbem::H2DistributedSystem &)> load)
{
  PetscFunctionBegin;
  PetscCall(PCCompressedSet<PC_H2>(pc, PCH2, [&](PC_H2 &h2) { h2.factor_source = std::move(load); }));
  PetscFunctionReturn(PETSC_SUCCESS);
}
