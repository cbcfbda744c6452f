/* The dense path: the collocation matrix assembled into MATDENSE, each rank its own rows (see dense.h). */
#include "hssbem/petsc/dense.h"
#include "hssbem/petsc/log.h"
#include "hssbem/bem/rigid_modes.hpp"

#include "system_context.hpp"

#include <algorithm>
#include <exception>
#include <memory>
#include <new>
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
   rhs. Chunks of rows are independent: threads share them, each with its own operator workspace.
   Throws what the operator throws (no PETSc error handling inside the parallel region: the
   first failure is kept and rethrown after it). With nlocal = 0 (more ranks than nodes) it does
   nothing. */
static void FillLocalRows_Private(const hssbem::BemOperator &op, const hssbem::SystemSelection &sel, const std::vector<double> *rigid_modes, PetscInt nstart, PetscInt nlocal,
                                  PetscScalar *a, PetscScalar *rhs)
{
  const PetscInt     nn = op.num_nodes(), N = 3 * nn, m = 3 * nlocal, chunk = 16;
  std::vector<int>   J(nn);
  std::exception_ptr failure;

  std::iota(J.begin(), J.end(), 0);
  auto keep = [&failure] {
#pragma omp critical(hssbem_dense_fill)
    if (!failure) failure = std::current_exception();
  };
#pragma omp parallel
  {
    std::unique_ptr<hssbem::BemOperator::Workspace> ws;
    std::vector<double>                             rows;
    try {
      ws = std::make_unique<hssbem::BemOperator::Workspace>(op);
      rows.resize(3 * chunk * (size_t)N);
    } catch (...) {
      keep();
    }
#pragma omp for schedule(dynamic, 1)
    for (PetscInt r0 = 0; r0 < nlocal; r0 += chunk) {
      if (!ws || rows.empty()) continue;
      try { // exceptions must not leave the worksharing loop: the first is kept and rethrown after the region
        std::vector<int> I(std::min(chunk, nlocal - r0));
        std::iota(I.begin(), I.end(), (int)(nstart + r0));
        hssbem::fill_system_block(op, sel, I, J, rows.data(), N, rhs + 3 * r0, *ws);
        if (rigid_modes) AddRigidRegularization_Private(*rigid_modes, 3 * (nstart + r0), 3 * I.size(), N, rows.data());
        for (PetscInt c = 0; c < N; ++c) // column-major destination: consecutive writes per column
          for (size_t r = 0; r < 3 * I.size(); ++r) a[(size_t)c * m + 3 * r0 + r] = rows[r * N + c];
      } catch (...) {
        keep();
      }
    }
  }
  if (failure) std::rethrow_exception(failure);
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
  HssbemGuard    guard;

  PetscFunctionBegin;
  PetscCall(PetscLogEventBegin(BEM_Assembly, 0, 0, 0, 0));
  PetscCall(HssbemOwnedNodes(comm, nn, &nstart, &nlocal));
  PetscCall(MatCreateDense(comm, 3 * nlocal, 3 * nlocal, N, N, NULL, A));
  PetscCall(MatSetBlockSize(*A, 3));
  PetscCall(MatCreateVecs(*A, NULL, b));
  PetscCall(MatDenseGetArrayWrite(*A, &a));
  PetscCall(VecGetArrayWrite(*b, &rhs));
  guard.Run("DenseAssembly", [&] { FillLocalRows_Private(op, sel, rigid_modes, nstart, nlocal, a, rhs); });
  PetscCall(VecRestoreArrayWrite(*b, &rhs));
  PetscCall(MatDenseRestoreArrayWrite(*A, &a));
  PetscCall(guard.Check(comm, "dense assembly")); /* before the collective assembly: a rank that failed alone must not leave the others waiting there */
  PetscCall(MatAssemblyBegin(*A, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*A, MAT_FINAL_ASSEMBLY));
  PetscCall(PetscLogFlops(0.0));
  PetscCall(PetscLogEventEnd(BEM_Assembly, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}
