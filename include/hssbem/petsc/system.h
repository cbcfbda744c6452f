/* The collocation system of a BEM problem as PETSc objects: the matrix A (dense, or a MatShell
   backed by the HSS or the H² engine) and the right-hand side b. The public entry point of the
   library for programs that run their own KSP (see examples/). */
#pragma once

#include "hssbem/petsc/compat.h"

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/core/option_table.hpp"
#include "hssbem/core/size_limits.hpp"
#include "hssbem/h2/h2_compression.hpp"
#include "hssbem/h2/h2_system.hpp"
#include "hssbem/h2factor/h2_factorization.hpp"
#include "hssbem/hss/hss_compression.hpp"

#include <petscksp.h>
#include <functional>
#include <memory>
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

/* What HssbemCreateSystemWithOptions() builds with: the compressions' options and what the size
   check needs of the solver, typed (HssbemCreateSystem() reads them from the options database). */
struct HssbemSystemOptions {
  hssbem::H2Options            h2;               /* the H² operator's compression (pressure_columns follows sel) */
  hssbem::HssOptions           hss;              /* the HSS operator's */
  hssbem::SizeOptions          solver;           /* the solver's part of the size model (HssbemKSPGetSizeOptions()); its compression fields follow h2 and hss */
  const hssbem::MachineLimits *limits = nullptr; /* the machine of the size check (null: HssbemMachineLimits()) */
  /* When set, the H² operator's matrix is this function's instead of a compression (a saved one,
     session/h2_file.hpp): called on every rank, collectively, with the layout's partition (the
     part of each dof node) and its ranks. */
  std::function<std::shared_ptr<const hssbem::H2DistributedSystem>(const std::vector<int> &node_part, const hssbem::RankComm &comm)> h2_source;
};

/* HssbemCreateSystem() with the options given instead of read: the session layer reads the
   options once and hands them down. */
PetscErrorCode HssbemCreateSystemWithOptions(MPI_Comm comm, const hssbem::BemOperator &op, const hssbem::SystemSelection &sel, const std::vector<double> *rigid_modes, const char *mat_type,
                                             const HssbemSystemOptions &opts, Mat *A, Vec *b);

/* The rows of HssbemCreateSystem()'s A, b and solution: mesh order (3 per dof node, nodes split in
   contiguous blocks) for the dense system and the compressed ones on one rank; on several ranks
   the H² and HSS systems are distributed by a METIS partition of the surface and their rows are
   in cluster order, rank p holding part p's nodes. These convert either way between A's layout and
   a mesh-order vector from HssbemMatCreateMeshOrderVec() (a copy when A is in mesh order). */
PetscErrorCode HssbemMatCreateMeshOrderVec(Mat A, Vec *y);

/* The H² system behind A (every rank its part) and the layout's partition, or null (and an empty
   partition) when A is not the H² operator of HssbemCreateSystem(): what a save keeps. */
PetscErrorCode HssbemMatGetH2System(Mat A, std::shared_ptr<const hssbem::H2DistributedSystem> *sys, std::vector<int> *node_part);
PetscErrorCode HssbemVecToMeshOrder(Mat A, Vec x, Vec y);
PetscErrorCode HssbemVecFromMeshOrder(Mat A, Vec y, Vec x);

/* The machine as the size check sees it (collective): the smallest node memory over the ranks
   (MemTotal, or the cgroup's memory.max when lower, or -hssbem_memory_limit <bytes> when given),
   the most ranks on one node, and PETSC_MAX_INT. HssbemCreateSystem() refuses a system that
   hssbem::size_refusal() says does not fit, before allocating it. */
PetscErrorCode HssbemMachineLimits(MPI_Comm comm, hssbem::MachineLimits *limits);

/* Read -<prefix>mat_hss_rel_tol, _leaf_size, _max_rank, _proxy_ratio, _proxy_points into opts
   (which holds the values to keep where none is given) and check them against the table of
   options (core/option_table.def). */
PetscErrorCode HssbemHssOptionsFromDatabase(MPI_Comm comm, const char *prefix, hssbem::HssOptions *opts);

/* Read -<prefix>mat_h2_rel_tol, _leaf_size, _eta, _max_rank, _proxy_ratio, _proxy_points,
   _single_precision into opts (which holds the values to keep where none is given) and check them
   against the table of options. */
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
   preonly + PC hss (a direct HSS solve) for HSSBEM_MAT_HSS, GMRES right-preconditioned by PC h2
   for HSSBEM_MAT_H2 (restart and tolerance: the table's -ksp_gmres_restart and -ksp_rtol),
   preonly + LU for HSSBEM_MAT_DENSE. */
PetscErrorCode HssbemKSPCreate(MPI_Comm comm, const char *mat_type, KSP *ksp);

/* What the size model needs of that KSP's solver: the Krylov method's vectors (GMRES: restart +
   1; preonly: 0) and, when its PC is h2, that the matrix is factored and PC h2's options. */
PetscErrorCode HssbemKSPGetSizeOptions(KSP ksp, hssbem::SizeOptions *o);

/* The options that KSP and its PC use, named as in the table of options: ksp_type, pc_type, and
   ksp_rtol and ksp_gmres_restart with GMRES, -pc_h2_* with PC h2, -pc_hss_* with PC hss. */
PetscErrorCode HssbemKSPGetOptionValues(KSP ksp, hssbem::OptionValues *values);

/* The options a PC h2 (a PC hss) holds, named as in the table; nothing for another PC. */
PetscErrorCode HssbemPCH2GetOptionValues(PC pc, hssbem::OptionValues *values);
PetscErrorCode HssbemPCHSSGetOptionValues(PC pc, hssbem::OptionValues *values);
/* A PC h2's factorization options (*is_h2: pc is one; else o is left alone). */
PetscErrorCode HssbemPCH2GetFactorOptions(PC pc, hssbem::H2FactorOptions *o, PetscBool *is_h2);

/* The largest true relative residual ||b - A x|| / ||b|| that HssbemSolveSystem() accepts as a
   solution by default (-hssbem_residual_max's default, core/option_table.def): the default
   solvers reach far below (GMRES to -ksp_rtol, dense LU), a direct H² or HSS solve about its
   tolerance. */
#define HSSBEM_RESIDUAL_MAX (hssbem::option_default::hssbem_residual_max)

/* Solve A x = b with that KSP. A dense A is converted in place when its factorization needs
   another format (ScaLAPACK for parallel LU, AIJ for MUMPS). A diverged solve is an error, and so
   is a solution whose true relative residual is not finite or exceeds -hssbem_residual_max, with
   any KSP (preonly included). */
PetscErrorCode HssbemSolveSystem(KSP ksp, Mat *A, Vec b, Vec x, HssbemSolveInfo *info);
