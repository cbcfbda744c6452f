// HSS direct solve against dense assembly + LU on one mesh; prints one CSV row (see benchmarks/README.md).
//
//   bench_hss --mesh FILE [--tol 1e-6] [--leaf 256] [--dense 0|1] [--header]
//
// Problem: the nodes below the median height are clamped (u = 0, traction unknown), the others
// carry a uniform traction (0, 0, -1) (displacement unknown), E = 1, nu = 0.3.
#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/hss/hss_system.hpp"
#include "hssbem/problem/benchmark_problem.hpp"

#include "bench_support.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <numeric>
#include <string>

using namespace hssbem;


int main(int argc, char **argv)
{
  std::string mesh_path;
  HssOptions opt;
  opt.rel_tol = 1e-6; // --tol: bench_hss.py gives each run's
  bool dense = true, header = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument("missing value after " + a);
      return argv[++i];
    };
    if (a == "--mesh") mesh_path = next();
    else if (a == "--tol") opt.rel_tol = std::stod(next());
    else if (a == "--leaf") opt.leaf_size = std::stoi(next());
    else if (a == "--proxy-ratio") opt.proxy_ratio = std::stod(next());
    else if (a == "--proxy-points") opt.proxy_points = std::stoi(next());
    else if (a == "--dense") dense = std::stoi(next()) != 0;
    else if (a == "--header") header = true;
    else {
      std::fprintf(stderr, "bench_hss: unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  if (header)
    std::printf("mesh,N,tol,leaf,dense_assembly_s,dense_lu_s,compress_s,factor_s,solve_s,matvec_s,max_row_rank,max_col_rank,top_front,"
                "hss_memory_mb,factor_memory_mb,peak_rss_mb,rel_diff\n");
  if (mesh_path.empty()) return header ? 0 : 2;

  SurfaceMesh mesh = read_mesh(mesh_path);
  std::vector<std::string> notices;
  validate_and_orient(mesh, notices);
  Discretization disc(mesh, 40.0);
  BemOperator op(disc, Material::from_young(1.0, 0.3));
  const int n = disc.num_nodes();
  const SystemSelection sel = clamped_lower_half(disc, {0, 0, -1});

  // HSS: compress K once, right-hand side by a fast product, factor the pattern, solve.
  Timer timer;
  HssBemSystem sys(op, opt);
  const double t_compress = timer.seconds();
  timer.restart();
  const std::vector<double> b = sys.rhs(sel);
  const double t_matvec = timer.seconds();
  timer.restart();
  const auto F = sys.factor(sel);
  const double t_factor = timer.seconds();
  timer.restart();
  const std::vector<double> x_hss = sys.solve(*F, b);
  const double t_solve = timer.seconds();
  const HssMatrix &K = sys.matrix();
  const double rss = bench::peak_rss_mb();
  const HssStats &st = K.stats();
  for (std::size_t l = 0; l < st.levels.size(); ++l)
    std::fprintf(stderr, "level %zu: %d clusters, row rank max %d mean %.0f, column rank max %d mean %.0f\n", l, st.levels[l].clusters,
                 st.levels[l].max_row_rank, st.levels[l].mean_row_rank, st.levels[l].max_col_rank, st.levels[l].mean_col_rank);
  std::fprintf(stderr, "compress: tree %.2f s, rigid %.2f s, couplings %.2f s, leaves %.2f s; summed over threads: near field %.2f s, IDs %.2f s; %.3g entries, %d proxy points\n",
               st.time_tree, st.time_rigid, st.time_couplings, st.time_leaves, st.time_near_field, st.time_ids, double(st.entries_evaluated),
               st.proxy_points);

  const bench::DenseFigures d = bench::dense_figures(dense, op, sel, x_hss);
  std::printf("%s,%d,%.0e,%d,%.3f,%.3f,%.3f,%.3f,%.4f,%.4f,%d,%d,%d,%.1f,%.1f,%.0f,%.3e\n", mesh_path.substr(mesh_path.find_last_of('/') + 1).c_str(), 3 * n,
              opt.rel_tol, opt.leaf_size, d.t_assembly, d.t_lu, t_compress, t_factor, t_solve, t_matvec, st.max_row_rank(), st.max_col_rank(), F->max_front(),
              st.memory_bytes / 1048576.0, F->memory_bytes() / 1048576.0, rss, d.rel_diff);
  return 0;
}
