/* Private to the PETSc layer: the skeleton PC hss and PC h2 share. Each factors a distributed
   compression of the BEM system (the matrix's own, or one of its own on the matrix's partition;
   on a dense matrix, on a partition made for the PC): one path for every matrix and number of
   ranks. The skeleton owns the layout, the scatter between the matrix's rows and the PC's (when
   they differ), the guards of set-up and apply, and the breakdown's report. */
#pragma once

#include "system_context.hpp"

#include <petsc/private/pcimpl.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

struct PC_Compressed {
  const HssbemSystemContext    *system = nullptr;  /* the matrix's system at the last set-up */
  bool                          fresh  = true;     /* it changed then: nothing of before may be reused */
  std::unique_ptr<HssbemLayout> own_layout;        /* on a dense matrix: the PC's partition and ranks */
  const HssbemLayout           *layout = nullptr;
  VecScatter                    scatter = nullptr; /* the matrix's rows to the PC's, when they differ */
  Vec                           xs = nullptr, ys = nullptr;
  std::string                   failure; /* a breakdown on this rank (empty: none here) */
  bool                          broke   = false; /* a breakdown on some rank */
  double                        seconds_compress = 0, seconds_factor = 0;
};

/* The PC's work of a set-up on every rank, collective on the layout's ranks: make the
   compression and factor it, a breakdown in c->failure; returns the compression factored (whose
   rows the PC's vectors take). */
using PCCompressedFactor = std::function<const hssbem::DistributedBemSystem &(const HssbemSystemContext &p, const HssbemLayout &layout)>;

/* Set-up: the system of pc->pmat (refused unless HssbemCreateSystem() made it), its layout (on a
   dense matrix made once), factor() under the guard (fault site PCSetUp) with the error of any
   rank raised on every rank as "<what> set-up: ...", a breakdown on any rank reported on every
   rank (PC_FACTOR_NUMERIC_ZEROPIVOT), and the scatter to the PC's rows. */
PetscErrorCode PCCompressedSetUp(PC pc, PC_Compressed *c, const char *what, const PCCompressedFactor &factor);

/* Apply: y = F⁻¹ x through solve(b, x) on this rank's rows of the PC's compression (collective),
   under the guard (fault site PCApply); Inf after a failed set-up, so that KSP stops. */
PetscErrorCode PCCompressedApply(PC pc, PC_Compressed *c, Vec x, Vec y, const char *what, const std::function<void(const double *, double *)> &solve);

/* Reset: the scatter, its vectors and the layout go (the PC drops what it made on the layout first). */
PetscErrorCode PCCompressedReset(PC_Compressed *c);

/* The line of a failed set-up, in a view. */
PetscErrorCode PCCompressedViewFailure(PetscViewer viewer, const PC_Compressed &c);

/* set(data) when pc is of type `type` (Data its pc->data), else nothing: a setter of one PC type
   on a PC of another, as PetscTryMethod does. */
template <class Data, class Set>
PetscErrorCode PCCompressedSet(PC pc, const char *type, Set &&set)
{
  PetscBool match;

  PetscFunctionBegin;
  PetscCall(PetscObjectTypeCompare((PetscObject)pc, type, &match));
  if (match) set(*(Data *)pc->data);
  PetscFunctionReturn(PETSC_SUCCESS);
}
