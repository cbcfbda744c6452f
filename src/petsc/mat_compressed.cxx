/* The BEM operator as a MatShell backed by a compressed K (HSS with -bem_mat_type hss, H² with
   -bem_mat_type h2): MatMult by the O(N·r) product, MatGetDiagonal from the leaves' true
   entries, MatView with ranks and memory. One shell serves both formats through
   hssbem::CompressedBemSystem on one rank and hssbem::DistributedBemSystem on several; only
   MatView and the construction tell them apart. */
#include "mat_compressed.hpp"

#include "hssbem/petsc/log.h"
#include "hssbem/bem/rigid_modes.hpp"

#include <algorithm>

#include <exception>
#include <string>

namespace {

struct Mat_Compressed {
  HssbemSystemContext *sys = nullptr; /* owned by the container composed with the Mat */
  HssbemRootExchange   ex;
};

PetscErrorCode MatCompressedGetContext(Mat A, Mat_Compressed **ctx)
{
  PetscFunctionBegin;
  PetscCall(MatShellGetContext(A, ctx));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Mesh-order dof of local row i of the distributed system. */
inline std::size_t MeshDof_Private(const HssbemSystemContext &p, int i)
{
  const hssbem::DistributedBemSystem &s = *p.distributed();
  return 3 * (std::size_t)s.tree().perm()[s.first_point() + i / 3] + (std::size_t)(i % 3);
}

/* y += c Q (Qᵀ x) on this rank's rows of the distributed system (Qᵀ x summed over the ranks). */
void AddDistributedRegularization_Private(const HssbemSystemContext &p, const PetscScalar *x, PetscScalar *y)
{
  const int n = 3 * p.distributed()->num_points();
  double    qx[6] = {0, 0, 0, 0, 0, 0};
  for (int i = 0; i < n; ++i) {
    const double *q = &p.modes[6 * MeshDof_Private(p, i)];
    for (int m = 0; m < 6; ++m) qx[m] += q[m] * x[i];
  }
  p.comm->sum(qx, 6);
  for (int m = 0; m < 6; ++m) qx[m] *= hssbem::rigid_regularization_weight;
  for (int i = 0; i < n; ++i) {
    const double *q = &p.modes[6 * MeshDof_Private(p, i)];
    for (int m = 0; m < 6; ++m) y[i] += q[m] * qx[m];
  }
}

PetscErrorCode MatMult_Compressed(Mat A, Vec x, Vec y)
{
  Mat_Compressed    *ctx;
  HssbemGuard        guard;
  const PetscScalar *xa;
  PetscScalar       *ya;

  PetscFunctionBegin;
  PetscCall(MatCompressedGetContext(A, &ctx));
  const HssbemSystemContext &p = *ctx->sys;
  if (p.distributed()) {
    PetscCall(VecGetArrayRead(x, &xa));
    PetscCall(VecGetArrayWrite(y, &ya));
    guard.Run([&] {
      /* the ranks meet in the product's exchanges: a fault here must be agreed on first */
      hssbem::collectively(*p.comm, [] { hssbem::fault_point("MatMult"); });
      p.distributed()->apply(p.sel, xa, ya);
      if (!p.modes.empty()) AddDistributedRegularization_Private(p, xa, ya);
    });
    PetscCall(VecRestoreArrayRead(x, &xa));
    PetscCall(VecRestoreArrayWrite(y, &ya));
    PetscCall(guard.Check(PetscObjectComm((PetscObject)A), "MatMult"));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PetscCall(ctx->ex.SetUp(x));
  PetscCall(ctx->ex.Gather(x, &xa));
  PetscCall(ctx->ex.GetOut(&ya));
  guard.Run("MatMult", [&] {
    if (!p.compressed()) return; /* the compression lives on rank 0 */
    p.compressed()->apply(p.sel, xa, ya);
    if (!p.modes.empty()) HssbemAddRegularization(p.modes, xa, ya);
  });
  PetscCall(ctx->ex.RestoreGather(&xa));
  PetscCall(ctx->ex.ScatterOut(&ya, y));
  PetscCall(guard.Check(PetscObjectComm((PetscObject)A), "MatMult"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode MatGetDiagonal_Compressed(Mat A, Vec d)
{
  Mat_Compressed *ctx;
  HssbemGuard     guard;
  PetscScalar    *da;

  PetscFunctionBegin;
  PetscCall(MatCompressedGetContext(A, &ctx));
  const HssbemSystemContext &p = *ctx->sys;
  if (p.distributed()) {
    PetscCall(VecGetArrayWrite(d, &da));
    guard.Run("MatGetDiagonal", [&] {
      const std::vector<double> diag = p.distributed()->diagonal(p.sel);
      for (std::size_t i = 0; i < diag.size(); ++i) {
        da[i] = diag[i];
        if (p.modes.empty()) continue;
        const double *q = &p.modes[6 * MeshDof_Private(p, (int)i)];
        da[i] += hssbem::rigid_regularization_weight * (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] + q[4] * q[4] + q[5] * q[5]);
      }
    });
    PetscCall(VecRestoreArrayWrite(d, &da));
    PetscCall(guard.Check(PetscObjectComm((PetscObject)A), "MatGetDiagonal"));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PetscCall(ctx->ex.SetUp(d));
  PetscCall(ctx->ex.GetOut(&da));
  guard.Run("MatGetDiagonal", [&] {
    if (!p.compressed()) return;
    const std::vector<double> diag = p.compressed()->diagonal(p.sel);
    for (std::size_t i = 0; i < diag.size(); ++i) {
      da[i] = diag[i];
      if (!p.modes.empty()) {
        const double *q = &p.modes[6 * i];
        da[i] += hssbem::rigid_regularization_weight * (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] + q[4] * q[4] + q[5] * q[5]);
      }
    }
  });
  PetscCall(ctx->ex.ScatterOut(&da, d));
  PetscCall(guard.Check(PetscObjectComm((PetscObject)A), "MatGetDiagonal"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode MatView_Compressed(Mat A, PetscViewer viewer)
{
  Mat_Compressed *ctx;
  PetscBool       ascii;

  PetscFunctionBegin;
  PetscCall(PetscObjectTypeCompare((PetscObject)viewer, PETSCVIEWERASCII, &ascii));
  if (!ascii) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(MatCompressedGetContext(A, &ctx));
  const HssbemSystemContext &p = *ctx->sys;
  if (p.type == hssbem::OperatorType::H2) {
    const hssbem::H2Options &o = p.h2_options;
    PetscCall(PetscViewerASCIIPrintf(viewer, "BEM operator in H² form (hssbem, strong admissibility): relative tolerance %g, leaf size %d, eta %g, rank cap %s, proxy ratio %g, blocks in %s precision\n",
                                     o.rel_tol, o.leaf_size, o.eta, o.max_rank > 0 ? std::to_string(o.max_rank).c_str() : "none", o.proxy_ratio, o.single_precision ? "single" : "double"));
  } else {
    const hssbem::HssOptions &o = p.hss_options;
    PetscCall(PetscViewerASCIIPrintf(viewer, "BEM operator in HSS form (hssbem): relative tolerance %g, leaf size %d, rank cap %s, proxy ratio %g\n", o.rel_tol, o.leaf_size,
                                     o.max_rank > 0 ? std::to_string(o.max_rank).c_str() : "none", o.proxy_ratio));
  }
  const bool pressure = p.type == hssbem::OperatorType::H2 ? p.h2_options.pressure_columns : p.hss_options.pressure_columns;
  if (p.distributed()) {
    const hssbem::NodePartitionStats &ps = p.partition;
    double mem[2] = {(double)p.distributed()->memory_bytes(), (double)p.distributed()->memory_bytes()};
    p.comm->sum(&mem[0], 1);
    mem[1] = p.comm->max(mem[1]);
    PetscCall(PetscViewerASCIIPrintf(viewer, "  pattern: %s; rigid-mode regularisation: %s\n", pressure ? "K = [H, G, Gn] (pressure loads)" : "K = [H, G]", p.modes.empty() ? "no" : "yes"));
    PetscCall(PetscViewerASCIIPrintf(viewer, "  distributed over %d ranks by METIS: %d to %d nodes per rank (imbalance %.3f), edge cut %ld of %ld node-graph edges%s\n", ps.parts, ps.min_nodes, ps.max_nodes, ps.imbalance,
                                     ps.edge_cut, ps.edges, ps.disconnected_parts ? " (some parts not connected)" : ""));
    if (p.h2dist) {
      const hssbem::H2DistributedProduct &prod = p.h2dist->product();
      const double traffic[2] = {p.comm->max((double)prod.values_sent()), p.comm->max((double)prod.messages_sent())};
      PetscCall(PetscViewerASCIIPrintf(viewer, "  memory %.1f MB in all, %.1f MB on the largest rank; per product a rank sends at most %.0f values in %.0f messages\n", mem[0] / 1048576.0, mem[1] / 1048576.0,
                                       traffic[0], traffic[1]));
    } else {
      const hssbem::HssDistributedProduct &prod = p.hssdist->product();
      const hssbem::HssStats             &st   = p.hssdist->matrix().stats();
      const double traffic[2] = {p.comm->max((double)prod.values_sent()), p.comm->max((double)prod.messages_sent())};
      PetscCall(PetscViewerASCIIPrintf(viewer, "  memory %.1f MB in all, %.1f MB on the largest rank, of which the top (%d clusters above the parts, rank 0) %.2f MB; per product a rank sends at most %.0f values in %.0f messages\n",
                                       mem[0] / 1048576.0, mem[1] / 1048576.0, st.top_clusters, st.top_bytes / 1048576.0, traffic[0], traffic[1]));
    }
    PetscCall(PetscViewerASCIIPrintf(viewer, "  rank 0's part (ranks per level: all parts):\n"));
    PetscCall(PetscViewerASCIIPushTab(viewer));
    PetscCall(PetscViewerASCIIPushTab(viewer));
    if (p.h2dist) PetscCall(HssbemViewH2Matrix_Private(viewer, p.h2dist->matrix()));
    else PetscCall(HssbemViewHssMatrix_Private(viewer, p.hssdist->matrix()));
    PetscCall(PetscViewerASCIIPopTab(viewer));
    PetscCall(PetscViewerASCIIPopTab(viewer));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PetscCall(PetscViewerASCIIPrintf(viewer, "  pattern: %s; rigid-mode regularisation: %s; the compression lives on rank 0\n", pressure ? "K = [H, G, Gn] (pressure loads)" : "K = [H, G]",
                                   p.modes.empty() ? "no" : "yes"));
  if (p.compressed()) { /* rank 0 */
    PetscCall(PetscViewerASCIIPushTab(viewer));
    if (p.h2) PetscCall(HssbemViewH2Matrix_Private(viewer, p.h2->matrix()));
    else PetscCall(HssbemViewHssMatrix_Private(viewer, p.hss->matrix()));
    PetscCall(PetscViewerASCIIPopTab(viewer));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode MatDestroyContext_Compressed(void *ctx)
{
  PetscFunctionBegin;
  delete static_cast<Mat_Compressed *>(ctx);
  PetscFunctionReturn(PETSC_SUCCESS);
}

} // namespace

PetscErrorCode HssbemViewHssMatrix_Private(PetscViewer viewer, const hssbem::HssMatrix &K)
{
  const hssbem::HssStats &s = K.stats();
  const double            n = K.num_rows(), dense_entries = n * K.num_cols();

  PetscFunctionBegin;
  PetscCall(PetscViewerASCIIPrintf(viewer, "%d rows, %d levels, %d proxy points; max rank %d (rows) / %d (columns); memory %.1f MB (dense K: %.1f MB)\n", K.num_rows(), (int)s.levels.size(),
                                   s.proxy_points, s.max_row_rank(), s.max_col_rank(), s.memory_bytes / 1048576.0, 8 * dense_entries / 1048576.0));
  PetscCall(PetscViewerASCIIPrintf(viewer, "rank per level (clusters: rows max/mean, columns max/mean):"));
  PetscCall(PetscViewerASCIIUseTabs(viewer, PETSC_FALSE));
  for (std::size_t l = 1; l < s.levels.size(); ++l) {
    const hssbem::HssLevelStats &L = s.levels[l];
    PetscCall(PetscViewerASCIIPrintf(viewer, " L%d (%d: %d/%.0f, %d/%.0f)", (int)l, L.clusters, L.max_row_rank, L.mean_row_rank, L.max_col_rank, L.mean_col_rank));
  }
  PetscCall(PetscViewerASCIIPrintf(viewer, "\n"));
  PetscCall(PetscViewerASCIIUseTabs(viewer, PETSC_TRUE));
  PetscCall(PetscViewerASCIIPrintf(viewer, "entries evaluated %lld (%.2f x dense K); seconds: tree %.2f, near field %.2f, IDs %.2f, couplings %.2f, leaves %.2f, rigid-body terms %.2f\n",
                                   s.entries_evaluated, s.entries_evaluated / dense_entries, s.time_tree, s.time_near_field, s.time_ids, s.time_couplings, s.time_leaves, s.time_rigid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode HssbemViewH2Matrix_Private(PetscViewer viewer, const hssbem::H2Matrix &K)
{
  const hssbem::H2Stats &s = K.stats();
  const double           n = K.num_rows(), dense_entries = n * K.num_cols();

  PetscFunctionBegin;
  PetscCall(PetscViewerASCIIPrintf(viewer, "%d rows, %d levels, %d proxy points; max rank %d (rows) / %d (columns); memory %.1f MB (bases %.1f, %ld far blocks %.1f, %ld near blocks %.1f; dense K: %.1f MB)\n",
                                   K.num_rows(), (int)s.levels.size(), s.proxy_points, s.max_row_rank(), s.max_col_rank(), s.memory_bytes / 1048576.0, s.basis_bytes / 1048576.0, s.far_blocks,
                                   s.far_bytes / 1048576.0, s.near_blocks, s.near_bytes / 1048576.0, 8 * dense_entries / 1048576.0));
  PetscCall(PetscViewerASCIIPrintf(viewer, "rank per level (clusters with a basis: rows max/mean, columns max/mean):"));
  PetscCall(PetscViewerASCIIUseTabs(viewer, PETSC_FALSE));
  for (std::size_t l = 1; l < s.levels.size(); ++l) {
    const hssbem::H2LevelStats &L = s.levels[l];
    if (L.clusters > 0) PetscCall(PetscViewerASCIIPrintf(viewer, " L%d (%d: %d/%.0f, %d/%.0f)", (int)l, L.clusters, L.max_row_rank, L.mean_row_rank, L.max_col_rank, L.mean_col_rank));
  }
  PetscCall(PetscViewerASCIIPrintf(viewer, "\n"));
  PetscCall(PetscViewerASCIIUseTabs(viewer, PETSC_TRUE));
  PetscCall(PetscViewerASCIIPrintf(viewer, "entries evaluated %lld (%.2f x dense K); seconds: tree and partition %.2f, ID samples %.2f and IDs %.2f (thread-seconds), far blocks %.2f, near blocks %.2f, rigid-body terms %.2f\n",
                                   s.entries_evaluated, s.entries_evaluated / dense_entries, s.time_tree, s.time_near_field, s.time_ids, s.time_far, s.time_near, s.time_rigid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The MatShell's operations and layout (3 * nlocal rows of N here). */
static PetscErrorCode CreateShell_Private(MPI_Comm comm, HssbemSystemContext *sys, PetscInt nlocal, PetscInt N, Mat *A, Vec *b)
{
  Mat_Compressed *ctx;

  PetscFunctionBegin;
  PetscCallCXX(ctx = new Mat_Compressed);
  ctx->sys = sys;
  PetscCall(MatCreateShell(comm, 3 * nlocal, 3 * nlocal, N, N, ctx, A));
  PetscCall(MatShellSetContextDestroy(*A, MatDestroyContext_Compressed));
  PetscCall(MatSetBlockSize(*A, 3));
  PetscCall(MatShellSetOperation(*A, MATOP_MULT, (void (*)(void))MatMult_Compressed));
  PetscCall(MatShellSetOperation(*A, MATOP_GET_DIAGONAL, (void (*)(void))MatGetDiagonal_Compressed));
  PetscCall(MatShellSetOperation(*A, MATOP_VIEW, (void (*)(void))MatView_Compressed));
  PetscCall(MatSetOption(*A, MAT_SYMMETRIC, PETSC_FALSE));
  PetscCall(MatCreateVecs(*A, NULL, b));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The H² or HSS system on several ranks: the surface partitioned by METIS (rank 0, broadcast),
   each rank compressing its part; rows in cluster order (sys->system_of_dof). */
static PetscErrorCode CreateDistributed_Private(MPI_Comm comm, HssbemSystemContext *sys, Mat *A, Vec *b)
{
  const hssbem::BemOperator &op = *sys->op;
  const PetscInt             nn = op.num_nodes();
  const bool                 h2 = sys->type == hssbem::OperatorType::H2;
  PetscMPIInt                rank, size;
  HssbemGuard                guard;
  std::vector<double>        b0;
  PetscScalar               *ba;
  double                     figures[7] = {0, 0, 0, 0, 0, 0, 0};
  MPI_Comm                   dup;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(PetscLogEventBegin(BEM_Partition, 0, 0, 0, 0));
  /* The engines' own communicator, duplicated on every rank before anything can fail on one. */
  PetscCallMPI(MPI_Comm_dup(comm, &dup));
  guard.Run([&] {
    try {
      sys->comm = std::make_unique<HssbemMpiComm>(dup, true);
    } catch (...) {
      MPI_Comm_free(&dup);
      throw;
    }
    hssbem::fault_point("Partition");
    sys->node_part.resize((std::size_t)nn);
    if (rank != 0) return;
    sys->node_part                     = hssbem::partition_nodes(op.discretization(), size, &sys->partition);
    const hssbem::NodePartitionStats &s = sys->partition;
    const double f[7] = {(double)s.parts, (double)s.edge_cut, (double)s.edges, s.imbalance, (double)s.min_nodes, (double)s.max_nodes, (double)s.disconnected_parts};
    std::copy(f, f + 7, figures);
  });
  PetscCall(guard.Check(comm, "the partition of the surface failed"));
  PetscCallMPI(MPI_Bcast(sys->node_part.data(), (PetscMPIInt)nn, MPI_INT, 0, comm));
  PetscCallMPI(MPI_Bcast(figures, 7, MPI_DOUBLE, 0, comm));
  sys->partition = hssbem::NodePartitionStats{(int)figures[0], (long)figures[1], (long)figures[2], figures[3], (int)figures[4], (int)figures[5], (int)figures[6]};
  PetscCall(PetscLogEventEnd(BEM_Partition, 0, 0, 0, 0));
  guard.Run([&] {
    hssbem::collectively(*sys->comm, [] { hssbem::fault_point("Compression"); }); /* as in MatMult */
    if (h2) sys->h2dist = hssbem::make_shared_collectively<hssbem::H2DistributedSystem>(*sys->comm, op, sys->h2_options, sys->node_part, *sys->comm);
    else sys->hssdist = hssbem::make_shared_collectively<hssbem::HssDistributedSystem>(*sys->comm, op, sys->hss_options, sys->node_part, *sys->comm);
    b0                              = sys->distributed()->rhs(sys->sel);
    const hssbem::ClusterTree &tree = sys->distributed()->tree();
    sys->system_of_dof.resize(3 * (std::size_t)nn);
    for (PetscInt d = 0; d < 3 * nn; ++d) sys->system_of_dof[d] = 3 * (PetscInt)tree.iperm()[d / 3] + d % 3;
  });
  PetscCall(guard.Check(comm, h2 ? "H2 compression failed" : "HSS compression failed"));
  PetscCall(CreateShell_Private(comm, sys, sys->distributed()->num_points(), 3 * nn, A, b));
  PetscCall(VecGetArrayWrite(*b, &ba));
  std::copy(b0.begin(), b0.end(), ba);
  PetscCall(VecRestoreArrayWrite(*b, &ba));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode HssbemMatCreateCompressed_Private(MPI_Comm comm, HssbemSystemContext *sys, Mat *A, Vec *b)
{
  const hssbem::BemOperator &op = *sys->op;
  const bool                 h2 = sys->type == hssbem::OperatorType::H2;
  const PetscInt             nn = op.num_nodes(), N = 3 * nn;
  PetscInt                   nstart, nlocal;
  PetscMPIInt                rank;
  HssbemGuard                guard;
  std::vector<double>        b0;
  Mat_Compressed            *ctx;
  PetscScalar               *ba;

  PetscFunctionBegin;
  PetscCall(PetscLogEventBegin(BEM_Assembly, 0, 0, 0, 0));
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  {
    PetscMPIInt size;
    PetscCallMPI(MPI_Comm_size(comm, &size));
    if (size > 1) {
      PetscCall(CreateDistributed_Private(comm, sys, A, b));
      PetscCall(PetscLogEventEnd(BEM_Assembly, 0, 0, 0, 0));
      PetscFunctionReturn(PETSC_SUCCESS);
    }
  }
  guard.Run("Compression", [&] {
      if (rank != 0) return; /* one rank */
      if (h2) {
        auto K  = std::make_shared<hssbem::H2BemSystem>(op, sys->h2_options);
        b0      = K->rhs(sys->sel);
        sys->h2 = K;
      } else {
        auto K   = std::make_shared<hssbem::HssBemSystem>(op, sys->hss_options);
        b0       = K->rhs(sys->sel);
        sys->hss = K;
      }
    });
  PetscCall(guard.Check(comm, h2 ? "H2 compression failed" : "HSS compression failed"));
  PetscCall(HssbemOwnedNodes(comm, nn, &nstart, &nlocal));
  PetscCall(CreateShell_Private(comm, sys, nlocal, N, A, b));
  PetscCall(MatShellGetContext(*A, &ctx));
  PetscCall(ctx->ex.SetUp(*b));
  PetscCall(ctx->ex.GetOut(&ba));
  for (std::size_t i = 0; i < b0.size(); ++i) ba[i] = b0[i];
  PetscCall(ctx->ex.ScatterOut(&ba, *b));
  PetscCall(PetscLogEventEnd(BEM_Assembly, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}
