/* The dense path: the collocation matrix assembled into MATDENSE, each rank its own rows (see dense.h). */
#include "hssbem/petsc/dense.h"
#include "hssbem/petsc/log.h"
#include "hssbem/bem/rigid_modes.hpp"

#include "system_context.hpp"

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
