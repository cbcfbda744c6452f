// The HSS matrix and its ULV factorization distributed over the MPI ranks (hss/hss_distributed.hpp,
// hss/ulv.hpp) on a METIS partition: one line of figures per run, for side-by-side runs at 1, 2,
// 4 … ranks on the same mesh.
//
//   OMP_NUM_THREADS=1 mpirun -n P build/bin/bench_hss_mpi --mesh M.msh [--tol 1e-6] [--leaf 256]
//                                                      [--products 10] [--solves 10] [--header]
//
// Columns: ranks, unknowns, construction seconds (compression and the product's plan, slowest
// rank), seconds per product, factorization seconds, seconds per solve (means, slowest rank), per
// product and rank the values sent (max) and messages (max), peak resident memory per rank (max
// and min over the ranks, MB), the matrix's and the factors' memory on the largest rank (MB), the
// top's share on rank 0 (the clusters above the parts: generators and factors, MB), the root
// block's unknowns, the largest row and column rank, and the relative residual ‖A x − b‖/‖b‖ of
// a solve measured with the distributed product (a check: about the tolerance). Problem: the
// clamped lower half of benchmark_problem.hpp (E = 1, ν = 0.3), K = [H, G].
#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/bem/node_partition.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/hss/hss_system.hpp"
#include "hssbem/petsc/compat.h"
#include "hssbem/petsc/mpi_comm.h"
#include "hssbem/problem/benchmark_problem.hpp"

#include "bench_support.hpp"

#include <petscsys.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>

using namespace hssbem;

namespace {

struct Args {
  std::string mesh;
  double tol = 1e-6;
  int leaf = 256, products = 10, solves = 10;
  bool header = false;
};

bool parse(int argc, char **argv, Args &a)
{
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    if (s == "--mesh" && i + 1 < argc) a.mesh = argv[++i];
    else if (s == "--tol" && i + 1 < argc) a.tol = std::stod(argv[++i]);
    else if (s == "--leaf" && i + 1 < argc) a.leaf = std::stoi(argv[++i]);
    else if (s == "--products" && i + 1 < argc) a.products = std::stoi(argv[++i]);
    else if (s == "--solves" && i + 1 < argc) a.solves = std::stoi(argv[++i]);
    else if (s == "--header") a.header = true;
    else {
      std::fprintf(stderr, "bench_hss_mpi: unknown argument %s\n", s.c_str());
      return false;
    }
  }
  return true;
}

/// ‖a‖² summed over the ranks.
double norm2(const HssbemMpiComm &comm, const std::vector<double> &a)
{
  double s = 0;
  for (double v : a) s += v * v;
  comm.sum(&s, 1);
  return s;
}

} // namespace

int main(int argc, char **argv)
{
  Args a;
  if (!parse(argc, argv, a)) return 2;
  if (a.header)
    std::printf("ranks,N,construct_s,product_s,factor_s,solve_s,values_sent_max,messages_max,peak_rss_mb_max,peak_rss_mb_min,matrix_mb_max,factors_mb_max,top_mb,root_size,max_rank_row,max_rank_col,residual\n");
  if (a.mesh.empty()) return a.header ? 0 : 2;
  PetscCall(PetscInitializeNoArguments());
  {
    const HssbemMpiComm comm(PETSC_COMM_WORLD);
    SurfaceMesh mesh = read_mesh(a.mesh);
    std::vector<std::string> notices;
    validate_and_orient(mesh, notices);
    Discretization disc(mesh, 40.0);
    BemOperator op(disc, Material::from_young(1.0, 0.3));
    const SystemSelection sel = clamped_lower_half(disc, {0, 0, -1});
    std::vector<int> part;
    if (comm.rank() == 0) part = partition_nodes(disc, comm.size());
    part.resize(disc.num_nodes());
    MPI_Bcast(part.data(), disc.num_nodes(), MPI_INT, 0, PETSC_COMM_WORLD);

    HssOptions o;
    o.rel_tol = a.tol;
    o.leaf_size = a.leaf;
    MPI_Barrier(PETSC_COMM_WORLD);
    Timer timer;
    const HssDistributedSystem sys(op, o, part, comm);
    const double t_build = comm.max(timer.seconds());

    const int m = sys.num_points();
    std::mt19937 gen(3 + comm.rank());
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<double> x(3L * m), y(3L * m);
    for (double &v : x) v = u(gen);
    sys.apply(sel, x.data(), y.data()); // warm-up
    MPI_Barrier(PETSC_COMM_WORLD);
    timer.restart();
    for (int k = 0; k < a.products; ++k) sys.apply(sel, x.data(), y.data());
    const double t_prod = comm.max(timer.seconds() / a.products);

    MPI_Barrier(PETSC_COMM_WORLD);
    timer.restart();
    const std::unique_ptr<UlvFactorization> F = sys.factor(sel);
    const double t_factor = comm.max(timer.seconds());

    const std::vector<double> b = sys.rhs(sel);
    std::vector<double> z(b.size());
    MPI_Barrier(PETSC_COMM_WORLD);
    timer.restart();
    for (int k = 0; k < a.solves; ++k) {
      z = b;
      F->solve(z.data());
    }
    const double t_solve = comm.max(timer.seconds() / a.solves);
    sys.apply(sel, z.data(), y.data());
    for (std::size_t i = 0; i < y.size(); ++i) y[i] -= b[i];
    const double residual = std::sqrt(norm2(comm, y) / norm2(comm, b));

    const double rss = bench::peak_rss_mb(), rss_max = comm.max(rss), rss_min = -comm.max(-rss);
    const HssStats &st = sys.matrix().stats();
    const double mat_mb = comm.max(st.memory_bytes / 1048576.0), fac_mb = comm.max(F->memory_bytes() / 1048576.0);
    const double top_mb = comm.max((st.top_bytes + F->top_bytes()) / 1048576.0);
    const double root = comm.max(F->root_size());
    const double sent = comm.max(static_cast<double>(sys.product().values_sent())), msgs = comm.max(static_cast<double>(sys.product().messages_sent()));
    if (comm.rank() == 0)
      std::printf("%d,%d,%.2f,%.4f,%.2f,%.4f,%.0f,%.0f,%.0f,%.0f,%.1f,%.1f,%.1f,%.0f,%d,%d,%.2e\n", comm.size(), 3 * disc.num_nodes(), t_build, t_prod, t_factor, t_solve, sent, msgs,
                  rss_max, rss_min, mat_mb, fac_mb, top_mb, root, st.max_row_rank(), st.max_col_rank(), residual);
  }
  PetscCall(PetscFinalize());
  return 0;
}
