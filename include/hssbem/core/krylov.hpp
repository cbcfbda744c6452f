/// \file krylov.hpp
/// A Krylov solve that an engine asks of the layer that has one (the PETSc face's GMRES,
/// petsc/krylov.h): solve A x = b with x holding the initial guess on entry, apply_A(in, out) the
/// operator and apply_M(in, out) the preconditioner (an approximate inverse, applied on the
/// right, so that rtol bounds the true relative residual ||b - A x|| / ||b||); returns the
/// iterations. Throws std::runtime_error when it does not converge within max_it. A scene's
/// krylov strategy and the H² reference's accurate solves take one.
#pragma once

#include <functional>

namespace hssbem {

struct KrylovSolver {
  virtual ~KrylovSolver() = default;
  virtual long long solve(int n, const std::function<void(const double *, double *)> &apply_A, const std::function<void(const double *, double *)> &apply_M,
                          const double *b, double *x, double rtol, int max_it) = 0;
};

} // namespace hssbem
