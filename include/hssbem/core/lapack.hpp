/// \file lapack.hpp
/// The few BLAS/LAPACK routines the core calls (Fortran ABI, 32-bit integers as in Debian's
/// reference and OpenBLAS builds). The core does not go through PETSc for them.
#pragma once

extern "C" {
void dsyev_(const char *jobz, const char *uplo, const int *n, double *a, const int *lda, double *w, double *work, const int *lwork, int *info);
void dgesv_(const int *n, const int *nrhs, double *a, const int *lda, int *ipiv, double *b, const int *ldb, int *info);
}

namespace hssbem::lapack {

/// Eigenvalues (ascending, in w) and eigenvectors (columns of a, column-major) of a symmetric n×n.
int syev(int n, double *a, double *w);
/// Solve A X = B in place (column-major); returns LAPACK's info.
int gesv(int n, int nrhs, double *a, double *b);

} // namespace hssbem::lapack
