// Solver configurations side by side on one problem, through the PETSc face: dense LU, the HSS
// direct solve, GMRES preconditioned by HSS factorizations at loose tolerances, and GMRES with
// -pc_type none / jacobi. One table row per configuration (CSV on stdout).
//
//   bench_ksp -mesh FILE [-matrix dense|hss|h2] [-direct_tol 1e-6] [-pc_tols 1e-2,1e-3,1e-4]
//             [-rtol 1e-10] [-max_it 300] [-skip none,jacobi] [-reference 1]
//
// -direct_tol 0 skips the HSS direct solve, -pc_tols none the HSS preconditioners, and
// -reference 0 the dense reference (then the error column is nan): for sizes past dense reach.
// The last line reports the peak resident memory of the process.
//
// Problem (as bench_hss): nodes below the median height clamped, the others loaded by a traction
// (0, 0, -1); E = 1, nu = 0.3. The Krylov runs use the -matrix operator: dense (exact entries,
// BLAS product), the HSS MatShell at -mat_hss_rel_tol (PC tolerances looser than that are
// truncated from it) or the H² MatShell at -mat_h2_rel_tol (the PCs compress HSS anew). Every run's error is measured against the dense LU solution.
#include "hssbem/core/operator_type.hpp"
#include "hssbem/petsc/log.h"
#include "hssbem/petsc/pc_hss.h"
#include "hssbem/petsc/system.h"
#include "hssbem/problem/benchmark_problem.hpp"

#include <petscksp.h>
#include <petsctime.h>

#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

using namespace hssbem;

static const char help[] = "Solver configurations side by side on one BEM problem.\n";

namespace {

struct Row {
  std::string name;
  PetscInt its = 0;
  KSPConvergedReason reason = KSP_CONVERGED_ITERATING;
  double setup = 0, solve = 0, error = 0;
};

/* Solve A x = b with the options under `prefix` (set by the caller); times of PCSetUp and KSPSolve. */
PetscErrorCode Run(Mat A, Vec b, Vec xref, const std::string &name, const std::string &prefix, Row *row, Vec *xout)
{
  KSP            ksp;
  Vec            x;
  PetscLogDouble t0, t1, t2;

  PetscFunctionBegin;
  row->name  = name;
  row->error = NAN;
  PetscCall(KSPCreate(PETSC_COMM_WORLD, &ksp));
  PetscCall(KSPSetOptionsPrefix(ksp, prefix.c_str()));
  PetscCall(KSPSetOperators(ksp, A, A));
  PetscCall(KSPSetFromOptions(ksp));
  PetscCall(VecDuplicate(b, &x));
  PetscCall(PetscTime(&t0));
  PetscCall(KSPSetUp(ksp));
  PetscCall(PetscTime(&t1));
  PetscCall(KSPSolve(ksp, b, x));
  PetscCall(PetscTime(&t2));
  PetscCall(KSPGetIterationNumber(ksp, &row->its));
  PetscCall(KSPGetConvergedReason(ksp, &row->reason));
  row->setup = t1 - t0;
  row->solve = t2 - t1;
  if (xref) {
    Vec       d;
    PetscReal nd, nr;
    PetscCall(VecDuplicate(x, &d));
    PetscCall(VecWAXPY(d, -1.0, xref, x));
    PetscCall(VecNorm(d, NORM_2, &nd));
    PetscCall(VecNorm(xref, NORM_2, &nr));
    row->error = nd / nr;
    PetscCall(VecDestroy(&d));
  }
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "%s,%" PetscInt_FMT ",%s,%.2f,%.2f,%.2e\n", name.c_str(), row->its, KSPConvergedReasons[row->reason], row->setup, row->solve, row->error));
  if (xout) *xout = x;
  else PetscCall(VecDestroy(&x));
  PetscCall(KSPDestroy(&ksp));
  PetscFunctionReturn(PETSC_SUCCESS);
}

std::vector<std::string> Split(const std::string &s)
{
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

} // namespace

int main(int argc, char **argv)
{
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(HssbemInitializePackage());
  {
    char      mesh_path[PETSC_MAX_PATH_LEN] = "", matrix[16] = "dense", tols[256] = "1e-2,1e-3,1e-4", skip[64] = "";
    PetscReal direct_tol = 1e-6, rtol = 1e-10;
    PetscInt  max_it = 300;
    PetscBool set, reference = PETSC_TRUE;
    PetscCall(PetscOptionsGetString(NULL, NULL, "-mesh", mesh_path, sizeof(mesh_path), &set));
    PetscCheck(set, PETSC_COMM_WORLD, PETSC_ERR_USER, "give -mesh FILE");
    PetscCall(PetscOptionsGetString(NULL, NULL, "-matrix", matrix, sizeof(matrix), NULL));
    PetscCall(PetscOptionsGetString(NULL, NULL, "-pc_tols", tols, sizeof(tols), NULL));
    PetscCall(PetscOptionsGetString(NULL, NULL, "-skip", skip, sizeof(skip), NULL));
    PetscCall(PetscOptionsGetReal(NULL, NULL, "-direct_tol", &direct_tol, NULL));
    PetscCall(PetscOptionsGetReal(NULL, NULL, "-rtol", &rtol, NULL));
    PetscCall(PetscOptionsGetInt(NULL, NULL, "-max_it", &max_it, NULL));
    PetscCall(PetscOptionsGetBool(NULL, NULL, "-reference", &reference, NULL));

    SurfaceMesh              mesh = read_mesh(mesh_path);
    std::vector<std::string> notices;
    validate_and_orient(mesh, notices);
    Discretization  disc(mesh, 40.0);
    BemOperator     op(disc, Material::from_young(1.0, 0.3));
    SystemSelection sel = clamped_lower_half(disc, {0, 0, -1});
    PetscLogDouble  t0, t1;

    Mat Ad = NULL, Ak = NULL;
    Vec bd = NULL, bk = NULL, xref = NULL;
    const std::optional<OperatorType> matrix_type = parse_operator_type(matrix);
    const bool                        hss_matrix  = matrix_type && is_compressed(*matrix_type);
    PetscCheck(reference || hss_matrix, PETSC_COMM_WORLD, PETSC_ERR_USER, "-reference 0 needs -matrix hss or h2");
    if (reference) {
      PetscCall(PetscTime(&t0));
      PetscCall(HssbemCreateSystem(PETSC_COMM_WORLD, op, sel, nullptr, HSSBEM_MAT_DENSE, &Ad, &bd));
      PetscCall(PetscTime(&t1));
      PetscCall(PetscPrintf(PETSC_COMM_WORLD, "# %s: %d unknowns; dense assembly %.2f s\n", mesh_path, 3 * disc.num_nodes(), t1 - t0));
    } else {
      PetscCall(PetscPrintf(PETSC_COMM_WORLD, "# %s: %d unknowns; no dense reference\n", mesh_path, 3 * disc.num_nodes()));
    }
    if (hss_matrix) {
      PetscCall(PetscTime(&t0));
      PetscCall(HssbemCreateSystem(PETSC_COMM_WORLD, op, sel, nullptr, matrix, &Ak, &bk));
      PetscCall(PetscTime(&t1));
      PetscCall(PetscPrintf(PETSC_COMM_WORLD, "# %s matrix (MatShell) compression %.2f s\n", matrix, t1 - t0));
      PetscCall(MatView(Ak, PETSC_VIEWER_STDOUT_WORLD));
    }
    PetscCall(PetscPrintf(PETSC_COMM_WORLD, "configuration,iterations,reason,setup_s,solve_s,error_vs_dense_lu\n"));
    Row row;
    if (reference) {
      PetscCall(PetscOptionsInsertString(NULL, "-lu_ksp_type preonly -lu_pc_type lu"));
      PetscCall(Run(Ad, bd, NULL, "dense LU", "lu_", &row, &xref));
    }
    Mat A = hss_matrix ? Ak : Ad;
    Vec b = reference ? bd : bk; /* the same right-hand side for every run: the exact one when there is a reference */
    char opts[256];
    if (direct_tol > 0) {
      PetscCall(PetscSNPrintf(opts, sizeof(opts), "-direct_ksp_type preonly -direct_pc_type hss -direct_pc_hss_rel_tol %g", (double)direct_tol));
      PetscCall(PetscOptionsInsertString(NULL, opts));
      PetscCall(Run(A, b, xref, "preonly + hss direct " + std::string(opts).substr(std::string(opts).rfind(' ') + 1), "direct_", &row, NULL));
    }
    int k = 0;
    for (const std::string &tol : Split(tols)) {
      if (tol == "none") continue;
      const std::string prefix = "g" + std::to_string(k++) + "_";
      PetscCall(PetscSNPrintf(opts, sizeof(opts), "-%sksp_type gmres -%sksp_rtol %g -%sksp_max_it %d -%sksp_gmres_restart 100 -%spc_type hss -%spc_hss_rel_tol %s", prefix.c_str(), prefix.c_str(),
                              (double)rtol, prefix.c_str(), (int)max_it, prefix.c_str(), prefix.c_str(), prefix.c_str(), tol.c_str()));
      PetscCall(PetscOptionsInsertString(NULL, opts));
      PetscCall(Run(A, b, xref, "gmres + hss " + tol, prefix, &row, NULL));
    }
    for (const char *pc : {"none", "jacobi"}) {
      if (std::string(skip).find(pc) != std::string::npos) continue;
      const std::string prefix = std::string(pc) + "_";
      PetscCall(PetscSNPrintf(opts, sizeof(opts), "-%sksp_type gmres -%sksp_rtol %g -%sksp_max_it %d -%sksp_gmres_restart 100 -%spc_type %s", prefix.c_str(), prefix.c_str(), (double)rtol, prefix.c_str(),
                              (int)max_it, prefix.c_str(), prefix.c_str(), pc));
      PetscCall(PetscOptionsInsertString(NULL, opts));
      PetscCall(Run(A, b, xref, std::string("gmres + ") + pc, prefix, &row, NULL));
    }
    {
      std::ifstream status("/proc/self/status");
      for (std::string line; std::getline(status, line);)
        if (line.rfind("VmHWM:", 0) == 0) PetscCall(PetscPrintf(PETSC_COMM_WORLD, "# peak resident memory %.0f MB (rank 0)\n", std::stod(line.substr(6)) / 1024.0));
    }
    PetscCall(VecDestroy(&xref));
    PetscCall(MatDestroy(&Ad));
    PetscCall(VecDestroy(&bd));
    PetscCall(MatDestroy(&Ak));
    PetscCall(VecDestroy(&bk));
  }
  PetscCall(PetscFinalize());
  return 0;
}
