/// \file lapack.hpp
/// The few BLAS/LAPACK routines the core calls (Fortran ABI, 32-bit integers as in Debian's
/// reference and OpenBLAS builds). The core does not go through PETSc for them.
///
/// The hidden character-length arguments of the Fortran ABI are omitted throughout: every
/// character argument here is a single letter, which the routines read as such. Where PETSc's
/// petscblaslapack.h declares the same routine (dgemm_, dtrsm_), the declaration here matches it
/// exactly, so a translation unit may include both headers.
#pragma once

extern "C" {
void dgesvd_(const char *jobu, const char *jobvt, const int *m, const int *n, double *a, const int *lda, double *s, double *u, const int *ldu, double *vt, const int *ldvt, double *work, const int *lwork, int *info);
void dgesdd_(const char *jobz, const int *m, const int *n, double *a, const int *lda, double *s, double *u, const int *ldu, double *vt, const int *ldvt, double *work, const int *lwork, int *iwork, int *info);
void dsyev_(const char *jobz, const char *uplo, const int *n, double *a, const int *lda, double *w, double *work, const int *lwork, int *info);
void dgesv_(const int *n, const int *nrhs, double *a, const int *lda, int *ipiv, double *b, const int *ldb, int *info);
void dgeqp3_(const int *m, const int *n, double *a, const int *lda, int *jpvt, double *tau, double *work, const int *lwork, int *info);
void dtrsm_(const char *side, const char *uplo, const char *transa, const char *diag, const int *m, const int *n, const double *alpha, const double *a, const int *lda, double *b, const int *ldb);
void dgeqrf_(const int *m, const int *n, double *a, const int *lda, double *tau, double *work, const int *lwork, int *info);
void dgelqf_(const int *m, const int *n, double *a, const int *lda, double *tau, double *work, const int *lwork, int *info);
void dormqr_(const char *side, const char *trans, const int *m, const int *n, const int *k, const double *a, const int *lda, const double *tau, double *c, const int *ldc, double *work, const int *lwork, int *info);
void dormlq_(const char *side, const char *trans, const int *m, const int *n, const int *k, const double *a, const int *lda, const double *tau, double *c, const int *ldc, double *work, const int *lwork, int *info);
void dgetrf_(const int *m, const int *n, double *a, const int *lda, int *ipiv, int *info);
void dgetrs_(const char *trans, const int *n, const int *nrhs, const double *a, const int *lda, const int *ipiv, double *b, const int *ldb, int *info);
void dgemv_(const char *trans, const int *m, const int *n, const double *alpha, const double *a, const int *lda, const double *x, const int *incx, const double *beta, double *y, const int *incy);
void dgeqrt3_(const int *m, const int *n, double *a, const int *lda, double *t, const int *ldt, int *info);
void dlarfb_(const char *side, const char *trans, const char *direct, const char *storev, const int *m, const int *n, const int *k, const double *v, const int *ldv, const double *t, const int *ldt, double *c, const int *ldc, double *work, const int *ldwork);
void dsyrk_(const char *uplo, const char *trans, const int *n, const int *k, const double *alpha, const double *a, const int *lda, const double *beta, double *c, const int *ldc);
void dpstrf_(const char *uplo, const int *n, double *a, const int *lda, int *piv, int *rank, const double *tol, double *work, int *info);
void sgemm_(const char *transa, const char *transb, const int *m, const int *n, const int *k, const float *alpha, const float *a, const int *lda, const float *b, const int *ldb, const float *beta, float *c, const int *ldc);
void sgemv_(const char *trans, const int *m, const int *n, const float *alpha, const float *a, const int *lda, const float *x, const int *incx, const float *beta, float *y, const int *incy);
void sgetrf_(const int *m, const int *n, float *a, const int *lda, int *ipiv, int *info);
void sgetrs_(const char *trans, const int *n, const int *nrhs, const float *a, const int *lda, const int *ipiv, float *b, const int *ldb, int *info);
void dgetri_(const int *n, double *a, const int *lda, const int *ipiv, double *work, const int *lwork, int *info);
void sgetri_(const int *n, float *a, const int *lda, const int *ipiv, float *work, const int *lwork, int *info);
void dgemm_(const char *transa, const char *transb, const int *m, const int *n, const int *k, const double *alpha, const double *a, const int *lda, const double *b, const int *ldb, const double *beta, double *c, const int *ldc);
void dlaswp_(const int *n, double *a, const int *lda, const int *k1, const int *k2, const int *ipiv, const int *incx);
void dtrsv_(const char *uplo, const char *trans, const char *diag, const int *n, const double *a, const int *lda, double *x, const int *incx);
}

namespace hssbem::lapack {

/// Eigenvalues (ascending, in w) and eigenvectors (columns of a, column-major) of a symmetric n×n.
int syev(int n, double *a, double *w);
/// Thin SVD A = U diag(s) Vᵀ of the m×n matrix a (destroyed; column-major): s gets min(m, n)
/// singular values (descending), u m × min(m, n), vt min(m, n) × n (dgesvd 'S', 'S'). Returns info.
int gesvd(int m, int n, double *a, int lda, double *s, double *u, int ldu, double *vt, int ldvt);
/// The same by divide and conquer (dgesdd 'S'): several times faster for the vectors of a large
/// matrix; a is overwritten. Returns info.
int gesdd(int m, int n, double *a, int lda, double *s, double *u, int ldu, double *vt, int ldvt);
/// Solve A X = B in place (column-major); returns LAPACK's info.
int gesv(int n, int nrhs, double *a, double *b);

/// Column-pivoted QR A P = Q R of the m×n matrix a (column-major, leading dimension lda), in
/// place as dgeqp3 leaves it. jpvt (n entries) and tau (min(m,n) entries) are outputs; every
/// column is free (jpvt is zeroed here) and jpvt is 1-based, as LAPACK returns it. The workspace
/// is queried and allocated inside. Returns LAPACK's info.
int geqp3(int m, int n, double *a, int lda, int *jpvt, double *tau);
/// B ← alpha op(A)⁻¹ B (side 'L') or B ← alpha B op(A)⁻¹ (side 'R') with A triangular (dtrsm).
void trsm(char side, char uplo, char transa, char diag, int m, int n, double alpha, const double *a, int lda, double *b, int ldb);
/// The row interchanges of getrf's first k pivots (1-based) applied to the ncols columns of a (dlaswp).
void laswp(int ncols, double *a, int lda, int k, const int *piv);
/// x ← A⁻¹ x for a triangular n×n A (dtrsv, no transpose; diag 'U' for a unit diagonal).
void trsv(char uplo, char diag, int n, const double *a, int lda, double *x);
/// C ← alpha op(A) op(B) + beta C, C m×n, inner dimension k (dgemm).
void gemm(char transa, char transb, int m, int n, int k, double alpha, const double *a, int lda, const double *b, int ldb, double beta, double *c, int ldc);

/// C ← alpha Aᵀ A + beta C for the m×n matrix a (upper triangle of the n×n C; dsyrk 'U', 'T').
void syrk_t(int n, int m, double alpha, const double *a, int lda, double beta, double *c, int ldc);
/// Pivoted Cholesky Pᵀ A P = Uᵀ U (dpstrf 'U') of the n×n symmetric positive semidefinite a (upper
/// triangle), stopped once the largest remaining diagonal entry is ≤ tol; piv is 1-based, as
/// LAPACK returns it. Returns the rank (the number of rows of U computed).
int pstrf_upper(int n, double *a, int lda, int *piv, double tol);
/// QR (dgeqrf) of the m×n matrix a in place; tau gets min(m, n) entries. Returns info.
int geqrf(int m, int n, double *a, int lda, double *tau);
/// Recursive QR (dgeqrt3, level-3 BLAS throughout) of the m×n matrix a (m ≥ n) in place: R above
/// the diagonal, the reflectors V below it, and the n×n triangular factor of Q = I − V T Vᵀ in t.
/// Returns info.
int geqrt3(int m, int n, double *a, int lda, double *t, int ldt);
/// C ← Qᵀ C (trans 'T') or Q C (trans 'N') for Q = I − V T Vᵀ from geqrt3, C m×n, k reflectors
/// (dlarfb, side 'L', forward, columnwise; the workspace is allocated inside).
void larfb_left(char trans, int m, int n, int k, const double *v, int ldv, const double *t, int ldt, double *c, int ldc);
/// LQ (dgelqf) of the m×n matrix a in place; tau gets min(m, n) entries. Returns info.
int gelqf(int m, int n, double *a, int lda, double *tau);
/// C ← op(Q) C or C op(Q) with Q from geqrf (k reflectors stored in a). Returns info.
int ormqr(char side, char trans, int m, int n, int k, const double *a, int lda, const double *tau, double *c, int ldc);
/// C ← op(Q) C or C op(Q) with Q from gelqf (k reflectors stored in the rows of a). Returns info.
int ormlq(char side, char trans, int m, int n, int k, const double *a, int lda, const double *tau, double *c, int ldc);
/// LU with partial pivoting of the n×n matrix a (dgetrf); ipiv gets n entries. Returns info.
int getrf(int n, double *a, int lda, int *ipiv);
/// Solve with the factors of getrf: B ← op(A)⁻¹ B for nrhs columns. Returns info.
int getrs(char trans, int n, int nrhs, const double *a, int lda, const int *ipiv, double *b, int ldb);
/// The inverse from the factors of getrf, in place (dgetri: 4/3 n³ flops, against 2 n³ for getrs
/// on the identity). Returns info.
int getri(int n, double *a, int lda, const int *ipiv);
/// y ← alpha op(A) x + beta y with A m×n (dgemv); unit strides.
void gemv(char trans, int m, int n, double alpha, const double *a, int lda, const double *x, double beta, double *y);

/// Single-precision twins of gemm, gemv, getrf, getrs and getri (sgemm, sgemv, sgetrf, sgetrs, sgetri), for
/// mixed-precision code that refines in double (the scene's capacitance inverse).
void gemm(char transa, char transb, int m, int n, int k, float alpha, const float *a, int lda, const float *b, int ldb, float beta, float *c, int ldc);
void gemv(char trans, int m, int n, float alpha, const float *a, int lda, const float *x, float beta, float *y);
int getrf(int n, float *a, int lda, int *ipiv);
int getrs(char trans, int n, int nrhs, const float *a, int lda, const int *ipiv, float *b, int ldb);
int getri(int n, float *a, int lda, const int *ipiv);
} // namespace hssbem::lapack
