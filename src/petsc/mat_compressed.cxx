/* The BEM operator as a MatShell backed by a compressed K (HSS or H²) distributed over the ranks:
   MatMult by the O(N·r) product, MatGetDiagonal from the leaves' true entries, MatView with ranks
   and memory; one shell for both formats (hssbem::DistributedBemSystem). */
#include "mat_compressed.hpp"

#include "hssbem/petsc/log.h"

#include <algorithm>
#include <cstdio>
#include <string>

namespace {

PetscErrorCode MatMult_Compressed(Mat A, Vec x, Vec y)
{
  HssbemSystemContext *p;
  HssbemGuard          guard;
  const PetscScalar   *xa;
  PetscScalar         *ya;

  PetscFunctionBegin;
  PetscCall(MatShellGetContext(A, &p));
  PetscCall(VecGetArrayRead(x, &xa));
  PetscCall(VecGetArrayWrite(y, &ya));
  guard.Run([&] {
    /* the ranks meet in the product's exchanges: a fault here must be agreed on first */
    hssbem::collectively(*p->layout->comm, [] { hssbem::fault_point("MatMult"); });
    p->distributed()->apply(p->sel, xa, ya);
    if (!p->modes.empty()) HssbemAddRegularization(*p->distributed(), *p->layout->comm, p->modes, xa, ya);
  });
  PetscCall(VecRestoreArrayRead(x, &xa));
  PetscCall(VecRestoreArrayWrite(y, &ya));
  PetscCall(guard.Check(PetscObjectComm((PetscObject)A), "MatMult"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode MatGetDiagonal_Compressed(Mat A, Vec d)
{
  HssbemSystemContext *p;
  HssbemGuard          guard;
  PetscScalar         *da;

  PetscFunctionBegin;
  PetscCall(MatShellGetContext(A, &p));
  PetscCall(VecGetArrayWrite(d, &da));
  guard.Run("MatGetDiagonal", [&] {
    const std::vector<double> diag = p->distributed()->diagonal(p->sel);
    std::copy(diag.begin(), diag.end(), da);
    if (!p->modes.empty()) HssbemAddRegularizationDiagonal(*p->distributed(), p->modes, da);
  });
  PetscCall(VecRestoreArrayWrite(d, &da));
  PetscCall(guard.Check(PetscObjectComm((PetscObject)A), "MatGetDiagonal"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The format's options, the pattern and the partition (collective: memory and traffic over the
   ranks), then rank 0's part. */
PetscErrorCode MatView_Compressed(Mat A, PetscViewer viewer)
{
  HssbemSystemContext *p;
  PetscBool            ascii;

  PetscFunctionBegin;
  PetscCall(PetscObjectTypeCompare((PetscObject)viewer, PETSCVIEWERASCII, &ascii));
  if (!ascii) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(MatShellGetContext(A, &p));
  const bool h2 = p->type == hssbem::OperatorType::H2;
  if (h2) {
    const hssbem::H2Options &o = p->h2_options;
    PetscCall(PetscViewerASCIIPrintf(viewer, "BEM operator in H² form (hssbem, strong admissibility): relative tolerance %g, leaf size %d, eta %g, rank cap %s, proxy ratio %g, blocks in %s precision\n",
                                     o.rel_tol, o.leaf_size, o.eta, o.max_rank > 0 ? std::to_string(o.max_rank).c_str() : "none", o.proxy_ratio, o.single_precision ? "single" : "double"));
  } else {
    const hssbem::HssOptions &o = p->hss_options;
    PetscCall(PetscViewerASCIIPrintf(viewer, "BEM operator in HSS form (hssbem): relative tolerance %g, leaf size %d, rank cap %s, proxy ratio %g\n", o.rel_tol, o.leaf_size,
                                     o.max_rank > 0 ? std::to_string(o.max_rank).c_str() : "none", o.proxy_ratio));
  }
  const bool                        pressure = h2 ? p->h2_options.pressure_columns : p->hss_options.pressure_columns;
  const hssbem::RankComm           &comm     = *p->layout->comm;
  const hssbem::NodePartitionStats &ps       = p->layout->partition;
  double                            mem[2]   = {(double)p->distributed()->memory_bytes(), 0};
  mem[1] = comm.max(mem[0]);
  comm.sum(&mem[0], 1);
  const double sent[2] = {comm.max(h2 ? (double)p->h2->product().values_sent() : (double)p->hss->product().values_sent()),
                          comm.max(h2 ? (double)p->h2->product().messages_sent() : (double)p->hss->product().messages_sent())};
  PetscCall(PetscViewerASCIIPrintf(viewer, "  pattern: %s; rigid-mode regularisation: %s\n", pressure ? "K = [H, G, Gn] (pressure loads)" : "K = [H, G]", p->modes.empty() ? "no" : "yes"));
  PetscCall(PetscViewerASCIIPrintf(viewer, "  distributed over %d ranks by METIS: %d to %d nodes per rank (imbalance %.3f), edge cut %ld of %ld node-graph edges%s\n", ps.parts, ps.min_nodes, ps.max_nodes, ps.imbalance,
                                   ps.edge_cut, ps.edges, ps.disconnected_parts ? " (some parts not connected)" : ""));
  char top[96] = ""; /* one line: the ASCII viewer indents every print */
  if (!h2) std::snprintf(top, sizeof top, ", of which the top (%d clusters above the parts, rank 0) %.2f MB", p->hss->matrix().stats().top_clusters, p->hss->matrix().stats().top_bytes / 1048576.0);
  PetscCall(PetscViewerASCIIPrintf(viewer, "  memory %.1f MB in all, %.1f MB on the largest rank%s; per product a rank sends at most %.0f values in %.0f messages\n", mem[0] / 1048576.0, mem[1] / 1048576.0, top, sent[0], sent[1]));
  PetscCall(PetscViewerASCIIPrintf(viewer, "  rank 0's part (ranks per level: all parts):\n"));
  PetscCall(PetscViewerASCIIPushTab(viewer));
  PetscCall(PetscViewerASCIIPushTab(viewer));
  if (h2) PetscCall(HssbemViewH2Matrix_Private(viewer, p->h2->matrix()));
  else PetscCall(HssbemViewHssMatrix_Private(viewer, p->hss->matrix()));
  PetscCall(PetscViewerASCIIPopTab(viewer));
  PetscCall(PetscViewerASCIIPopTab(viewer));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* One line: the rank per level (1 down) of the levels with clusters, HSS or H². */
template <class Level>
PetscErrorCode ViewLevelRanks_Private(PetscViewer viewer, const char *which, const std::vector<Level> &levels)
{
  PetscFunctionBegin;
  PetscCall(PetscViewerASCIIPrintf(viewer, "rank per level (%s: rows max/mean, columns max/mean):", which));
  PetscCall(PetscViewerASCIIUseTabs(viewer, PETSC_FALSE));
  for (std::size_t l = 1; l < levels.size(); ++l) {
    const Level &L = levels[l];
    if (L.clusters > 0) PetscCall(PetscViewerASCIIPrintf(viewer, " L%d (%d: %d/%.0f, %d/%.0f)", (int)l, L.clusters, L.max_row_rank, L.mean_row_rank, L.max_col_rank, L.mean_col_rank));
  }
  PetscCall(PetscViewerASCIIPrintf(viewer, "\n"));
  PetscCall(PetscViewerASCIIUseTabs(viewer, PETSC_TRUE));
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
  PetscCall(ViewLevelRanks_Private(viewer, "clusters", s.levels));
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
  PetscCall(ViewLevelRanks_Private(viewer, "clusters with a basis", s.levels));
  PetscCall(PetscViewerASCIIPrintf(viewer, "entries evaluated %lld (%.2f x dense K); seconds: tree and partition %.2f, ID samples %.2f and IDs %.2f (thread-seconds), far blocks %.2f, near blocks %.2f, rigid-body terms %.2f\n",
                                   s.entries_evaluated, s.entries_evaluated / dense_entries, s.time_tree, s.time_near_field, s.time_ids, s.time_far, s.time_near, s.time_rigid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode HssbemMatCreateCompressed_Private(MPI_Comm comm, HssbemSystemContext *sys, Mat *A, Vec *b)
{
  const hssbem::BemOperator &op = *sys->op;
  const bool                 h2 = sys->type == hssbem::OperatorType::H2;
  const PetscInt             N  = 3 * op.num_nodes();
  HssbemGuard                guard;
  std::vector<double>        b0;
  PetscScalar               *ba;

  PetscFunctionBegin;
  PetscCall(PetscLogEventBegin(BEM_Assembly, 0, 0, 0, 0));
  PetscCall(HssbemLayoutCreate(comm, op, &sys->layout));
  const HssbemLayout &L = *sys->layout;
  guard.Run([&] {
    hssbem::collectively(*L.comm, [] { hssbem::fault_point("Compression"); }); /* as in MatMult */
    if (h2 && sys->h2_source) sys->h2 = sys->h2_source(L.node_part, *L.comm); /* collective */
    else if (h2) sys->h2 = hssbem::make_shared_collectively<hssbem::H2DistributedSystem>(*L.comm, op, sys->h2_options, L.node_part, *L.comm);
    else sys->hss = hssbem::make_shared_collectively<hssbem::HssDistributedSystem>(*L.comm, op, sys->hss_options, L.node_part, *L.comm);
    b0                 = sys->distributed()->rhs(sys->sel);
    sys->system_of_dof = HssbemSystemRows(sys->distributed()->tree());
  });
  PetscCall(guard.Check(comm, h2 ? "H2 compression failed" : "HSS compression failed"));
  const PetscInt n = 3 * sys->distributed()->num_points();
  PetscCall(MatCreateShell(comm, n, n, N, N, sys, A));
  PetscCall(MatSetBlockSize(*A, 3));
  PetscCall(MatShellSetOperation(*A, MATOP_MULT, (void (*)(void))MatMult_Compressed));
  PetscCall(MatShellSetOperation(*A, MATOP_GET_DIAGONAL, (void (*)(void))MatGetDiagonal_Compressed));
  PetscCall(MatShellSetOperation(*A, MATOP_VIEW, (void (*)(void))MatView_Compressed));
  PetscCall(MatSetOption(*A, MAT_SYMMETRIC, PETSC_FALSE));
  PetscCall(MatCreateVecs(*A, NULL, b));
  PetscCall(VecGetArrayWrite(*b, &ba));
  std::copy(b0.begin(), b0.end(), ba);
  PetscCall(VecRestoreArrayWrite(*b, &ba));
  PetscCall(PetscLogEventEnd(BEM_Assembly, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}
