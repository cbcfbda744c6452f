/* The collocation system of a BEM problem as PETSc objects: the matrix A (dense, or a MatShell
   backed by the HSS or the H² engine) and the right-hand side b. The public entry point of the
   library for programs that run their own KSP (see examples/). */
#pragma once

#include "hssbem/petsc/compat.h"

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/core/size_limits.hpp"
#include "hssbem/h2/h2_compression.hpp"
#include "hssbem/hss/hss_compression.hpp"

#include <petscksp.h>
#include <string>
#include <vector>

/* Operator representations, for -bem_mat_type, HssbemCreateSystem() and HssbemKSPCreate(): the
   names of hssbem::OperatorType (core/operator_type.hpp); any other mat_type is an error. */
#define HSSBEM_MAT_HSS   "hss"
#define HSSBEM_MAT_DENSE "dense"
#define HSSBEM_MAT_H2    "h2"

/* Assemble A and b = Σ_known (−H u + G t) of the pattern `sel` on comm (3 rows per dof node, block
   size 3): for HSSBEM_MAT_DENSE a MATDENSE filled row by row with the operator primitive (nodes
   split in contiguous blocks across the ranks); for HSSBEM_MAT_HSS and HSSBEM_MAT_H2 a MatShell
   (MatMult, MatGetDiagonal, MatView) over the HSS or H² compression of K = [H, G] made with the
   -mat_hss_* or -mat_h2_* options, distributed by a METIS partition of the surface, one part per
   rank (rows in cluster order, see below). With rigid_modes (orthonormal, row-major 3N × 6, see
   orthonormal_rigid_modes()), A gets + rigid_regularization_weight · Q Qᵀ (pure-traction
   problems). Every such matrix carries the system (operator, pattern, modes), so PC hss and
   PC h2 can factor it (docs/performance.md, "Choosing the operator"). op must outlive A. */
PetscErrorCode HssbemCreateSystem(MPI_Comm comm, const hssbem::BemOperator &op, const hssbem::SystemSelection &sel, const std::vector<double> *rigid_modes, const char *mat_type, Mat *A,
                                  Vec *b);

/* The rows of HssbemCreateSystem()'s A, b and solution: mesh order (3 per dof node, nodes split in
   contiguous blocks) for the dense system and the compressed ones on one rank; on several ranks
   the H² and HSS systems are distributed by a METIS partition of the surface and their rows are
   in cluster order, rank p holding part p's nodes. These convert either way between A's layout and
   a mesh-order vector from HssbemMatCreateMeshOrderVec() (a copy when A is in mesh order). */
PetscErrorCode HssbemMatCreateMeshOrderVec(Mat A, Vec *y);
PetscErrorCode HssbemVecToMeshOrder(Mat A, Vec x, Vec y);
PetscErrorCode HssbemVecFromMeshOrder(Mat A, Vec y, Vec x);

/* The machine as the size check sees it (collective): the smallest node memory over the ranks
   (MemTotal, or the cgroup's memory.max when lower, or -hssbem_memory_limit <bytes> when given),
   the most ranks on one node, and PETSC_MAX_INT. HssbemCreateSystem() refuses a system that
   hssbem::size_refusal() says does not fit, before allocating it. */
PetscErrorCode HssbemMachineLimits(MPI_Comm comm, hssbem::MachineLimits *limits);

/* Read -<prefix>mat_hss_rel_tol, _leaf_size, _max_rank, _proxy_ratio, _proxy_points into opts
   (which holds the defaults on entry) and check them. */
PetscErrorCode HssbemHssOptionsFromDatabase(MPI_Comm comm, const char *prefix, hssbem::HssOptions *opts);

/* Read -<prefix>mat_h2_rel_tol, _leaf_size, _eta, _max_rank, _proxy_ratio, _proxy_points into
   opts (which holds the defaults on entry) and check them. */
PetscErrorCode HssbemH2OptionsFromDatabase(MPI_Comm comm, const char *prefix, hssbem::H2Options *opts);

/* PETSC_TRUE when A is a compressed MatShell (HSS or H²) of HssbemCreateSystem(): no entries. */
PetscErrorCode HssbemMatIsCompressed(Mat A, PetscBool *compressed);

/* Outcome of a solve, for the result file. */
struct HssbemSolveInfo {
  PetscInt           iterations = 0;
  PetscReal          residual   = 0; /* ||b - A x|| / ||b|| with A's own product */
  KSPConvergedReason reason     = KSP_CONVERGED_ITERATING;
  std::string        ksp_type, pc_type, solver_type;
};

/* The main KSP (no prefix) with the defaults of the matrix type, then the options database:
   preonly + PC hss (a direct HSS solve) for HSSBEM_MAT_HSS, GMRES(100) right-preconditioned by
   PC h2 at -ksp_rtol 1e-8 for HSSBEM_MAT_H2, preonly + LU for HSSBEM_MAT_DENSE. */
PetscErrorCode HssbemKSPCreate(MPI_Comm comm, const char *mat_type, KSP *ksp);

/* The largest true relative residual ||b - A x|| / ||b|| that HssbemSolveSystem() accepts as a
   solution by default (-hssbem_residual_max): the default solvers reach 1e-8 (GMRES, dense LU
   far below), a direct H² or HSS solve about its tolerance. */
#define HSSBEM_RESIDUAL_MAX 1e-4

/* Solve A x = b with that KSP. A dense A is converted in place when its factorization needs
   another format (ScaLAPACK for parallel LU, AIJ for MUMPS). A diverged solve is an error, and so
   is a solution whose true relative residual is not finite or exceeds -hssbem_residual_max, with
   any KSP (preonly included). */
PetscErrorCode HssbemSolveSystem(KSP ksp, Mat *A, Vec b, Vec x, HssbemSolveInfo *info);
