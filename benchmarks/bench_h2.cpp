// H² (strong admissibility) against HSS (weak admissibility) compression of K = [H, G] on one
// mesh; prints one CSV row per format (see README.md).
//
//   bench_h2 --mesh FILE [--tol 1e-6] [--leaf 64] [--eta 0] [--single 0|1] [--hss 0|1] [--hss-leaf 256] [--header]
//
// Accuracy: K x for a random x against the exact product on 48 sampled rows (all columns,
// true entries with the rigid-body terms), so no dense K is needed at any size.
#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/h2/h2_compression.hpp"
#include "hssbem/hss/bem_compression.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <random>
#include <string>

using namespace hssbem;

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

double peak_rss_mb()
{
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return 0;
}

/// A random x (mesh order, w per node), and K x on `rows` (nodes) from true entries.
struct Probe {
  std::vector<double> x;  ///< w per node, mesh order
  std::vector<int> rows;  ///< sampled nodes
  std::vector<double> y;  ///< 3 per sampled node
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
  std::vector<double> H(3 * p.rows.size() * ld), G(H.size()), Gn(w > 6 ? 3 * p.rows.size() * n : 0);
  BemOperator::Workspace ws(op);
  op.fill_hg(p.rows, all, H.data(), G.data(), ld, w > 6 ? Gn.data() : nullptr, n, ws);
  for (std::size_t r = 0; r < 3 * p.rows.size(); ++r)
    for (int j = 0; j < n; ++j)
      for (int s = 0; s < w; ++s)
        p.y[r] += p.x[static_cast<std::size_t>(w) * j + s] * (s < 3 ? H[r * ld + 3 * j + s] : s < 6 ? G[r * ld + 3 * j + s - 3] : Gn[r * n + j]);
  return p;
}

/// Apply a compressed K (HssMatrix or H2Matrix) to the probe; relative error on its rows and
/// the time of one product.
template <class M>
double probe_error(const M &K, const Probe &p, double &t_matvec)
{
  const ClusterTree &tree = K.tree();
  const int n = tree.num_points(), w = K.col_block();
  std::vector<double> xs(p.x), xc(xs.size()), yc(3L * n), y(3L * n);
  for (int j = 0; j < n; ++j)
    for (int q = 0; q < w; ++q) xs[static_cast<std::size_t>(w) * j + q] /= K.col_scale(q);
  tree.to_cluster_order(xs.data(), xc.data(), w);
  const auto t0 = Clock::now();
  K.apply(xc.data(), w * n, yc.data(), 3 * n);
  t_matvec = since(t0);
  tree.to_mesh_order(yc.data(), y.data(), 3);
  double e = 0, s = 0;
  for (std::size_t k = 0; k < p.rows.size(); ++k)
    for (int c = 0; c < 3; ++c) {
      const double d = y[3 * static_cast<std::size_t>(p.rows[k]) + c] - p.y[3 * k + c];
      e += d * d;
      s += p.y[3 * k + c] * p.y[3 * k + c];
    }
  return std::sqrt(e / s);
}

} // namespace

int main(int argc, char **argv)
{
  std::string mesh_path;
  H2Options opt;
  HssOptions hss;
  bool run_hss = false, header = false;
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
    else if (a == "--single") opt.single_precision = std::stoi(next()) != 0;
    else if (a == "--hss") run_hss = std::stoi(next()) != 0;
    else if (a == "--hss-leaf") hss.leaf_size = std::stoi(next());
    else if (a == "--header") header = true;
    else {
      std::fprintf(stderr, "bench_h2: unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  if (header)
    std::printf("format,mesh,N,tol,leaf,eta,compress_s,matvec_s,max_row_rank,max_col_rank,memory_mb,basis_mb,far_mb,near_mb,entries,peak_rss_mb,"
                "sample_err\n");
  if (mesh_path.empty()) return header ? 0 : 2;

  SurfaceMesh mesh = read_mesh(mesh_path);
  std::vector<std::string> notices;
  validate_and_orient(mesh, notices);
  Discretization disc(mesh, 40.0);
  BemOperator op(disc, Material::from_young(1.0, 0.3));
  const std::string name = mesh_path.substr(mesh_path.find_last_of('/') + 1);
  const int n = disc.num_nodes();
  const Probe probe = make_probe(op, 6);

  {
    auto t0 = Clock::now();
    const H2Matrix K = compress_bem_operator_h2(op, opt);
    const double t_compress = since(t0);
    double t_mv = 0;
    const double err = probe_error(K, probe, t_mv);
    const H2Stats &st = K.stats();
    for (std::size_t l = 0; l < st.levels.size(); ++l)
      std::fprintf(stderr, "h2 level %zu: %d bases, row rank max %d mean %.0f, column rank max %d mean %.0f, %ld far blocks\n", l, st.levels[l].clusters,
                   st.levels[l].max_row_rank, st.levels[l].mean_row_rank, st.levels[l].max_col_rank, st.levels[l].mean_col_rank, st.levels[l].far_blocks);
    std::fprintf(stderr, "h2: tree+partition %.2f s, far blocks %.2f s, near blocks %.2f s, rigid %.2f s; summed over threads: ID samples %.2f s, IDs %.2f s; %ld far, %ld near blocks\n",
                 st.time_tree, st.time_far, st.time_near, st.time_rigid, st.time_near_field, st.time_ids, st.far_blocks, st.near_blocks);
    std::printf("%s,%s,%d,%.0e,%d,%.2f,%.3f,%.4f,%d,%d,%.1f,%.1f,%.1f,%.1f,%.3g,%.0f,%.3e\n", opt.single_precision ? "h2-single" : "h2", name.c_str(), 3 * n, opt.rel_tol, opt.leaf_size, opt.eta, t_compress,
                t_mv, st.max_row_rank(), st.max_col_rank(), st.memory_bytes / 1048576.0, st.basis_bytes / 1048576.0, st.far_bytes / 1048576.0,
                st.near_bytes / 1048576.0, double(st.entries_evaluated), peak_rss_mb(), err);
    std::fflush(stdout);
  }
  if (run_hss) {
    auto t0 = Clock::now();
    const HssMatrix K = compress_bem_operator(op, hss);
    const double t_compress = since(t0);
    double t_mv = 0;
    const double err = probe_error(K, probe, t_mv);
    const HssStats &st = K.stats();
    std::printf("hss,%s,%d,%.0e,%d,,%.3f,%.4f,%d,%d,%.1f,,,,%.3g,%.0f,%.3e\n", name.c_str(), 3 * n, hss.rel_tol, hss.leaf_size, t_compress, t_mv,
                st.max_row_rank(), st.max_col_rank(), st.memory_bytes / 1048576.0, double(st.entries_evaluated), peak_rss_mb(), err);
  }
  return 0;
}
