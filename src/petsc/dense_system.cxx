#include "hssbem/petsc/dense.h"
#include "hssbem/petsc/pc_hss.h"
#include "hssbem/petsc/system.h"
#include "hssbem/petsc/log.h"
#include "hssbem/bem/rigid_modes.hpp"

#include "problem_context.hpp"

#include <algorithm>
#include <exception>
#include <string>
#include <numeric>
#include <vector>

/* rows(r, :) += c Q(row0 + r, :) Q^T for nrows rows of width N (row-major). */
static void AddRigidRegularization_Private(const std::vector<double> &Q, PetscInt row0, size_t nrows, PetscInt N, double *rows)
{
  const double c = hssbem::rigid_regularization_weight;
  for (size_t r = 0; r < nrows; ++r) {
    const double *q = &Q[(row0 + r) * 6];
    for (PetscInt j = 0; j < N; ++j) {
      const double *qj = &Q[(size_t)j * 6];
      rows[r * N + j] += c * (q[0] * qj[0] + q[1] * qj[1] + q[2] * qj[2] + q[3] * qj[3] + q[4] * qj[4] + q[5] * qj[5]);
    }
  }
}

/* Rows [nstart, nstart + nlocal) (nodes) into the column-major local block a (3 nlocal x 3 nn) and
   rhs. Chunks of rows are independent: threads share them, each with its own operator workspace. */
static PetscErrorCode FillLocalRows_Private(const hssbem::BemOperator &op, const hssbem::SystemSelection &sel, const std::vector<double> *rigid_modes, PetscInt nstart, PetscInt nlocal,
                                            PetscScalar *a, PetscScalar *rhs)
{
  const PetscInt nn = op.num_nodes(), N = 3 * nn, m = 3 * nlocal, chunk = 16;
  std::vector<int> J(nn);
  bool             failed = false;
  std::string      message;

  PetscFunctionBegin;
  std::iota(J.begin(), J.end(), 0);
#pragma omp parallel
  {
    hssbem::BemOperator::Workspace ws(op);
    std::vector<double>            rows(3 * chunk * (size_t)N);
#pragma omp for schedule(dynamic, 1)
    for (PetscInt r0 = 0; r0 < nlocal; r0 += chunk) {
      std::vector<int> I(std::min(chunk, nlocal - r0));
      std::iota(I.begin(), I.end(), (int)(nstart + r0));
      try { // no PETSc error handling inside the parallel region: remember and report after it
        hssbem::fill_system_block(op, sel, I, J, rows.data(), N, rhs + 3 * r0, ws);
      } catch (const std::exception &e) {
#pragma omp critical
        {
          failed  = true;
          message = e.what();
        }
        continue;
      }
      if (rigid_modes) AddRigidRegularization_Private(*rigid_modes, 3 * (nstart + r0), 3 * I.size(), N, rows.data());
      for (PetscInt c = 0; c < N; ++c) // column-major destination: consecutive writes per column
        for (size_t r = 0; r < 3 * I.size(); ++r) a[(size_t)c * m + 3 * r0 + r] = rows[r * N + c];
    }
  }
  PetscCheck(!failed, PETSC_COMM_SELF, PETSC_ERR_LIB, "assembly failed: %s", message.c_str());
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemAssembleDense - Assembles the collocation matrix A and right-hand side b with the operator
  primitive; each rank fills its own rows (column-major local storage of MATDENSE).

  Level: intermediate
@*/
PetscErrorCode HssbemAssembleDense(MPI_Comm comm, const hssbem::BemOperator &op, const hssbem::SystemSelection &sel, const std::vector<double> *rigid_modes, Mat *A, Vec *b)
{
  const PetscInt nn = op.num_nodes(), N = 3 * nn;
  PetscInt       nstart = 0, nlocal = 0;
  PetscScalar   *a, *rhs;

  PetscFunctionBegin;
  PetscCall(PetscLogEventBegin(BEM_Assembly, 0, 0, 0, 0));
  PetscCall(HssbemOwnedNodes(comm, nn, &nstart, &nlocal));
  PetscCall(MatCreateDense(comm, 3 * nlocal, 3 * nlocal, N, N, NULL, A));
  PetscCall(MatSetBlockSize(*A, 3));
  PetscCall(MatCreateVecs(*A, NULL, b));
  PetscCall(MatDenseGetArrayWrite(*A, &a));
  PetscCall(VecGetArrayWrite(*b, &rhs));
  PetscCall(FillLocalRows_Private(op, sel, rigid_modes, nstart, nlocal, a, rhs));
  PetscCall(VecRestoreArrayWrite(*b, &rhs));
  PetscCall(MatDenseRestoreArrayWrite(*A, &a));
  PetscCall(MatAssemblyBegin(*A, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*A, MAT_FINAL_ASSEMBLY));
  PetscCall(PetscLogFlops(0.0));
  PetscCall(PetscLogEventEnd(BEM_Assembly, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The format the factorization needs: MATDENSE LU works on one rank only, parallel dense LU is
   ScaLAPACK's, and MUMPS takes AIJ. Krylov methods with point preconditioners keep MATDENSE. */
static PetscErrorCode FactorMatType_Private(KSP ksp, Mat A, MatType *type)
{
  char        solver[64] = "";
  PetscBool   set;
  PetscMPIInt size;
  PC          pc;
  PCType      pctype;

  PetscFunctionBegin;
  *type = NULL;
  PetscCallMPI(MPI_Comm_size(PetscObjectComm((PetscObject)A), &size));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PCGetType(pc, &pctype));
  PetscCall(PetscOptionsGetString(NULL, NULL, "-pc_factor_mat_solver_type", solver, sizeof(solver), &set));
  const std::string pct(pctype ? pctype : ""), st(solver);
  if (pct != PCLU && pct != PCCHOLESKY && pct != PCILU) PetscFunctionReturn(PETSC_SUCCESS);
  {
    PetscBool compressed;
    PetscCall(HssbemMatIsCompressed(A, &compressed));
    PetscCheck(!compressed, PetscObjectComm((PetscObject)A), PETSC_ERR_ARG_INCOMP, "the compressed (HSS or H2) matrix has no entries for -pc_type %s: use -pc_type hss, or -bem_mat_type dense", pct.c_str());
  }
  if (st == "mumps" || st == "superlu_dist") *type = MATAIJ;
  else if (st == "scalapack" || (st.empty() && size > 1)) *type = MATSCALAPACK;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* to := from, for vectors with the same global size and different layouts (ScaLAPACK picks its own). */
static PetscErrorCode CopyAcrossLayouts_Private(Vec from, Vec to)
{
  PetscInt   lo, hi;
  IS         is;
  VecScatter sc;

  PetscFunctionBegin;
  PetscCall(VecGetOwnershipRange(to, &lo, &hi));
  PetscCall(ISCreateStride(PetscObjectComm((PetscObject)to), hi - lo, lo, 1, &is));
  PetscCall(VecScatterCreate(from, is, to, NULL, &sc));
  PetscCall(VecScatterBegin(sc, from, to, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(sc, from, to, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterDestroy(&sc));
  PetscCall(ISDestroy(&is));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Solve with vectors in the operator's layout (ScaLAPACK picks its own), copying in and out;
   the relative residual ||b - A x|| / ||b|| is measured there too. */
static PetscErrorCode KSPSolveInLayout_Private(KSP ksp, Mat op, Vec b, Vec x, PetscReal *residual)
{
  Vec       bo, xo, r;
  PetscReal bnorm, rnorm;

  PetscFunctionBegin;
  PetscCall(MatCreateVecs(op, &xo, &bo));
  PetscCall(CopyAcrossLayouts_Private(b, bo));
  PetscCall(KSPSolve(ksp, bo, xo));
  PetscCall(CopyAcrossLayouts_Private(xo, x));
  PetscCall(VecDuplicate(bo, &r));
  PetscCall(MatMult(op, xo, r));
  PetscCall(VecAYPX(r, -1.0, bo));
  PetscCall(VecNorm(r, NORM_2, &rnorm));
  PetscCall(VecNorm(bo, NORM_2, &bnorm));
  *residual = bnorm > 0 ? rnorm / bnorm : rnorm;
  PetscCall(VecDestroy(&r));
  PetscCall(VecDestroy(&bo));
  PetscCall(VecDestroy(&xo));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemKSPCreate - Creates the main solver (no prefix) with the defaults of the matrix type
  (-ksp_type preonly with -pc_type hss on the HSS matrix, GMRES(100) with -pc_type jacobi and
  -ksp_rtol 1e-8 on the H² one, -pc_type lu on the dense one) and applies
  the options database, before there is a matrix, so that option errors surface before the
  expensive assembly.

  Level: intermediate
@*/
PetscErrorCode HssbemKSPCreate(MPI_Comm comm, const char *mat_type, KSP *ksp)
{
  PC        pc;
  PetscBool hss, h2;

  PetscFunctionBegin;
  PetscCall(PetscStrcmp(mat_type, HSSBEM_MAT_HSS, &hss));
  PetscCall(PetscStrcmp(mat_type, HSSBEM_MAT_H2, &h2));
  PetscCall(KSPCreate(comm, ksp));
  PetscCall(KSPSetType(*ksp, h2 ? KSPGMRES : KSPPREONLY));
  if (h2) {
    PetscCall(KSPGMRESSetRestart(*ksp, 100));
    PetscCall(KSPSetTolerances(*ksp, 1e-8, PETSC_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT));
  }
  PetscCall(KSPGetPC(*ksp, &pc));
  PetscCall(PCSetType(pc, hss ? PCHSS : h2 ? PCJACOBI : PCLU));
  PetscCall(KSPSetFromOptions(*ksp));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemSolveSystem - Solves A x = b with a KSP from HssbemKSPCreate(); a dense A is converted in
  place to the format its factorization needs (so no second copy stays alive). A diverged solve
  is an error.

  Level: intermediate
@*/
PetscErrorCode HssbemSolveSystem(KSP ksp, Mat *A, Vec b, Vec x, HssbemSolveInfo *info)
{
  PC            pc;
  MatType       ftype;
  MatSolverType st = NULL;

  PetscFunctionBegin;
  PetscCall(PetscLogEventBegin(BEM_Solve, 0, 0, 0, 0));
  PetscCall(FactorMatType_Private(ksp, *A, &ftype));
  if (ftype) PetscCall(MatConvert(*A, ftype, MAT_INPLACE_MATRIX, A));
  PetscCall(KSPSetOperators(ksp, *A, *A));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(KSPSolveInLayout_Private(ksp, *A, b, x, &info->residual));
  PetscCall(KSPGetConvergedReason(ksp, &info->reason));
  PetscCall(KSPGetIterationNumber(ksp, &info->iterations));
  {
    KSPType kt;
    PCType  pt;
    PetscCall(KSPGetType(ksp, &kt));
    PetscCall(PCGetType(pc, &pt));
    info->ksp_type = kt;
    info->pc_type  = pt;
  }
  PetscCall(PCFactorGetMatSolverType(pc, &st));
  info->solver_type = st ? st : "";
  PetscCall(PetscLogEventEnd(BEM_Solve, 0, 0, 0, 0));
  PetscCheck(info->reason > 0, PetscObjectComm((PetscObject)*A), PETSC_ERR_NOT_CONVERGED, "the linear solve failed: %s after %" PetscInt_FMT " iterations", KSPConvergedReasons[info->reason], info->iterations);
  PetscFunctionReturn(PETSC_SUCCESS);
}
