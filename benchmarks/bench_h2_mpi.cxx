// The H² matrix distributed over the MPI ranks (h2/h2_distributed.hpp) on a METIS partition: one
// line of figures per run, for side-by-side runs at 1, 2, 4 … ranks on the same mesh.
//
//   OMP_NUM_THREADS=1 mpirun -n P build/bin/bench_h2_mpi --mesh M.msh [--tol 1e-5] [--leaf 64]
//                                                     [--products 10] [--header]
//
// Columns: ranks, unknowns, partition seconds, edge cut and imbalance, construction seconds
// (slowest rank), seconds per product (mean over --products, slowest rank), per product and rank:
// values sent (max and mean over ranks) and messages (max), peak resident memory per rank before
// the check below (max, MB), the matrix's memory on the largest rank (MB), the seconds to gather
// the matrix on rank 0 (what PC h2 does), and the relative difference of the product
// from the same matrix gathered on rank 0 (a check, ≈1e-16). Problem: the clamped lower half of
// benchmark_problem.hpp (E = 1, ν = 0.3), K = [H, G] in single-precision blocks (the driver's).
#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/bem/node_partition.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/h2/h2_system.hpp"
#include "hssbem/petsc/compat.h"
#include "hssbem/petsc/mpi_comm.h"
#include "hssbem/problem/benchmark_problem.hpp"

#include "bench_support.hpp"

#include <petscsys.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

using namespace hssbem;

int main(int argc, char **argv)
{
  std::string mesh_path;
  double tol = 1e-5;
  int leaf = 64, products = 10;
  bool header = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--mesh" && i + 1 < argc) mesh_path = argv[++i];
    else if (a == "--tol" && i + 1 < argc) tol = std::stod(argv[++i]);
    else if (a == "--leaf" && i + 1 < argc) leaf = std::stoi(argv[++i]);
    else if (a == "--products" && i + 1 < argc) products = std::stoi(argv[++i]);
    else if (a == "--header") header = true;
    else {
      std::fprintf(stderr, "bench_h2_mpi: unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  if (header)
    std::printf("ranks,N,partition_s,edge_cut,imbalance,construct_s,product_s,values_sent_max,values_sent_mean,messages_max,peak_rss_mb_max,matrix_mb_max,gather_s,check_rel_diff\n");
  if (mesh_path.empty()) return header ? 0 : 2;
  PetscCall(PetscInitializeNoArguments());
  {
    const HssbemMpiComm comm(PETSC_COMM_WORLD);
    SurfaceMesh mesh = read_mesh(mesh_path);
    std::vector<std::string> notices;
    validate_and_orient(mesh, notices);
    Discretization disc(mesh, 40.0);
    BemOperator op(disc, Material::from_young(1.0, 0.3));
    const SystemSelection sel = clamped_lower_half(disc, {0, 0, -1});

    Timer timer;
    NodePartitionStats ps;
    std::vector<int> part;
    if (comm.rank() == 0) part = partition_nodes(disc, comm.size(), &ps);
    part.resize(disc.num_nodes());
    MPI_Bcast(part.data(), disc.num_nodes(), MPI_INT, 0, PETSC_COMM_WORLD);
    const double t_part = comm.max(timer.seconds());

    H2Options o;
    o.rel_tol = tol;
    o.leaf_size = leaf;
    o.single_precision = true;
    MPI_Barrier(PETSC_COMM_WORLD);
    timer.restart();
    const H2DistributedSystem sys(op, o, part, comm);
    const double t_build = comm.max(timer.seconds());

    const int m = sys.num_points();
    std::mt19937 gen(3 + comm.rank());
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<double> x(3L * m), y(3L * m);
    for (double &v : x) v = u(gen);
    sys.apply(sel, x.data(), y.data()); // warm-up
    MPI_Barrier(PETSC_COMM_WORLD);
    timer.restart();
    for (int k = 0; k < products; ++k) sys.apply(sel, x.data(), y.data());
    const double t_prod = comm.max(timer.seconds() / products);

    const double rss = comm.max(bench::peak_rss_mb()); // before the check's gathered copy

    // Check: the same product by the matrix gathered on rank 0.
    const H2DistributedProduct &P = sys.product();
    const int w = sys.matrix().col_block(), n = sys.matrix().tree().num_points();
    std::vector<double> X(static_cast<std::size_t>(w) * m), Y(3L * m);
    for (double &v : X) v = u(gen);
    P.apply(X.data(), w * m, Y.data(), 3 * m);
    std::vector<int> counts, displs(comm.size(), 0);
    std::vector<double> Xall(static_cast<std::size_t>(w) * n), Yall(3L * n);
    const std::vector<int> firsts = comm.allgather({P.first_point()}, counts);
    std::vector<int> xc(comm.size()), xd(comm.size()), yc(comm.size()), yd(comm.size());
    const std::vector<int> sizes = comm.allgather({m}, counts);
    for (int q = 0; q < comm.size(); ++q) xc[q] = w * sizes[q], xd[q] = w * firsts[q], yc[q] = 3 * sizes[q], yd[q] = 3 * firsts[q];
    MPI_Gatherv(X.data(), w * m, MPI_DOUBLE, Xall.data(), xc.data(), xd.data(), MPI_DOUBLE, 0, PETSC_COMM_WORLD);
    MPI_Gatherv(Y.data(), 3 * m, MPI_DOUBLE, Yall.data(), yc.data(), yd.data(), MPI_DOUBLE, 0, PETSC_COMM_WORLD);
    timer.restart();
    const std::optional<H2Matrix> whole = gather_h2_matrix(sys.matrix(), comm);
    const double t_gather = comm.max(timer.seconds());
    double check = 0;
    if (whole) {
      std::vector<double> Yw(Yall.size());
      whole->apply(Xall.data(), w * n, Yw.data(), 3 * n);
      check = bench::rel_diff(Yall, Yw);
    }

    double sent[2] = {static_cast<double>(P.values_sent()), static_cast<double>(P.values_sent())};
    const double sent_max = comm.max(sent[0]);
    comm.sum(&sent[1], 1);
    const double msgs = comm.max(static_cast<double>(P.messages_sent()));
    const double mb = comm.max(sys.matrix().stats().memory_bytes / 1048576.0);
    if (comm.rank() == 0)
      std::printf("%d,%d,%.2f,%ld,%.3f,%.2f,%.4f,%.0f,%.0f,%.0f,%.0f,%.1f,%.2f,%.2e\n", comm.size(), 3 * n, t_part, ps.edge_cut, ps.imbalance, t_build, t_prod, sent_max,
                  sent[1] / comm.size(), msgs, rss, mb, t_gather, check);
  }
  PetscCall(PetscFinalize());
  return 0;
}
