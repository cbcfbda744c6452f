/* Private to the PETSc layer: the skeleton PC hss and PC h2 share (docs/distributed.md). It owns
   the layout, the scatter between the matrix's rows and the PC's (when they differ), the guards
   of set-up and apply, and the breakdown's report; each PC factors a distributed compression. */
#pragma once

#include "system_context.hpp"

#include <petsc/private/pcimpl.h>

#include <memory>
#include <string>
#include <vector>

/* The PC's data: the skeleton's state, and the hooks each PC fills in. */
struct PC_Compressed {
  explicit PC_Compressed(const char *name) : what(name) {}
  virtual ~PC_Compressed() = default;
  /* A set-up's work on every rank, collective on the layout's ranks: make the compression and
     factor it, a breakdown in `failure`; returns the compression factored (whose rows the PC's
     vectors take). */
  virtual const hssbem::DistributedBemSystem &Factor(const HssbemSystemContext &p, const HssbemLayout &layout) = 0;
  /* out = F⁻¹ b on this rank's rows of the PC's compression (collective). */
  virtual void Solve(const double *b, double *out) const = 0;
  /* Drop what the PC made on the layout (before the skeleton drops the layout). */
  virtual void Drop() = 0;

  const char                   *what;              /* "PC hss", "PC h2": the errors' prefix */
  const HssbemSystemContext    *system = nullptr;  /* the matrix's system at the last set-up */
  bool                          fresh  = true;     /* it changed then: nothing of before may be reused */
  std::unique_ptr<HssbemLayout> own_layout;        /* on a dense matrix: the PC's partition and ranks */
  const HssbemLayout           *layout = nullptr;
  VecScatter                    scatter = nullptr; /* the matrix's rows to the PC's, when they differ */
  Vec                           xs = nullptr, ys = nullptr;
  std::string                   failure; /* a breakdown, on every rank (empty: none) */
  double                        seconds_compress = 0, seconds_factor = 0;
};

/* The PC's operations, on pc->data a PC_Compressed.
   SetUp: the system of pc->pmat (refused unless HssbemCreateSystem() made it), its layout (on a
   dense matrix made once), Factor() under the guard (fault site PCSetUp) with the error of any
   rank raised on every rank as "<what> set-up: ...", a breakdown on any rank reported on every
   rank (PC_FACTOR_NUMERIC_ZEROPIVOT), and the scatter to the PC's rows.
   Apply: y = F⁻¹ x through Solve() under the guard (fault site PCApply); Inf after a failed
   set-up, so that KSP stops.
   Reset: Drop(), then the scatter, its vectors and the layout. Destroy: Reset, then the data. */
PetscErrorCode PCSetUp_Compressed(PC pc);
PetscErrorCode PCApply_Compressed(PC pc, Vec x, Vec y);
PetscErrorCode PCReset_Compressed(PC pc);
PetscErrorCode PCDestroy_Compressed(PC pc);

/* pc->data = c (owned by the PC from then on) and the PC's operations: the skeleton's, and the
   PC's own options and view. */
PetscErrorCode PCCompressedCreate(PC pc, PC_Compressed *c, PetscErrorCode (*setfromoptions)(PC, PetscOptionItems *), PetscErrorCode (*view)(PC, PetscViewer));

/* The line of a failed set-up, in a view. */
PetscErrorCode PCCompressedViewFailure(PetscViewer viewer, const PC_Compressed &c);

/* pc->data as the PC's own type. */
template <class Data>
Data *PCCompressedData(PC pc)
{
  return static_cast<Data *>((PC_Compressed *)pc->data);
}

/* set(data) when pc is of type `type` (Data its pc->data), else nothing: a setter of one PC type
   on a PC of another, as PetscTryMethod does. */
template <class Data, class Set>
PetscErrorCode PCCompressedSet(PC pc, const char *type, Set &&set)
{
  PetscBool match;

  PetscFunctionBegin;
  PetscCall(PetscObjectTypeCompare((PetscObject)pc, type, &match));
  if (match) set(*PCCompressedData<Data>(pc));
  PetscFunctionReturn(PETSC_SUCCESS);
}
