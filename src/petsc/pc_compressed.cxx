/* The skeleton PC hss and PC h2 share (see pc_compressed.hpp). */
#include "pc_compressed.hpp"

#include <petsc/private/pcimpl.h>

/* The map from the matrix's rows to the PC's: the matrix's row r is mesh-order dof d (its own
   rows, or mesh order on a dense matrix), whose PC row is rows[d]. Empty when it is the
   identity. */
static std::vector<PetscInt> RowMap_Private(const HssbemSystemContext &p, std::vector<PetscInt> rows)
{
  if (!p.system_of_dof.empty()) {
    std::vector<PetscInt> map(rows.size());
    for (std::size_t d = 0; d < rows.size(); ++d) map[(std::size_t)p.system_of_dof[d]] = rows[d];
    rows.swap(map);
  }
  for (std::size_t r = 0; r < rows.size(); ++r)
    if (rows[r] != (PetscInt)r) return rows;
  return {};
}

/* The scatter to the PC's rows and its vectors go; with `all`, the layout too. */
static PetscErrorCode ResetSkeleton_Private(PC_Compressed *c, bool all)
{
  PetscFunctionBegin;
  PetscCall(VecScatterDestroy(&c->scatter));
  PetscCall(VecDestroy(&c->xs));
  PetscCall(VecDestroy(&c->ys));
  if (!all) PetscFunctionReturn(PETSC_SUCCESS);
  c->own_layout.reset();
  c->layout = nullptr;
  c->system = nullptr;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCSetUp_Compressed(PC pc)
{
  PC_Compressed        *c = (PC_Compressed *)pc->data;
  const char           *what = c->what;
  HssbemSystemContext  *p;
  MPI_Comm              comm = PetscObjectComm((PetscObject)pc);
  HssbemGuard           guard;
  std::vector<PetscInt> map;
  PetscInt              local = 0;
  PetscMPIInt           remap;
  Vec                   x;

  PetscFunctionBegin;
  PetscCall(HssbemMatGetSystemContext(pc->pmat, &p));
  PetscCheck(p, comm, PETSC_ERR_ARG_WRONG, "%s factors BEM system matrices only: build the matrix with HssbemCreateSystem() (the hssbem driver does)", what);
  c->fresh = c->system != p;
  PetscCall(ResetSkeleton_Private(c, c->fresh));
  c->system = p;
  if (p->layout) c->layout = p->layout.get();
  else if (!c->own_layout) {
    PetscCall(HssbemLayoutCreate(comm, *p->op, &c->own_layout));
    c->layout = c->own_layout.get();
  }
  c->failure.clear();
  guard.Run([&] {
    hssbem::collectively(*c->layout->comm, [] { hssbem::fault_point("PCSetUp"); }); /* every step is collective */
    const hssbem::DistributedBemSystem &s = c->Factor(*p, *c->layout);
    hssbem::collectively(*c->layout->comm, [&] {
      map   = RowMap_Private(*p, HssbemSystemRows(s.tree()));
      local = 3 * (PetscInt)s.num_points();
    });
  });
  hssbem::fault_end("PCSetUp");
  PetscCall(guard.Check(comm, (std::string(what) + " set-up").c_str()));
  if (!c->failure.empty()) { /* the factorizations agree on a breakdown: every rank has it */
    PetscCall(PetscInfo(pc, "%s: the factorization broke down: %s\n", what, c->failure.c_str()));
    PetscCall(PCSetFailedReason(pc, PC_FACTOR_NUMERIC_ZEROPIVOT));
  }
  remap = !map.empty(); /* the PC's rows are not the matrix's (on some rank) */
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &remap, 1, MPI_INT, MPI_MAX, comm));
  if (!remap) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(MatCreateVecs(pc->pmat, &x, NULL));
  PetscCall(VecCreateMPI(comm, local, PETSC_DETERMINE, &c->xs));
  PetscCall(VecDuplicate(c->xs, &c->ys));
  PetscCall(HssbemRowScatterCreate(x, c->xs, map, &c->scatter));
  PetscCall(VecDestroy(&x));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCApply_Compressed(PC pc, Vec x, Vec y)
{
  PC_Compressed     *c = (PC_Compressed *)pc->data;
  HssbemGuard        guard;
  PCFailedReason     reason;
  const PetscScalar *xa;
  PetscScalar       *ya;

  PetscFunctionBegin;
  PetscCall(PCGetFailedReason(pc, &reason));
  if (reason) { /* a failed factorization: tell the Krylov method, do not crash */
    PetscCall(VecSetInf(y));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  Vec in = x, out = y;
  if (c->scatter) {
    PetscCall(VecScatterBegin(c->scatter, x, c->xs, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecScatterEnd(c->scatter, x, c->xs, INSERT_VALUES, SCATTER_FORWARD));
    in  = c->xs;
    out = c->ys;
  }
  PetscCall(VecGetArrayRead(in, &xa));
  PetscCall(VecGetArrayWrite(out, &ya));
  guard.Run([&] {
    hssbem::collectively(*c->layout->comm, [] { hssbem::fault_point("PCApply"); }); /* the ranks meet in the solve's exchanges */
    c->Solve(xa, ya);
  });
  PetscCall(VecRestoreArrayRead(in, &xa));
  PetscCall(VecRestoreArrayWrite(out, &ya));
  PetscCall(guard.Check(PetscObjectComm((PetscObject)pc), c->what));
  if (c->scatter) {
    PetscCall(VecScatterBegin(c->scatter, c->ys, y, INSERT_VALUES, SCATTER_REVERSE));
    PetscCall(VecScatterEnd(c->scatter, c->ys, y, INSERT_VALUES, SCATTER_REVERSE));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCReset_Compressed(PC pc)
{
  PC_Compressed *c = (PC_Compressed *)pc->data;

  PetscFunctionBegin;
  c->Drop();
  PetscCall(ResetSkeleton_Private(c, true));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCDestroy_Compressed(PC pc)
{
  PetscFunctionBegin;
  PetscCall(PCReset_Compressed(pc));
  delete (PC_Compressed *)pc->data;
  pc->data = NULL;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCCompressedCreate(PC pc, PC_Compressed *c, PetscErrorCode (*setfromoptions)(PC, PetscOptionItems *), PetscErrorCode (*view)(PC, PetscViewer))
{
  PetscFunctionBegin;
  pc->data                = c;
  pc->ops->setup          = PCSetUp_Compressed;
  pc->ops->apply          = PCApply_Compressed;
  pc->ops->reset          = PCReset_Compressed;
  pc->ops->destroy        = PCDestroy_Compressed;
  pc->ops->setfromoptions = setfromoptions;
  pc->ops->view           = view;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCCompressedViewFailure(PetscViewer viewer, const PC_Compressed &c)
{
  PetscFunctionBegin;
  PetscCall(PetscViewerASCIIPrintf(viewer, "factorization failed: %s\n", c.failure.c_str()));
  PetscFunctionReturn(PETSC_SUCCESS);
}
