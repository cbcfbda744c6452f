// The H² factorization (PC h2) on one mesh: H² compression, factorization, GMRES(100) with it as
// a right preconditioner (or, with --mode direct, one solve with it), a second pattern refactored
// on the same compression, ||I - A F^-1|| by power iterations, and optionally dense assembly + LU
// of the same system in the same run. Prints one CSV row (see --header); levels on stderr.
//
//   bench_h2_factor --mesh FILE [--tol 1e-5] [--leaf 64] [--single 1] [--ftol 3e-3] [--fleaf 0]
//                   [--top 2000] [--mixed-top 4000] [--sketch 0] [--mode pc|direct] [--rtol 1e-8] [--refactor 1] [--ierr 3]
//                   [--dense 0|1] [--parts 1] [--header]
//
// Problem (as bench_h2): the nodes below the median height clamped, the others loaded by a
// traction (0, 0, -1); E = 1, nu = 0.3. The second pattern switches 30 % of the vertices (u known
// <-> t known). GMRES is right-preconditioned: its rtol bounds the true residual ||b - A x||/||b||
// with the H² product. Threads: OMP_NUM_THREADS (OpenMP and OpenBLAS). --parts P > 1: the tree's
// top levels are P METIS parts, eliminated separately as P ranks would (H2FactorOptions::
// within_parts), simulated in this one process.
#include "hssbem/bem/node_partition.hpp"
#include "hssbem/core/rank_comm.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/h2/h2_compression.hpp"
#include "hssbem/h2/h2_system.hpp"
#include "hssbem/h2factor/h2_factorization.hpp"
#include "hssbem/petsc/compat.h"
#include "hssbem/problem/benchmark_problem.hpp"

#include "bench_support.hpp"

#include <petscksp.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>

using namespace hssbem;

namespace {

struct Args {
  std::string mesh, mode = "pc";
  H2Options h2;
  H2FactorOptions factor;
  double rtol = 1e-8;
  int ierr = 3, parts = 1;
  bool refactor = true, dense = false, header = false;
};

Args parse(int argc, char **argv)
{
  Args a;
  a.h2.rel_tol = 1e-5;
  a.h2.single_precision = true;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    const auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument("missing value after " + k);
      return argv[++i];
    };
    if (k == "--mesh") a.mesh = next();
    else if (k == "--tol") a.h2.rel_tol = std::stod(next());
    else if (k == "--leaf") a.h2.leaf_size = std::stoi(next());
    else if (k == "--single") a.h2.single_precision = std::stoi(next()) != 0;
    else if (k == "--ftol") a.factor.rel_tol = std::stod(next());
    else if (k == "--fleaf") a.factor.leaf_size = std::stoi(next());
    else if (k == "--top") a.factor.top_size = std::stoi(next());
    else if (k == "--mixed-top") a.factor.single_top_from = std::stoi(next());
    else if (k == "--sketch") a.factor.sketch_columns = std::stoi(next());
    else if (k == "--mode") a.mode = next();
    else if (k == "--rtol") a.rtol = std::stod(next());
    else if (k == "--refactor") a.refactor = std::stoi(next()) != 0;
    else if (k == "--ierr") a.ierr = std::stoi(next());
    else if (k == "--dense") a.dense = std::stoi(next()) != 0;
    else if (k == "--parts") a.parts = std::stoi(next());
    else if (k == "--header") a.header = true;
    else throw std::invalid_argument("unknown argument " + k);
  }
  if (a.mode != "pc" && a.mode != "direct") throw std::invalid_argument("--mode is pc or direct");
  return a;
}

/// A x for the pattern, through the H² product (mesh order).
struct Shell {
  const H2BemSystem *sys;
  const SystemSelection *sel;
  const H2Factorization *F;
};

PetscErrorCode MatMult_Bench(Mat A, Vec x, Vec y)
{
  Shell *s;
  const PetscScalar *xa;
  PetscScalar *ya;
  PetscFunctionBeginUser;
  PetscCall(MatShellGetContext(A, &s));
  PetscCall(VecGetArrayRead(x, &xa));
  PetscCall(VecGetArrayWrite(y, &ya));
  s->sys->apply(*s->sel, xa, ya);
  PetscCall(VecRestoreArrayRead(x, &xa));
  PetscCall(VecRestoreArrayWrite(y, &ya));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PCApply_Bench(PC pc, Vec x, Vec y)
{
  Shell *s;
  const PetscScalar *xa;
  PetscScalar *ya;
  PetscFunctionBeginUser;
  PetscCall(PCShellGetContext(pc, &s));
  PetscCall(VecGetArrayRead(x, &xa));
  PetscCall(VecGetArrayWrite(y, &ya));
  solve_mesh_order(*s->F, xa, ya);
  PetscCall(VecRestoreArrayRead(x, &xa));
  PetscCall(VecRestoreArrayWrite(y, &ya));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/// GMRES(100), right-preconditioned by the factorization, to rtol: the solution and iterations.
PetscErrorCode gmres(Shell &s, const std::vector<double> &b, double rtol, std::vector<double> &x, PetscInt *its)
{
  const PetscInt N = static_cast<PetscInt>(b.size());
  Mat A;
  Vec vb, vx;
  KSP ksp;
  PC pc;
  KSPConvergedReason reason;
  PetscFunctionBeginUser;
  PetscCall(MatCreateShell(PETSC_COMM_SELF, N, N, N, N, &s, &A));
  PetscCall(MatShellSetOperation(A, MATOP_MULT, (void (*)(void))MatMult_Bench));
  x.assign(b.size(), 0.0);
  PetscCall(VecCreateSeqWithArray(PETSC_COMM_SELF, 1, N, b.data(), &vb));
  PetscCall(VecCreateSeqWithArray(PETSC_COMM_SELF, 1, N, x.data(), &vx));
  PetscCall(KSPCreate(PETSC_COMM_SELF, &ksp));
  PetscCall(KSPSetOperators(ksp, A, A));
  PetscCall(KSPSetType(ksp, KSPGMRES));
  PetscCall(KSPGMRESSetRestart(ksp, 100));
  PetscCall(KSPSetPCSide(ksp, PC_RIGHT));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PCSetType(pc, PCSHELL));
  PetscCall(PCShellSetContext(pc, &s));
  PetscCall(PCShellSetApply(pc, PCApply_Bench));
  PetscCall(KSPSetTolerances(ksp, rtol, PETSC_DEFAULT, PETSC_DEFAULT, 1000));
  PetscCall(KSPSolve(ksp, vb, vx));
  PetscCall(KSPGetIterationNumber(ksp, its));
  PetscCall(KSPGetConvergedReason(ksp, &reason));
  PetscCheck(reason > 0, PETSC_COMM_SELF, PETSC_ERR_NOT_CONVERGED, "GMRES did not converge: %s", KSPConvergedReasons[reason]);
  PetscCall(KSPDestroy(&ksp));
  PetscCall(VecDestroy(&vx));
  PetscCall(VecDestroy(&vb));
  PetscCall(MatDestroy(&A));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/// The pattern with 30 % of the vertices switched (all three components), reproducibly.
SystemSelection switched(const SystemSelection &sel)
{
  SystemSelection s = sel;
  std::mt19937 gen(30);
  std::bernoulli_distribution flip(0.3);
  for (auto &k : s.displacement_known)
    if (flip(gen)) k = {!k[0], !k[1], !k[2]};
  return s;
}

/// ||b - A x|| / ||b|| with the H² product.
double residual(const H2BemSystem &sys, const SystemSelection &sel, const std::vector<double> &x, const std::vector<double> &b)
{
  std::vector<double> ax(b.size());
  sys.apply(sel, x.data(), ax.data());
  return bench::rel_diff(ax, b);
}

void print_levels(const H2FactorStats &st)
{
  for (const H2FactorLevelStats &l : st.levels)
    std::fprintf(stderr, "level %d: %d boxes, %.0f unknowns per box (max %d) -> skeleton %.0f (max %d), %lld eliminated, %.1f MB, %.2f s; %lld cross blocks, %.1f MB\n", l.level, l.boxes,
                 l.mean_candidates, l.max_candidates, l.mean_rank, l.max_rank, l.eliminated, l.bytes / 1048576.0, l.seconds, l.cross_blocks, l.cross_bytes / 1048576.0);
  std::fprintf(stderr, "factorization %.2f s: sketch %.2f (p = %d), first boxes %.2f, skeletons %.2f, eliminations %.2f (thread-s), merges %.2f, top %.2f (%d unknowns%s); %.3g Schur flop; %.1f MB (%s panels), working blocks at most %.1f MB\n",
               st.seconds(), st.time_sketch, st.sketch_columns, st.time_init, st.time_skeleton, st.time_eliminate, st.time_merge, st.time_top, st.top_size, st.top_mixed ? ", single-precision LU refined in double" : st.top_single ? ", single-precision LU" : "", st.flops_schur, st.bytes / 1048576.0,
               st.single_panels ? "single" : "double", st.workspace_bytes / 1048576.0);
}

} // namespace

int main(int argc, char **argv)
{
  Args a;
  try {
    a = parse(argc, argv);
  } catch (const std::exception &e) {
    std::fprintf(stderr, "bench_h2_factor: %s\n", e.what());
    return 2;
  }
  if (a.header)
    std::printf("mesh,N,tol,leaf,ftol,fleaf,mode,compress_s,factor_s,sketch_s,solve_s,pc_apply_s,iterations,residual,refactor_s,inv_err,top,factor_mb,h2_mb,peak_rss_mb,"
                "dense_assembly_s,dense_lu_s,rel_diff\n");
  if (a.mesh.empty()) return a.header ? 0 : 2;
  PetscCall(PetscInitializeNoArguments());
  {
    SurfaceMesh mesh = read_mesh(a.mesh);
    std::vector<std::string> notices;
    validate_and_orient(mesh, notices);
    Discretization disc(mesh, 40.0);
    BemOperator op(disc, Material::from_young(1.0, 0.3));
    const SystemSelection sel = clamped_lower_half(disc, {0, 0, -1});
    Timer t;
    a.factor.within_parts = a.parts > 1;
    const H2BemSystem sys = a.parts > 1 ? H2BemSystem(compress_bem_operator_h2(op, a.h2, partition_nodes(disc, a.parts), SerialComm())) : H2BemSystem(op, a.h2);
    const double t_compress = t.seconds();
    const std::vector<double> b = sys.rhs(sel);
    H2FactorCache cache(sys.matrix());
    t.restart();
    const H2Factorization F(cache, sel, a.factor);
    const double t_factor = t.seconds();
    print_levels(F.stats());
    Shell shell{&sys, &sel, &F};
    std::vector<double> x(b.size());
    t.restart();
    solve_mesh_order(F, b.data(), x.data());
    const double t_apply = t.seconds();
    PetscInt its = 0;
    double t_solve = t_apply;
    if (a.mode == "pc") {
      t.restart();
      PetscCall(gmres(shell, b, a.rtol, x, &its));
      t_solve = t.seconds();
    }
    const double res = residual(sys, sel, x, b);
    std::vector<double> in_mesh(b.size()), out_mesh(b.size());
    const double inv_err = a.ierr > 0 ? estimate_inverse_error(
                                          F,
                                          [&](const double *in, double *out) { // cluster order, as F.solve()
                                            sys.matrix().tree().to_mesh_order(in, in_mesh.data(), 3);
                                            sys.apply(sel, in_mesh.data(), out_mesh.data());
                                            sys.matrix().tree().to_cluster_order(out_mesh.data(), out, 3);
                                          },
                                          a.ierr)
                                      : NAN;
    double t_refactor = NAN;
    if (a.refactor) {
      const SystemSelection sel2 = switched(sel);
      t.restart();
      const H2Factorization F2(cache, sel2, a.factor);
      t_refactor = t.seconds();
      std::fprintf(stderr, "second pattern (30%% of the vertices switched): refactored in %.2f s (sketch %.2f s)\n", t_refactor, F2.stats().time_sketch);
    }
    const double rss = bench::peak_rss_mb();
    std::fprintf(stderr, "solve: %s, %d iterations, %.2f s; one application %.3f s; H2 residual %.2e; ||I - A F^-1|| ~ %.2e\n", a.mode.c_str(), (int)its, t_solve, t_apply, res, inv_err);
    const bench::DenseFigures d = bench::dense_figures(a.dense, op, sel, x);
    const std::string name = a.mesh.substr(a.mesh.find_last_of('/') + 1);
    std::printf("%s,%d,%.0e,%d,%.0e,%d,%s,%.3f,%.3f,%.3f,%.3f,%.4f,%d,%.3e,%.3f,%.3e,%d,%.1f,%.1f,%.0f,%.3f,%.3f,%.3e\n", name.c_str(), 3 * op.num_nodes(), a.h2.rel_tol, a.h2.leaf_size,
                a.factor.rel_tol, a.factor.leaf_size, a.mode.c_str(), t_compress, t_factor, F.stats().time_sketch, t_solve, t_apply, (int)its, res, t_refactor, inv_err, F.stats().top_size,
                F.stats().bytes / 1048576.0, sys.matrix().stats().memory_bytes / 1048576.0, std::max(rss, bench::peak_rss_mb()), d.t_assembly, d.t_lu, d.rel_diff);
  }
  PetscCall(PetscFinalize());
  return 0;
}
