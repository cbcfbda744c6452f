/* PETSc's GMRES behind hssbem::KrylovSolver (see krylov.h). */
#include "hssbem/petsc/krylov.h"

#include <petscksp.h>

#include <stdexcept>
#include <string>

namespace {

struct Callbacks {
  const std::function<void(const double *, double *)> *A, *M;
};

/* y = fn(x) on the arrays of x and y. */
PetscErrorCode ApplyCallback_Private(const std::function<void(const double *, double *)> &fn, Vec x, Vec y)
{
  const PetscScalar *in;
  PetscScalar       *out;

  PetscFunctionBegin;
  PetscCall(VecGetArrayRead(x, &in));
  PetscCall(VecGetArrayWrite(y, &out));
  PetscCallCXX(fn(in, out));
  PetscCall(VecRestoreArrayWrite(y, &out));
  PetscCall(VecRestoreArrayRead(x, &in));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode MatMult_SceneKrylov(Mat A, Vec x, Vec y)
{
  Callbacks *cb;

  PetscFunctionBegin;
  PetscCall(MatShellGetContext(A, &cb));
  PetscCall(ApplyCallback_Private(*cb->A, x, y));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCApply_SceneKrylov(PC pc, Vec x, Vec y)
{
  Callbacks *cb;

  PetscFunctionBegin;
  PetscCall(PCShellGetContext(pc, &cb));
  PetscCall(ApplyCallback_Private(*cb->M, x, y));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* What a solve is set up with. */
struct Setup {
  std::string prefix;
  int         restart;
};

PetscErrorCode Solve_Private(const Setup &setup, int n, Callbacks *cb, const double *b, double *x, double rtol, int max_it, PetscInt *its, KSPConvergedReason *reason)
{
  Mat A;
  KSP ksp;
  PC  pc;
  Vec vb, vx;

  PetscFunctionBegin;
  PetscCall(MatCreateShell(PETSC_COMM_SELF, n, n, n, n, cb, &A));
  PetscCall(MatShellSetOperation(A, MATOP_MULT, (void (*)(void))MatMult_SceneKrylov));
  PetscCall(VecCreateSeqWithArray(PETSC_COMM_SELF, 1, n, b, &vb));
  PetscCall(VecCreateSeqWithArray(PETSC_COMM_SELF, 1, n, x, &vx));
  PetscCall(KSPCreate(PETSC_COMM_SELF, &ksp));
  PetscCall(KSPSetOptionsPrefix(ksp, setup.prefix.c_str()));
  PetscCall(KSPSetType(ksp, KSPGMRES));
  PetscCall(KSPGMRESSetRestart(ksp, setup.restart));
  PetscCall(KSPSetPCSide(ksp, PC_RIGHT));
  PetscCall(KSPSetTolerances(ksp, rtol, PETSC_DEFAULT, PETSC_DEFAULT, max_it));
  PetscCall(KSPSetInitialGuessNonzero(ksp, PETSC_TRUE));
  PetscCall(KSPSetOperators(ksp, A, A));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PCSetType(pc, PCSHELL));
  PetscCall(PCShellSetContext(pc, cb));
  PetscCall(PCShellSetApply(pc, PCApply_SceneKrylov));
  PetscCall(KSPSetFromOptions(ksp));
  PetscCall(KSPSolve(ksp, vb, vx));
  PetscCall(KSPGetIterationNumber(ksp, its));
  PetscCall(KSPGetConvergedReason(ksp, reason));
  PetscCall(KSPDestroy(&ksp));
  PetscCall(VecDestroy(&vb));
  PetscCall(VecDestroy(&vx));
  PetscCall(MatDestroy(&A));
  PetscFunctionReturn(PETSC_SUCCESS);
}

class PetscGmres : public hssbem::KrylovSolver {
public:
  PetscGmres(const char *prefix, int restart, const char *what) : m_setup{prefix ? prefix : "", restart}, m_what(what) {}
  long long solve(int n, const std::function<void(const double *, double *)> &apply_A, const std::function<void(const double *, double *)> &apply_M, const double *b,
                  double *x, double rtol, int max_it) override
  {
    Callbacks          cb{&apply_A, &apply_M};
    PetscInt           its    = 0;
    KSPConvergedReason reason = KSP_CONVERGED_ITERATING;
    const PetscErrorCode ierr = Solve_Private(m_setup, n, &cb, b, x, rtol, max_it, &its, &reason);
    if (ierr) {
      const char *text = nullptr;
      PetscErrorMessage(ierr, &text, NULL);
      throw std::runtime_error(m_what + ": GMRES failed: " + (text ? text : "PETSc error"));
    }
    if (reason < 0) throw std::runtime_error(m_what + ": GMRES did not converge: " + KSPConvergedReasons[reason] + " after " + std::to_string(its) + " iterations");
    return its;
  }

private:
  Setup       m_setup;
  std::string m_what;
};

} // namespace

std::unique_ptr<hssbem::KrylovSolver> HssbemKrylovCreate(const char *prefix, int restart, const char *what)
{
  return std::make_unique<PetscGmres>(prefix, restart, what);
}

std::unique_ptr<hssbem::KrylovSolver> HssbemSceneKrylovCreate(void)
{
  return HssbemKrylovCreate("scene_", HSSBEM_SCENE_KRYLOV_RESTART, "scene frame");
}

std::unique_ptr<hssbem::KrylovSolver> HssbemH2ReferenceKrylovCreate(void)
{
  return HssbemKrylovCreate("contact_h2_", HSSBEM_H2_REFERENCE_KRYLOV_RESTART, "H2 reference");
}
