/* PC "h2": the H² factorization (strong recursive skeletonization) of the BEM system matrix, as
   a preconditioner for GMRES or, at a tight tolerance, a direct solver (see pc_h2.h). */
#include "hssbem/petsc/pc_h2.h"
#include "hssbem/core/fault.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/h2factor/h2_factorization.hpp"

#include "mat_compressed.hpp"

#include <petsc/private/pcimpl.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <random>
#include <string>

namespace {

/* Where the factored H² matrix came from. */
enum class Source { None, Matrix, Compressed };

struct PC_H2 {
  PetscReal rel_tol        = HSSBEM_PC_H2_DEFAULT_REL_TOL;
  PetscInt  leaf_size      = 0;    /* 0: the H² matrix's leaves */
  PetscInt  top_size       = 2000; /* unknowns factored densely at the top */
  PetscBool top_cheaper    = PETSC_TRUE; /* stop at a level that costs more than the dense top */
  PetscInt  mixed_top      = 4000; /* from this top size on, its LU in single precision refined in double (<= 0: never) */
  PetscBool spread_top     = PETSC_TRUE; /* distributed, single-precision top: spread over the ranks (ScaLAPACK) */
  PetscInt  sketch_size    = 0;    /* 0: from the tolerance */
  PetscInt  estimate_error = 0;    /* power iterations of the ‖I − A F⁻¹‖ estimate (0: none) */
  /* set up (rank 0) */
  Source                                       source = Source::None;
  double                                       compressed_tol = 0;
  std::shared_ptr<const hssbem::H2BemSystem>   sys;
  std::shared_ptr<const hssbem::H2DistributedSystem> dsys; /* on the distributed H² matrix: the matrix factored (every rank its part) */
  std::shared_ptr<hssbem::H2FactorCache>       cache;
  std::unique_ptr<hssbem::H2Factorization>     factors;
  std::string                                  failure;
  double                                       seconds_compress = 0, seconds_factor = 0, inverse_error = -1;
  std::unique_ptr<HssbemRootExchange>          ex;
};

hssbem::H2FactorOptions FactorOptions(const PC_H2 &h2)
{
  hssbem::H2FactorOptions o;
  o.rel_tol        = h2.rel_tol;
  o.leaf_size      = (int)h2.leaf_size;
  o.top_size       = (int)h2.top_size;
  o.top_when_cheaper = h2.top_cheaper == PETSC_TRUE;
  o.mixed_top_from = (int)h2.mixed_top;
  o.spread_top     = h2.spread_top == PETSC_TRUE;
  o.sketch_columns = (int)h2.sketch_size;
  return o;
}

/* Rank 0: the H² matrix to factor (the matrix's own, or one compressed at the PC's tolerance). */
void ChooseMatrixOnRoot(PC_H2 *h2, const HssbemSystemContext &p)
{
  const bool on_h2 = p.type == hssbem::OperatorType::H2 && p.h2;
  if (on_h2 && h2->rel_tol >= p.h2_options.rel_tol) {
    h2->sys            = p.h2;
    h2->source         = Source::Matrix;
    h2->compressed_tol = p.h2_options.rel_tol;
    return;
  }
  hssbem::H2Options o = on_h2 ? p.h2_options : hssbem::H2Options{};
  o.rel_tol           = h2->rel_tol;
  o.pressure_columns  = false; /* the factorization needs H and G only */
  hssbem::Timer timer;
  h2->sys              = std::make_shared<hssbem::H2BemSystem>(*p.op, o);
  h2->seconds_compress = timer.seconds();
  h2->source           = Source::Compressed;
  h2->compressed_tol   = o.rel_tol;
}

/* Rank 0: the factors (a breakdown in h2->failure, other errors as exceptions). */
void FactorOnRoot(PC_H2 *h2, const HssbemSystemContext &p)
{
  const hssbem::H2BemSystem *before = h2->sys.get();
  ChooseMatrixOnRoot(h2, p);
  if (!h2->cache || h2->sys.get() != before) h2->cache = std::make_shared<hssbem::H2FactorCache>(h2->sys->matrix());
  hssbem::Timer timer;
  try {
    h2->factors = std::make_unique<hssbem::H2Factorization>(*h2->cache, p.sel, FactorOptions(*h2), p.modes.empty() ? nullptr : &p.modes);
  } catch (const hssbem::H2Breakdown &e) {
    h2->failure = e.what();
    return;
  }
  h2->seconds_factor = timer.seconds();
  if (h2->estimate_error > 0) {
    /* Against the operator the Krylov method applies: the MatShell's compression when there is one. */
    const hssbem::CompressedBemSystem *A = p.compressed() ? p.compressed() : h2->sys.get();
    h2->inverse_error = hssbem::estimate_inverse_error(*h2->factors, [&](const double *x, double *y) {
      A->apply(p.sel, x, y);
      if (!p.modes.empty()) HssbemAddRegularization(p.modes, x, y);
    }, (int)h2->estimate_error);
  }
}

/* ‖I − A F⁻¹‖ estimated by power iterations on the ranks (the distributed estimate_inverse_error). */
double EstimateDistributed_Private(const PC_H2 &h2, const HssbemSystemContext &p)
{
  const hssbem::RankComm &comm = *p.comm;
  const std::size_t       n    = 3 * (std::size_t)h2.dsys->num_points();
  std::mt19937_64         gen(1 + (unsigned)comm.rank());
  std::normal_distribution<double> normal;
  std::vector<double>     v, z, w;
  hssbem::collectively(comm, [&] {
    for (auto *a : {&v, &z, &w}) a->resize(n);
    for (double &x : v) x = normal(gen);
  });
  const auto norm = [&](const std::vector<double> &x) {
    double s = 0;
    for (double e : x) s += e * e;
    comm.sum(&s, 1);
    return std::sqrt(s);
  };
  double worst = 0;
  for (int it = 0; it < (int)h2.estimate_error; ++it) {
    const double nv = norm(v);
    if (!(nv > 0)) break;
    h2.factors->solve_local(v.data(), z.data());
    p.distributed()->apply(p.sel, z.data(), w.data()); /* the MatShell's product */
    for (std::size_t i = 0; i < n; ++i) w[i] = v[i] - w[i];
    const double nw = norm(w);
    worst = std::max(worst, nw / nv);
    for (std::size_t i = 0; i < n; ++i) v[i] = w[i] / nw;
  }
  return worst;
}

/* Every rank (collective), on the distributed H² matrix: its own compression (or one made anew,
   distributed on the matrix's METIS partition, at a tolerance tighter than the matrix's), then
   the distributed factors; a breakdown on any rank in h2->failure on every rank. */
void FactorDistributed(PC_H2 *h2, const HssbemSystemContext &p)
{
  const hssbem::H2DistributedSystem *before = h2->dsys.get();
  if (h2->rel_tol >= p.h2_options.rel_tol) {
    h2->dsys           = p.h2dist;
    h2->source         = Source::Matrix;
    h2->compressed_tol = p.h2_options.rel_tol;
  } else if (!h2->dsys || h2->source != Source::Compressed || h2->compressed_tol != h2->rel_tol) {
    hssbem::H2Options o = p.h2_options;
    o.rel_tol           = h2->rel_tol;
    o.pressure_columns  = false; /* the factorization needs H and G only */
    hssbem::Timer timer;
    h2->dsys             = hssbem::make_shared_collectively<hssbem::H2DistributedSystem>(*p.comm, *p.op, o, p.node_part, *p.comm);
    h2->seconds_compress = timer.seconds();
    h2->source           = Source::Compressed;
    h2->compressed_tol   = o.rel_tol;
    hssbem::collectively(*p.comm, [&] { /* the same tree: this rank's rows are the matrix's */
      if (h2->dsys->first_point() != p.h2dist->first_point() || h2->dsys->num_points() != p.h2dist->num_points() || h2->dsys->tree().perm() != p.h2dist->tree().perm())
        throw std::logic_error("PC h2: its compression's rows on this rank are not the matrix's");
    });
  }
  hssbem::collectively(*p.comm, [&] {
    if (!h2->cache || h2->dsys.get() != before) h2->cache = std::make_shared<hssbem::H2FactorCache>(h2->dsys->product());
  });
  hssbem::Timer timer;
  try {
    h2->factors = hssbem::make_unique_collectively<hssbem::H2Factorization>(*p.comm, *h2->cache, *p.comm, p.sel, FactorOptions(*h2), p.modes.empty() ? nullptr : &p.modes);
  } catch (const hssbem::H2Breakdown &e) { /* thrown on every rank */
    h2->failure = e.what();
    return;
  }
  h2->seconds_factor = timer.seconds();
  if (h2->estimate_error > 0) h2->inverse_error = EstimateDistributed_Private(*h2, p);
}

PetscErrorCode PCSetUp_H2(PC pc)
{
  PC_H2               *h2 = (PC_H2 *)pc->data;
  HssbemSystemContext *p;
  MPI_Comm             comm = PetscObjectComm((PetscObject)pc);
  PetscMPIInt          rank;
  HssbemGuard          guard;
  int                  breakdown = 0;

  PetscFunctionBegin;
  PetscCall(HssbemMatGetSystemContext(pc->pmat, &p));
  PetscCheck(p, comm, PETSC_ERR_ARG_WRONG, "PC h2 factors BEM system matrices only: build the matrix with HssbemCreateSystem() (the hssbem driver does)");
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  h2->factors.reset();
  h2->failure.clear();
  h2->inverse_error = -1;
  if (p->h2dist) { /* distributed: each rank factors its part's subtree, rank 0 the top */
    guard.Run([&] {
      hssbem::collectively(*p->comm, [] { hssbem::fault_point("PCSetUp"); }); /* every step is collective */
      FactorDistributed(h2, *p);
    });
    hssbem::fault_end("PCSetUp");
    PetscCall(guard.Check(comm, "PC h2 set-up"));
    breakdown = !h2->failure.empty();
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &breakdown, 1, MPI_INT, MPI_MAX, comm));
    if (breakdown) {
      PetscCall(PetscInfo(pc, "H2 factorization broke down: %s\n", !h2->failure.empty() ? h2->failure.c_str() : "on another rank"));
      PetscCall(PCSetFailedReason(pc, PC_FACTOR_NUMERIC_ZEROPIVOT));
    }
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  /* A dense or HSS matrix: the factorization runs on rank 0, on an H² compression made there. */
  guard.Run("PCSetUp", [&] {
    h2->ex = std::make_unique<HssbemRootExchange>(p->system_of_dof);
    if (rank == 0) FactorOnRoot(h2, *p); /* the factorization runs on rank 0 */
  });
  hssbem::fault_end("PCSetUp");
  PetscCall(guard.Check(comm, "PC h2 set-up"));
  breakdown = rank == 0 && !h2->failure.empty();
  PetscCallMPI(MPI_Bcast(&breakdown, 1, MPI_INT, 0, comm));
  if (breakdown) {
    PetscCall(PetscInfo(pc, "H2 factorization broke down: %s\n", rank == 0 ? h2->failure.c_str() : "on rank 0"));
    PetscCall(PCSetFailedReason(pc, PC_FACTOR_NUMERIC_ZEROPIVOT));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCApply_H2(PC pc, Vec x, Vec y)
{
  PC_H2             *h2 = (PC_H2 *)pc->data;
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
  if (h2->dsys) { /* distributed: this rank's rows, which are the factorization's (cluster order) */
    PetscCall(VecGetArrayRead(x, &xa));
    PetscCall(VecGetArrayWrite(y, &ya));
    HssbemSystemContext *p;
    PetscCall(HssbemMatGetSystemContext(pc->pmat, &p));
    guard.Run([&] {
      hssbem::collectively(*p->comm, [] { hssbem::fault_point("PCApply"); }); /* the ranks meet in the solve's exchanges */
      h2->factors->solve_local(xa, ya);
    });
    PetscCall(VecRestoreArrayRead(x, &xa));
    PetscCall(VecRestoreArrayWrite(y, &ya));
    PetscCall(guard.Check(PetscObjectComm((PetscObject)pc), "PC h2"));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PetscCall(h2->ex->SetUp(x));
  PetscCall(h2->ex->Gather(x, &xa));
  PetscCall(h2->ex->GetOut(&ya));
  guard.Run("PCApply", [&] {
    if (h2->factors) h2->factors->solve(xa, ya); /* rank 0 holds them */
  });
  PetscCall(h2->ex->RestoreGather(&xa));
  PetscCall(h2->ex->ScatterOut(&ya, y));
  PetscCall(guard.Check(PetscObjectComm((PetscObject)pc), "PC h2"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCReset_H2(PC pc)
{
  PC_H2 *h2 = (PC_H2 *)pc->data;

  PetscFunctionBegin;
  h2->factors.reset();
  h2->cache.reset();
  h2->sys.reset();
  h2->dsys.reset();
  h2->ex.reset();
  h2->source = Source::None;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCDestroy_H2(PC pc)
{
  PetscFunctionBegin;
  PetscCall(PCReset_H2(pc));
  delete (PC_H2 *)pc->data;
  pc->data = NULL;
  PetscCall(PetscObjectComposeFunction((PetscObject)pc, "PCH2SetRelTol_C", NULL));
  PetscCall(PetscObjectComposeFunction((PetscObject)pc, "PCH2SetLeafSize_C", NULL));
  PetscCall(PetscObjectComposeFunction((PetscObject)pc, "PCH2SetTopSize_C", NULL));
  PetscCall(PetscObjectComposeFunction((PetscObject)pc, "PCH2SetTopWhenCheaper_C", NULL));
  PetscCall(PetscObjectComposeFunction((PetscObject)pc, "PCH2SetMixedTop_C", NULL));
  PetscCall(PetscObjectComposeFunction((PetscObject)pc, "PCH2SetSketchSize_C", NULL));
  PetscCall(PetscObjectComposeFunction((PetscObject)pc, "PCH2SetEstimateError_C", NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode CheckOptions_Private(PC pc, const PC_H2 &h2)
{
  MPI_Comm comm = PetscObjectComm((PetscObject)pc);

  PetscFunctionBegin;
  PetscCheck(h2.rel_tol > 0 && h2.rel_tol < 1, comm, PETSC_ERR_ARG_OUTOFRANGE, "-pc_h2_rel_tol must lie in (0, 1)");
  PetscCheck(h2.leaf_size >= 0, comm, PETSC_ERR_ARG_OUTOFRANGE, "-pc_h2_leaf_size must be 0 (the matrix's leaves) or positive");
  PetscCheck(h2.top_size >= 0, comm, PETSC_ERR_ARG_OUTOFRANGE, "-pc_h2_top_size must be >= 0");
  PetscCheck(h2.sketch_size >= 0 && h2.sketch_size <= hssbem::kMaxSketchColumns, comm, PETSC_ERR_ARG_OUTOFRANGE, "-pc_h2_sketch_size must be 0 (from the tolerance: 48 to 320) or at most %d, got %d", hssbem::kMaxSketchColumns,
             (int)h2.sketch_size);
  PetscCheck(h2.estimate_error >= 0 && h2.estimate_error <= 1000, comm, PETSC_ERR_ARG_OUTOFRANGE, "-pc_h2_estimate_error must lie in [0, 1000] (power iterations; 5 estimate the norm well), got %d", (int)h2.estimate_error);
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCSetFromOptions_H2(PC pc, PetscOptionItems *PetscOptionsObject)
{
  PC_H2 *h2 = (PC_H2 *)pc->data;

  PetscFunctionBegin;
  PetscOptionsHeadBegin(PetscOptionsObject, "H2 factorization options");
  PetscCall(PetscOptionsReal("-pc_h2_rel_tol", "Relative tolerance of the factorization (of each skeleton)", "PCH2SetRelTol", h2->rel_tol, &h2->rel_tol, NULL));
  PetscCall(PetscOptionsInt("-pc_h2_leaf_size", "Dof nodes per box at the first level factored (0: the H2 matrix's leaves, below tolerance 1e-5 their parents)", "PCH2SetLeafSize", h2->leaf_size, &h2->leaf_size, NULL));
  PetscCall(PetscOptionsInt("-pc_h2_top_size", "Unknowns factored densely at the top", "PCH2SetTopSize", h2->top_size, &h2->top_size, NULL));
  PetscCall(PetscOptionsBool("-pc_h2_top_when_cheaper", "Factor the rest densely from a level whose eliminations would cost more flops than that", "PCH2SetTopWhenCheaper", h2->top_cheaper, &h2->top_cheaper, NULL));
  PetscCall(PetscOptionsInt("-pc_h2_mixed_top", "From this many unknowns on, the dense top's LU in single precision, each solve refined in double (0: always double)", "PCH2SetMixedTop", h2->mixed_top, &h2->mixed_top, NULL));
  PetscCall(PetscOptionsBool("-pc_h2_spread_top", "On several ranks, spread a single-precision top's LU over the ranks (ScaLAPACK) instead of factoring it on rank 0", "", h2->spread_top, &h2->spread_top, NULL));
  PetscCall(PetscOptionsInt("-pc_h2_sketch_size", "Random vectors of the far-field sketch (0: from the tolerance)", "PCH2SetSketchSize", h2->sketch_size, &h2->sketch_size, NULL));
  PetscCall(PetscOptionsInt("-pc_h2_estimate_error", "Power iterations of the ||I - A F^-1|| estimate shown by -ksp_view (0: none)", "PCH2SetEstimateError", h2->estimate_error, &h2->estimate_error, NULL));
  PetscOptionsHeadEnd();
  PetscCall(CheckOptions_Private(pc, *h2));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* How the top's LU runs, between open and close; empty for the double LU. */
std::string TopLU_Private(const hssbem::H2Factorization &F, const char *open, const char *close)
{
  const hssbem::H2FactorStats &st = F.stats();
  if (st.top_mixed) return std::string(open) + "LU in single precision, solves refined in double" + close;
  if (!st.top_single) return "";
  char trial[96];
  std::snprintf(trial, sizeof trial, "LU in single precision like the panels, a trial solve off by %.1e", F.top_trial());
  return std::string(open) + trial + close;
}

PetscErrorCode ViewFactorization_Private(PetscViewer viewer, const hssbem::H2Factorization &F)
{
  const hssbem::H2FactorStats &st = F.stats();

  PetscFunctionBegin;
  PetscCall(PetscViewerASCIIPrintf(viewer, "factorization: %.2f s (sketch %.2f, first boxes %.2f, skeletons %.2f, eliminations %.2f, merges %.2f, top %.2f; thread-seconds for skeletons and eliminations)\n",
                                   st.seconds(), st.time_sketch, st.time_init, st.time_skeleton, st.time_eliminate, st.time_merge, st.time_top));
  PetscCall(PetscViewerASCIIPrintf(viewer, "factors: %.1f MB (%s panels and working blocks; those peaked at %.1f MB), dense top %d unknowns (%.1f MB%s), sketch of %d vectors\n", st.bytes / 1048576.0,
                                   st.single_panels ? "single-precision" : "double-precision", st.workspace_bytes / 1048576.0, st.top_size, st.top_bytes / 1048576.0,
                                   TopLU_Private(F, "; ", "").c_str(), st.sketch_columns));
  for (const hssbem::H2FactorLevelStats &l : st.levels)
    PetscCall(PetscViewerASCIIPrintf(viewer, "level %d: %d boxes, %.0f unknowns per box (max %d) -> skeleton %.0f (max %d), %lld eliminated, %.1f MB, %.2f s\n", l.level, l.boxes, l.mean_candidates,
                                     l.max_candidates, l.mean_rank, l.max_rank, l.eliminated, l.bytes / 1048576.0, l.seconds));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The distributed factorization: rank 0's top, then each rank's part (collective on the viewer). */
PetscErrorCode ViewDistributed_Private(PetscViewer viewer, const PC_H2 &h2)
{
  const hssbem::H2FactorStats &st = h2.factors->stats();
  PetscMPIInt                  rank;
  std::size_t                  cross = 0;
  long long                    eliminated = 0;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(PetscObjectComm((PetscObject)viewer), &rank));
  PetscCall(PetscViewerASCIIPrintf(viewer, "distributed: each rank factors its part's subtree (%d parts, cross blocks between them), %s\n", st.parts, st.top_spread > 0 ? "all ranks the top" : "rank 0 the top"));
  if (st.top_spread > 0)
    PetscCall(PetscViewerASCIIPrintf(viewer, "top spread over %d ranks (ScaLAPACK): %d unknowns of %d boxes, %.1f MB on rank 0%s, %.2f s\n", st.top_spread, st.top_size,
                                     st.top_boxes, st.top_bytes / 1048576.0, TopLU_Private(*h2.factors, " (", ")").c_str(), st.time_top));
  else
    PetscCall(PetscViewerASCIIPrintf(viewer, "top on rank 0: %d unknowns of %d boxes, %.1f MB%s, %.2f s\n", st.top_size, st.top_boxes, st.top_bytes / 1048576.0,
                                     TopLU_Private(*h2.factors, " (", ")").c_str(), st.time_top));
  for (const hssbem::H2FactorLevelStats &l : st.levels) {
    cross = std::max(cross, l.cross_bytes);
    eliminated += l.eliminated;
  }
  PetscCall(PetscViewerASCIIPushSynchronized(viewer));
  PetscCall(PetscViewerASCIISynchronizedPrintf(viewer, "    rank %d: %lld unknowns eliminated, factors %.1f MB, cross blocks at most %.1f MB, working blocks peaked at %.1f MB; %.2f s (sketch %.2f, skeletons %.2f, eliminations %.2f, merges %.2f)\n",
                                               (int)rank, eliminated, st.bytes / 1048576.0, cross / 1048576.0, st.workspace_bytes / 1048576.0, st.seconds(), st.time_sketch,
                                               st.time_skeleton, st.time_eliminate, st.time_merge));
  for (const hssbem::H2FactorLevelStats &l : st.levels)
    PetscCall(PetscViewerASCIISynchronizedPrintf(viewer, "      level %d: %d boxes, %.0f unknowns per box (max %d) -> skeleton %.0f (max %d), %lld eliminated, %lld cross blocks (%.1f MB), %.2f s\n", l.level, l.boxes,
                                                 l.mean_candidates, l.max_candidates, l.mean_rank, l.max_rank, l.eliminated, l.cross_blocks, l.cross_bytes / 1048576.0, l.seconds));
  PetscCall(PetscViewerFlush(viewer));
  PetscCall(PetscViewerASCIIPopSynchronized(viewer));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCView_H2(PC pc, PetscViewer viewer)
{
  PC_H2   *h2 = (PC_H2 *)pc->data;
  PetscBool ascii;

  PetscFunctionBegin;
  PetscCall(PetscObjectTypeCompare((PetscObject)viewer, PETSCVIEWERASCII, &ascii));
  if (!ascii) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscViewerASCIIPrintf(viewer, "  H2 factorization (strong recursive skeletonization): relative tolerance %g, leaf size %s, top %d\n", (double)h2->rel_tol,
                                   h2->leaf_size > 0 ? std::to_string((int)h2->leaf_size).c_str() : "the matrix's", (int)h2->top_size));
  if (h2->dsys) {
    PetscCall(PetscViewerASCIIPushTab(viewer));
    PetscCall(PetscViewerASCIIPushTab(viewer));
    if (h2->source == Source::Matrix) PetscCall(PetscViewerASCIIPrintf(viewer, "of the matrix's distributed H2 compression (at %g; no kernel entry evaluated)\n", h2->compressed_tol));
    else PetscCall(PetscViewerASCIIPrintf(viewer, "of a distributed H2 compression made at %g on the matrix's partition, %.2f s\n", h2->compressed_tol, h2->seconds_compress));
    if (h2->factors) PetscCall(ViewDistributed_Private(viewer, *h2));
    else PetscCall(PetscViewerASCIIPrintf(viewer, "factorization failed: %s\n", h2->failure.empty() ? "on another rank" : h2->failure.c_str()));
    if (h2->factors && h2->inverse_error >= 0) PetscCall(PetscViewerASCIIPrintf(viewer, "||I - A F^-1|| estimated at %.3e (%d power iterations)\n", h2->inverse_error, (int)h2->estimate_error));
    PetscCall(PetscViewerASCIIPopTab(viewer));
    PetscCall(PetscViewerASCIIPopTab(viewer));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  if (!h2->sys) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscViewerASCIIPushTab(viewer));
  PetscCall(PetscViewerASCIIPushTab(viewer));
  if (h2->source == Source::Matrix) PetscCall(PetscViewerASCIIPrintf(viewer, "of the matrix's H2 compression (at %g; no kernel entry evaluated)\n", h2->compressed_tol));
  else {
    PetscCall(PetscViewerASCIIPrintf(viewer, "of an H2 compression made at %g, %.2f s:\n", h2->compressed_tol, h2->seconds_compress));
    PetscCall(HssbemViewH2Matrix_Private(viewer, h2->sys->matrix()));
  }
  if (h2->factors) {
    PetscCall(ViewFactorization_Private(viewer, *h2->factors));
    if (h2->inverse_error >= 0) PetscCall(PetscViewerASCIIPrintf(viewer, "||I - A F^-1|| estimated at %.3e (%d power iterations)\n", h2->inverse_error, (int)h2->estimate_error));
  } else PetscCall(PetscViewerASCIIPrintf(viewer, "factorization failed: %s\n", h2->failure.c_str()));
  PetscCall(PetscViewerASCIIPopTab(viewer));
  PetscCall(PetscViewerASCIIPopTab(viewer));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The setters check the new value alone, then store it. */
PetscErrorCode PCH2SetRelTol_H2(PC pc, PetscReal tol)
{
  PetscFunctionBegin;
  PetscCheck(tol > 0 && tol < 1, PetscObjectComm((PetscObject)pc), PETSC_ERR_ARG_OUTOFRANGE, "the relative tolerance must lie in (0, 1)");
  ((PC_H2 *)pc->data)->rel_tol = tol;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCH2SetLeafSize_H2(PC pc, PetscInt n)
{
  PetscFunctionBegin;
  PetscCheck(n >= 0, PetscObjectComm((PetscObject)pc), PETSC_ERR_ARG_OUTOFRANGE, "the leaf size must be 0 (the matrix's leaves) or positive");
  ((PC_H2 *)pc->data)->leaf_size = n;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCH2SetTopSize_H2(PC pc, PetscInt n)
{
  PetscFunctionBegin;
  PetscCheck(n >= 0, PetscObjectComm((PetscObject)pc), PETSC_ERR_ARG_OUTOFRANGE, "the top size must be >= 0");
  ((PC_H2 *)pc->data)->top_size = n;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCH2SetTopWhenCheaper_H2(PC pc, PetscBool flg)
{
  PetscFunctionBegin;
  ((PC_H2 *)pc->data)->top_cheaper = flg;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCH2SetMixedTop_H2(PC pc, PetscInt n)
{
  PetscFunctionBegin;
  ((PC_H2 *)pc->data)->mixed_top = n; /* any value: <= 0 means always double */
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCH2SetSketchSize_H2(PC pc, PetscInt n)
{
  PetscFunctionBegin;
  PetscCheck(n >= 0 && n <= hssbem::kMaxSketchColumns, PetscObjectComm((PetscObject)pc), PETSC_ERR_ARG_OUTOFRANGE, "the sketch size must be 0 (from the tolerance) or at most %d", hssbem::kMaxSketchColumns);
  ((PC_H2 *)pc->data)->sketch_size = n;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCH2SetEstimateError_H2(PC pc, PetscInt n)
{
  PetscFunctionBegin;
  PetscCheck(n >= 0 && n <= 1000, PetscObjectComm((PetscObject)pc), PETSC_ERR_ARG_OUTOFRANGE, "the power iterations must lie in [0, 1000]");
  ((PC_H2 *)pc->data)->estimate_error = n;
  PetscFunctionReturn(PETSC_SUCCESS);
}

} // namespace

/*MC
  PCH2 - H² factorization of the BEM system matrix by strong recursive skeletonization (hssbem).

  Options Database Keys:
+ -pc_h2_rel_tol <tol>        - relative tolerance of each skeleton (default 2e-3: a preconditioner)
. -pc_h2_leaf_size <n>        - dof nodes per box at the first level factored (0: the H² leaves; below 1e-5 their parents)
. -pc_h2_top_size <n>         - unknowns factored densely at the top (default 2000)
. -pc_h2_top_when_cheaper <b> - also stop at a level whose eliminations would cost more flops than the dense top (default true)
. -pc_h2_mixed_top <n>        - from this top size on (default 4000), its LU in single precision, solves refined in double (0: never)
. -pc_h2_spread_top <b>       - on several ranks, spread a single-precision top's LU over the ranks, ScaLAPACK (default true; false: rank 0)
. -pc_h2_sketch_size <p>      - random vectors of the far-field sketch (0: from the tolerance)
- -pc_h2_estimate_error <k>   - power iterations of the ||I - A F^-1|| estimate in -ksp_view (0: none)

  Notes:
  On the H² MatShell the factorization reads the matrix's own compression (no kernel entry
  evaluated); on several ranks it is distributed like the matrix (each rank factors its part's
  subtree, rank 0 the top; a solve sends only the top's unknowns to rank 0 and back). On a dense
  or HSS matrix (on several ranks: on rank 0), or at a tolerance tighter than the H² matrix's, it
  compresses an H² matrix at its own tolerance first. With GMRES at the default tolerance it is
  a preconditioner; with -ksp_type preonly -pc_h2_rel_tol 1e-7 a direct solver to about that
  tolerance. A pivot block singular to working precision sets PC_FACTOR_NUMERIC_ZEROPIVOT.

  Level: beginner
M*/
PETSC_EXTERN PetscErrorCode PCCreate_H2(PC pc)
{
  PetscFunctionBegin;
  PetscCallCXX(pc->data = new PC_H2);
  pc->ops->setup          = PCSetUp_H2;
  pc->ops->apply          = PCApply_H2;
  pc->ops->reset          = PCReset_H2;
  pc->ops->destroy        = PCDestroy_H2;
  pc->ops->setfromoptions = PCSetFromOptions_H2;
  pc->ops->view           = PCView_H2;
  PetscCall(PetscObjectComposeFunction((PetscObject)pc, "PCH2SetRelTol_C", PCH2SetRelTol_H2));
  PetscCall(PetscObjectComposeFunction((PetscObject)pc, "PCH2SetLeafSize_C", PCH2SetLeafSize_H2));
  PetscCall(PetscObjectComposeFunction((PetscObject)pc, "PCH2SetTopSize_C", PCH2SetTopSize_H2));
  PetscCall(PetscObjectComposeFunction((PetscObject)pc, "PCH2SetTopWhenCheaper_C", PCH2SetTopWhenCheaper_H2));
  PetscCall(PetscObjectComposeFunction((PetscObject)pc, "PCH2SetMixedTop_C", PCH2SetMixedTop_H2));
  PetscCall(PetscObjectComposeFunction((PetscObject)pc, "PCH2SetSketchSize_C", PCH2SetSketchSize_H2));
  PetscCall(PetscObjectComposeFunction((PetscObject)pc, "PCH2SetEstimateError_C", PCH2SetEstimateError_H2));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@
  PCH2SetRelTol - Sets the relative tolerance of the H² factorization (of each skeleton).

  Logically Collective

  Level: intermediate
@*/
PetscErrorCode PCH2SetRelTol(PC pc, PetscReal tol)
{
  PetscFunctionBegin;
  PetscTryMethod(pc, "PCH2SetRelTol_C", (PC, PetscReal), (pc, tol));
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
  PetscTryMethod(pc, "PCH2SetLeafSize_C", (PC, PetscInt), (pc, n));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@
  PCH2SetTopSize - Sets how many unknowns may remain for the dense top factorization.

  Logically Collective

  Level: advanced
@*/
PetscErrorCode PCH2SetTopSize(PC pc, PetscInt n)
{
  PetscFunctionBegin;
  PetscTryMethod(pc, "PCH2SetTopSize_C", (PC, PetscInt), (pc, n));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@
  PCH2SetTopWhenCheaper - Sets whether the factorization stops at a level whose eliminations would
  cost more flops (an upper bound of its Schur complements) than factoring every unknown left
  densely; the rest becomes the top. PETSC_FALSE: go on while a level has a far field and more
  than the top size of unknowns remain.

  Logically Collective

  Level: advanced
@*/
PetscErrorCode PCH2SetTopWhenCheaper(PC pc, PetscBool flg)
{
  PetscFunctionBegin;
  PetscTryMethod(pc, "PCH2SetTopWhenCheaper_C", (PC, PetscBool), (pc, flg));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@
  PCH2SetMixedTop - Sets the top size from which the dense top is factored in single precision and
  every solve is refined in double against it (as accurate as a double LU, about half its time);
  0 or less: always in double.

  Logically Collective

  Level: advanced
@*/
PetscErrorCode PCH2SetMixedTop(PC pc, PetscInt n)
{
  PetscFunctionBegin;
  PetscTryMethod(pc, "PCH2SetMixedTop_C", (PC, PetscInt), (pc, n));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@
  PCH2SetSketchSize - Sets the random vectors of the far-field sketch (0: from the tolerance).

  Logically Collective

  Level: advanced
@*/
PetscErrorCode PCH2SetSketchSize(PC pc, PetscInt n)
{
  PetscFunctionBegin;
  PetscTryMethod(pc, "PCH2SetSketchSize_C", (PC, PetscInt), (pc, n));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@
  PCH2SetEstimateError - Sets the power iterations of the ||I - A F^-1|| estimate (0: none).

  Logically Collective

  Level: advanced
@*/
PetscErrorCode PCH2SetEstimateError(PC pc, PetscInt n)
{
  PetscFunctionBegin;
  PetscTryMethod(pc, "PCH2SetEstimateError_C", (PC, PetscInt), (pc, n));
  PetscFunctionReturn(PETSC_SUCCESS);
}
