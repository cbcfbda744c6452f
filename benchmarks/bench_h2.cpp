// The H² path end to end on one mesh: compression of K = [H, G], GMRES(100) + Jacobi through
// PETSc with the H² product, optionally against dense assembly + LU of the same system; prints
// one CSV row with bench_hss's columns (so bench_hss.py drives both, see benchmarks/README.md) and the H²
// extras.
//
//   bench_h2 --mesh FILE [--tol 1e-5] [--leaf 64] [--eta 0] [--single 0|1] [--dense 0|1]
//            [--rtol 1e-8] [--max-it 1000] [--hss 0|1] [--hss-leaf 256] [--header]
//
// --max-it 0 skips the solve (compression, memory and the sampled error only).
//
// Problem (as bench_hss): the nodes below the median height clamped, the others loaded by a
// traction (0, 0, -1); E = 1, nu = 0.3. Besides the solve, the product is checked against true
// entries on 48 sampled rows of K (all columns, rigid-body terms included: sample_err), so the
// accuracy is measured at any size. --hss 1 also compresses K as HSS (stderr: time, memory,
// sampled error) for a side-by-side look at the two formats.
#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/compress/pattern_columns.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/h2/h2_system.hpp"
#include "hssbem/hss/hss_compression.hpp"
#include "hssbem/petsc/compat.h"
#include "hssbem/problem/benchmark_problem.hpp"

#include "bench_support.hpp"

#include <petscksp.h>

#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>
#include <string>

using namespace hssbem;

namespace {

/// A random x (w per node, mesh order) and K x on 48 sampled nodes from true entries.
struct Probe {
  std::vector<double> x;
  std::vector<int> rows;
  std::vector<double> y; ///< 3 per sampled node
};

Probe make_probe(const BemOperator &op, int w)
{
  const int n = op.num_nodes();
  Probe p;
  std::mt19937 gen(11);
  std::normal_distribution<double> N01;
  p.x.resize(static_cast<std::size_t>(w) * n);
  for (double &v : p.x) v = N01(gen);
  for (int k = 0; k < 48 && k < n; ++k) p.rows.push_back(static_cast<int>((static_cast<long>(k) * n) / std::min(48, n)));
  std::vector<int> all(n);
  std::iota(all.begin(), all.end(), 0);
  p.y.assign(3 * p.rows.size(), 0.0);
  const long ld = 3L * n;
  std::vector<double> H(3 * p.rows.size() * ld), G(H.size());
  BemOperator::Workspace ws(op);
  op.fill_hg(p.rows, all, H.data(), G.data(), ld, nullptr, n, ws);
  for (std::size_t r = 0; r < 3 * p.rows.size(); ++r)
    for (int j = 0; j < n; ++j)
      for (int s = 0; s < w; ++s) p.y[r] += p.x[static_cast<std::size_t>(w) * j + s] * (s < 3 ? H[r * ld + 3 * j + s] : G[r * ld + 3 * j + s - 3]);
  return p;
}

/// Relative error of a compressed K (HssMatrix or H2Matrix) on the probe's rows.
template <class M>
double probe_error(const M &K, const Probe &p)
{
  std::vector<double> y(3L * K.tree().num_points());
  apply_compressed_k(K, p.x, y.data());
  double e = 0, s = 0;
  for (std::size_t k = 0; k < p.rows.size(); ++k)
    for (int c = 0; c < 3; ++c) {
      const double d = y[3 * static_cast<std::size_t>(p.rows[k]) + c] - p.y[3 * k + c];
      e += d * d;
      s += p.y[3 * k + c] * p.y[3 * k + c];
    }
  return std::sqrt(e / s);
}

/// The system matrix of a pattern as a sequential MatShell over the H² system.
struct ShellContext {
  const H2BemSystem *sys;
  const SystemSelection *sel;
};

PetscErrorCode ShellMult(Mat A, Vec x, Vec y)
{
  ShellContext *ctx;
  const PetscScalar *xa;
  PetscScalar *ya;
  PetscFunctionBeginUser;
  PetscCall(MatShellGetContext(A, &ctx));
  PetscCall(VecGetArrayRead(x, &xa));
  PetscCall(VecGetArrayWrite(y, &ya));
  ctx->sys->apply(*ctx->sel, xa, ya);
  PetscCall(VecRestoreArrayRead(x, &xa));
  PetscCall(VecRestoreArrayWrite(y, &ya));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ShellDiagonal(Mat A, Vec d)
{
  ShellContext *ctx;
  PetscScalar *da;
  PetscFunctionBeginUser;
  PetscCall(MatShellGetContext(A, &ctx));
  const std::vector<double> diag = ctx->sys->diagonal(*ctx->sel);
  PetscCall(VecGetArrayWrite(d, &da));
  std::copy(diag.begin(), diag.end(), da);
  PetscCall(VecRestoreArrayWrite(d, &da));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/// GMRES(restart 100) + Jacobi on the H² system: the solution, iterations and seconds.
PetscErrorCode gmres_jacobi(const H2BemSystem &sys, const SystemSelection &sel, const std::vector<double> &b, double rtol, int max_it,
                            std::vector<double> &x, PetscInt &its, double &seconds)
{
  const PetscInt N = static_cast<PetscInt>(b.size());
  ShellContext ctx{&sys, &sel};
  Mat A;
  Vec vb, vx;
  KSP ksp;
  PC pc;
  KSPConvergedReason reason;
  PetscFunctionBeginUser;
  PetscCall(MatCreateShell(PETSC_COMM_SELF, N, N, N, N, &ctx, &A));
  PetscCall(MatShellSetOperation(A, MATOP_MULT, (void (*)(void))ShellMult));
  PetscCall(MatShellSetOperation(A, MATOP_GET_DIAGONAL, (void (*)(void))ShellDiagonal));
  PetscCall(VecCreateSeqWithArray(PETSC_COMM_SELF, 1, N, b.data(), &vb));
  x.assign(b.size(), 0.0);
  PetscCall(VecCreateSeqWithArray(PETSC_COMM_SELF, 1, N, x.data(), &vx));
  PetscCall(KSPCreate(PETSC_COMM_SELF, &ksp));
  PetscCall(KSPSetOperators(ksp, A, A));
  PetscCall(KSPSetType(ksp, KSPGMRES));
  PetscCall(KSPGMRESSetRestart(ksp, 100));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PCSetType(pc, PCJACOBI));
  PetscCall(KSPSetTolerances(ksp, rtol, PETSC_DEFAULT, PETSC_DEFAULT, max_it));
  const Timer timer;
  PetscCall(KSPSolve(ksp, vb, vx));
  seconds = timer.seconds();
  PetscCall(KSPGetIterationNumber(ksp, &its));
  PetscCall(KSPGetConvergedReason(ksp, &reason));
  PetscCheck(reason > 0, PETSC_COMM_SELF, PETSC_ERR_NOT_CONVERGED, "GMRES did not converge: %s after %d iterations", KSPConvergedReasons[reason], (int)its);
  PetscCall(KSPDestroy(&ksp));
  PetscCall(VecDestroy(&vx));
  PetscCall(VecDestroy(&vb));
  PetscCall(MatDestroy(&A));
  PetscFunctionReturn(PETSC_SUCCESS);
}

} // namespace

int main(int argc, char **argv)
{
  std::string mesh_path;
  H2Options opt;
  opt.rel_tol = 1e-5;
  opt.single_precision = false; // --single 1 for the driver's blocks
  HssOptions hss;
  hss.rel_tol = 1e-6;
  bool dense = false, run_hss = false, header = false;
  double rtol = 1e-8;
  int max_it = 1000;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument("missing value after " + a);
      return argv[++i];
    };
    if (a == "--mesh") mesh_path = next();
    else if (a == "--tol") opt.rel_tol = hss.rel_tol = std::stod(next());
    else if (a == "--leaf") opt.leaf_size = std::stoi(next());
    else if (a == "--eta") opt.eta = std::stod(next());
    else if (a == "--proxy-ratio") opt.proxy_ratio = std::stod(next());
    else if (a == "--proxy-points") opt.proxy_points = std::stoi(next());
    else if (a == "--single") opt.single_precision = std::stoi(next()) != 0;
    else if (a == "--dense") dense = std::stoi(next()) != 0;
    else if (a == "--rtol") rtol = std::stod(next());
    else if (a == "--max-it") max_it = std::stoi(next());
    else if (a == "--hss") run_hss = std::stoi(next()) != 0;
    else if (a == "--hss-leaf") hss.leaf_size = std::stoi(next());
    else if (a == "--header") header = true;
    else {
      std::fprintf(stderr, "bench_h2: unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  if (header)
    std::printf("mesh,N,tol,leaf,dense_assembly_s,dense_lu_s,compress_s,factor_s,solve_s,matvec_s,max_row_rank,max_col_rank,top_front,"
                "hss_memory_mb,factor_memory_mb,peak_rss_mb,rel_diff,iterations,sample_err,eta,single,basis_mb,far_mb,near_mb\n");
  if (mesh_path.empty()) return header ? 0 : 2;
  PetscCall(PetscInitializeNoArguments());

  SurfaceMesh mesh = read_mesh(mesh_path);
  std::vector<std::string> notices;
  validate_and_orient(mesh, notices);
  Discretization disc(mesh, 40.0);
  BemOperator op(disc, Material::from_young(1.0, 0.3));
  const int n = disc.num_nodes();
  const SystemSelection sel = clamped_lower_half(disc, {0, 0, -1});
  const Probe probe = make_probe(op, 6);

  // H²: compress K once, right-hand side by a fast product, GMRES + Jacobi.
  Timer timer;
  const H2BemSystem sys(op, opt);
  const double t_compress = timer.seconds();
  timer.restart();
  const std::vector<double> b = sys.rhs(sel);
  const double t_matvec = timer.seconds();
  std::vector<double> x;
  PetscInt its = 0;
  double t_solve = 0;
  if (max_it > 0) PetscCall(gmres_jacobi(sys, sel, b, rtol, max_it, x, its, t_solve));
  else x.assign(b.size(), std::nan(""));
  const H2Matrix &K = sys.matrix();
  const double sample_err = probe_error(K, probe);
  const double rss = bench::peak_rss_mb();
  const H2Stats &st = K.stats();
  for (std::size_t l = 0; l < st.levels.size(); ++l)
    std::fprintf(stderr, "level %zu: %d clusters, row rank max %d mean %.0f, column rank max %d mean %.0f, %ld far blocks\n", l, st.levels[l].clusters,
                 st.levels[l].max_row_rank, st.levels[l].mean_row_rank, st.levels[l].max_col_rank, st.levels[l].mean_col_rank, st.levels[l].far_blocks);
  std::fprintf(stderr, "compress: tree+partition %.2f s, far blocks %.2f s, near blocks %.2f s, rigid %.2f s; summed over threads: ID samples %.2f s, IDs %.2f s; %.3g entries, %ld far and %ld near blocks, %d proxy points\n",
               st.time_tree, st.time_far, st.time_near, st.time_rigid, st.time_near_field, st.time_ids, double(st.entries_evaluated), st.far_blocks,
               st.near_blocks, st.proxy_points);
  {
    // Where the blocks' memory goes: near blocks on the diagonal, low rank, dense; far likewise.
    double self = 0, near_lr = 0, near_dense = 0, far_lr = 0, far_dense = 0;
    long near_lr_n = 0, far_lr_n = 0;
    for (int c = 0; c < K.tree().num_clusters(); ++c) {
      for (const H2Block &B : K.near_blocks(c)) {
        const double mb = B.bytes() / 1048576.0;
        if (B.col_cluster == c) self += mb;
        else if (B.is_low_rank()) near_lr += mb, ++near_lr_n;
        else near_dense += mb;
      }
      for (const H2Block &B : K.far_blocks(c)) {
        const double mb = B.bytes() / 1048576.0;
        if (B.is_low_rank()) far_lr += mb, ++far_lr_n;
        else far_dense += mb;
      }
    }
    std::fprintf(stderr, "blocks: near %.1f MB on the diagonal, %.1f MB in %ld low-rank blocks, %.1f MB dense; far %.1f MB in %ld low-rank blocks, %.1f MB dense\n", self,
                 near_lr, near_lr_n, near_dense, far_lr, far_lr_n, far_dense);
  }
  std::fprintf(stderr, "solve: GMRES(100) + Jacobi, %d iterations to rtol %g, %.2f s\n", (int)its, rtol, t_solve);

  if (run_hss) {
    timer.restart();
    const HssMatrix Kh = compress_bem_operator_hss(op, hss);
    std::fprintf(stderr, "hss (leaf %d): compress %.2f s, max rank %d/%d, memory %.1f MB, sampled error %.3e\n", hss.leaf_size, timer.seconds(),
                 Kh.stats().max_row_rank(), Kh.stats().max_col_rank(), Kh.stats().memory_bytes / 1048576.0, probe_error(Kh, probe));
  }

  const bench::DenseFigures d = bench::dense_figures(dense, op, sel, x);
  std::printf("%s,%d,%.0e,%d,%.3f,%.3f,%.3f,0,%.4f,%.4f,%d,%d,nan,%.1f,0,%.0f,%.3e,%d,%.3e,%.2f,%d,%.1f,%.1f,%.1f\n",
              mesh_path.substr(mesh_path.find_last_of('/') + 1).c_str(), 3 * n, opt.rel_tol, opt.leaf_size, d.t_assembly, d.t_lu, t_compress, t_solve, t_matvec,
              st.max_row_rank(), st.max_col_rank(), st.memory_bytes / 1048576.0, std::max(rss, bench::peak_rss_mb()), d.rel_diff, (int)its, sample_err, opt.eta,
              opt.single_precision ? 1 : 0, st.basis_bytes / 1048576.0, st.far_bytes / 1048576.0, st.near_bytes / 1048576.0);
  PetscCall(PetscFinalize());
  return 0;
}
