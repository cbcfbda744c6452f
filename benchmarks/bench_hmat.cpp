// Peer benchmark: hmat-oss's H-matrix LU on the system matrix of bench_h2 / bench_hss, optionally
// side by side with dense assembly + LU. Optional target, built only when hmat-oss is found
// (hmat-oss is GPL-2+; it is linked into this executable only, never into the library or tests).
//
//   bench_hmat --mesh FILE [--tol 1e-4] [--leaf 200] [--eta 2] [--svd-below 100] [--dense 0|1]
//              [--header]
//
// Problem (as bench_hss / bench_h2): the nodes below the median height clamped, the others loaded
// by a traction (0, 0, -1); E = 1, nu = 0.3. hmat-oss sees a matrix over dofs (3 per dof node,
// dof 3 i + c = component c of node i, at node i's collocation point); its block callback maps the
// requested dofs to their nodes, fills the node block with fill_system_block (OpenMP tiles, one
// workspace per thread) and copies the requested entries out.
//
// The rigid-body terms of H (bem_operator.hpp) need the whole row of H, so do the exact
// right-hand side and the sampled residual: one sweep over the rows (fill_system_block with every
// column, 16 rows at a time, no N x N array) gives them before hmat-oss starts. It costs about as
// much as a dense assembly and is reported on its own (prep_s), not in hmat-oss's figures; the H²
// path gets the same terms by fast products instead.
#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/problem/benchmark_problem.hpp"

#include "bench_support.hpp"

#include <dlfcn.h>
#include <hmat/hmat.h>
#include <omp.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <exception>
#include <memory>
#include <numeric>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

using namespace hssbem;

namespace {

constexpr int chunk_rows = 16; // dof nodes per row tile, as fill_system_block's own passes

/// What the callbacks share: the operator, the pattern, one workspace per thread, counters.
struct Assembler {
  const BemOperator *op;
  const SystemSelection *sel;
  int threads;
  std::vector<std::unique_ptr<BemOperator::Workspace>> ws;
  std::vector<int> node_slot;    ///< scratch, node -> position in a node list, -1 otherwise
  double node_pairs = 0;         ///< node blocks (3 x 3 entries each) evaluated
  long row_requests = 0, col_requests = 0, block_requests = 0, cache_hits = 0;
  std::exception_ptr error;      ///< first exception inside a callback (hmat-oss is C: none may escape)

  Assembler(const BemOperator &o, const SystemSelection &s, int t) : op(&o), sel(&s), threads(t), node_slot(o.num_nodes(), -1)
  {
    for (int k = 0; k < t; ++k) ws.push_back(std::make_unique<BemOperator::Workspace>(o));
  }

  /// A(I, J) of the node sets, row-major (3|I| x 3|J|, leading dimension ld), tiles on threads.
  void fill(const std::vector<int> &I, const std::vector<int> &J, double *out, long ld)
  {
    const int nI = static_cast<int>(I.size()), nJ = static_cast<int>(J.size());
    node_pairs += static_cast<double>(nI) * nJ;
    const int nrt = (nI + chunk_rows - 1) / chunk_rows;
    int nct = 1;
    if (threads > 1 && nrt < 2 * threads) nct = std::max(1, std::min(nJ / 32, (2 * threads + nrt - 1) / nrt));
    const int tiles = nrt * nct;
    if (threads <= 1 || tiles < 2 || static_cast<double>(nI) * nJ < 2048) {
      fill_system_block(*op, *sel, I, J, out, ld, nullptr, *ws[0]);
      return;
    }
    std::exception_ptr err;
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
    for (int t = 0; t < tiles; ++t) {
      try {
        const int r0 = (t / nct) * chunk_rows, r1 = std::min(nI, r0 + chunk_rows);
        const int c0 = static_cast<int>(static_cast<long>(nJ) * (t % nct) / nct), c1 = static_cast<int>(static_cast<long>(nJ) * (t % nct + 1) / nct);
        const std::vector<int> Is(I.begin() + r0, I.begin() + r1), Js(J.begin() + c0, J.begin() + c1);
        fill_system_block(*op, *sel, Is, Js, out + 3L * r0 * ld + 3L * c0, ld, nullptr, *ws[omp_get_thread_num()]);
      } catch (...) {
#pragma omp critical(bench_hmat_fill_error)
        if (!err) err = std::current_exception();
      }
    }
    if (err) std::rethrow_exception(err);
  }

  /// The distinct nodes of dofs[b, e) in order of appearance, and each dof's position in that list.
  void nodes_of(const std::vector<int> &dofs, int b, int e, std::vector<int> &nodes, std::vector<int> &pos)
  {
    nodes.clear();
    pos.resize(e - b);
    for (int k = b; k < e; ++k) {
      const int v = dofs[k] / 3;
      if (node_slot[v] < 0) {
        node_slot[v] = static_cast<int>(nodes.size());
        nodes.push_back(v);
      }
      pos[k - b] = node_slot[v];
    }
    for (int v : nodes) node_slot[v] = -1;
  }
};

/// One hmat-oss block: its dofs (client numbering) and the node rows/columns already evaluated
/// (ACA+ asks for one dof row or column at a time; a node gives all three components at once).
struct BlockData {
  Assembler *A;
  std::vector<int> rdof, cdof;
  std::vector<int> rnodes, cnodes, rpos, cpos;
  std::unordered_map<int, std::vector<double>> rows, cols; ///< node -> 3 x 3|cnodes| / 3|rnodes| x 3, row-major
};

void release_block(void *p) { delete static_cast<BlockData *>(p); }

void prepare_block(int row_start, int row_count, int col_start, int col_count, int *row_hmat2client, int * /*row_client2hmat*/,
                   int *col_hmat2client, int * /*col_client2hmat*/, void *context, hmat_block_info_t *info)
{
  auto *A = static_cast<Assembler *>(context);
  auto *b = new BlockData;
  b->A = A;
  b->rdof.assign(row_hmat2client + row_start, row_hmat2client + row_start + row_count);
  b->cdof.assign(col_hmat2client + col_start, col_hmat2client + col_start + col_count);
  A->nodes_of(b->rdof, 0, row_count, b->rnodes, b->rpos);
  A->nodes_of(b->cdof, 0, col_count, b->cnodes, b->cpos);
  info->block_type = hmat_block_full;
  info->user_data = b;
  info->release_user_data = release_block;
}

/// Entries [rs, rs + rc) x [cs, cs + cc) of the block, column-major, no padding.
void compute_block(void *data, int rs, int rc, int cs, int cc, void *out_v)
{
  auto *b = static_cast<BlockData *>(data);
  Assembler &A = *b->A;
  double *out = static_cast<double *>(out_v);
  if (A.error) { // an earlier callback failed: fill with NaN, the run is reported as failed
    std::fill(out, out + static_cast<long>(rc) * cc, NAN);
    return;
  }
  try {
    const int nr = static_cast<int>(b->rdof.size()), nc = static_cast<int>(b->cdof.size());
    if (rc == 1 && cs == 0 && cc == nc && nr > 1) { // one row (ACA+)
      ++A.row_requests;
      const int v = b->rdof[rs] / 3, comp = b->rdof[rs] % 3;
      const long ld = 3L * b->cnodes.size();
      auto it = b->rows.find(v);
      if (it == b->rows.end()) {
        it = b->rows.emplace(v, std::vector<double>(3 * ld)).first;
        A.fill({v}, b->cnodes, it->second.data(), ld);
      } else
        ++A.cache_hits;
      const double *r = it->second.data() + comp * ld;
      for (int j = 0; j < cc; ++j) out[j] = r[3 * b->cpos[j] + b->cdof[j] % 3];
      return;
    }
    if (cc == 1 && rs == 0 && rc == nr && nc > 1) { // one column (ACA+)
      ++A.col_requests;
      const int v = b->cdof[cs] / 3, comp = b->cdof[cs] % 3;
      auto it = b->cols.find(v);
      if (it == b->cols.end()) {
        it = b->cols.emplace(v, std::vector<double>(9 * b->rnodes.size())).first;
        A.fill(b->rnodes, {v}, it->second.data(), 3);
      } else
        ++A.cache_hits;
      const double *c = it->second.data();
      for (int i = 0; i < rc; ++i) out[i] = c[3 * (3 * b->rpos[i] + b->rdof[i] % 3) + comp];
      return;
    }
    // A full block (non-admissible leaf, or an admissible one compressed by SVD) or any other range.
    ++A.block_requests;
    std::vector<int> In, Jn, ip, jp;
    if (rs == 0 && rc == nr) In = b->rnodes, ip = b->rpos;
    else A.nodes_of(b->rdof, rs, rs + rc, In, ip);
    if (cs == 0 && cc == nc) Jn = b->cnodes, jp = b->cpos;
    else A.nodes_of(b->cdof, cs, cs + cc, Jn, jp);
    const long ld = 3L * Jn.size();
    std::vector<double> M(3 * In.size() * ld);
    A.fill(In, Jn, M.data(), ld);
    for (int j = 0; j < cc; ++j) {
      const long q = 3L * jp[j] + b->cdof[cs + j] % 3;
      for (int i = 0; i < rc; ++i) out[i + static_cast<long>(j) * rc] = M[(3L * ip[i] + b->rdof[rs + i] % 3) * ld + q];
    }
  } catch (...) {
    if (!A.error) A.error = std::current_exception();
    std::fill(out, out + static_cast<long>(rc) * cc, NAN);
  }
}

/// One sweep over all rows: the exact right-hand side, the rigid-body terms installed in `op` (so
/// that fill_system_block works on any block), and the true rows of the sampled nodes.
struct Prep {
  std::vector<double> b;       ///< 3 per node, mesh order
  std::vector<int> sample;     ///< sampled nodes
  std::vector<double> sample_rows; ///< 3 |sample| rows of A, 3n columns, row-major
  double check = NAN;          ///< max |A(sample, J) after installing the terms - A(sample, J) from the sweep| / max |A(sample, :)|
};

Prep prepare_system(BemOperator &op, const SystemSelection &sel, int threads)
{
  const int n = op.num_nodes();
  const long N = 3L * n;
  std::vector<int> all(n);
  std::iota(all.begin(), all.end(), 0);
  Prep p;
  p.b.assign(N, 0.0);
  for (int k = 0; k < 48 && k < n; ++k) p.sample.push_back(static_cast<int>((static_cast<long>(k) * n) / std::min(48, n)));
  std::vector<int> sample_slot(n, -1);
  for (std::size_t s = 0; s < p.sample.size(); ++s) sample_slot[p.sample[s]] = static_cast<int>(s);
  p.sample_rows.assign(3 * p.sample.size() * N, 0.0);
  std::vector<Mat3> D(n);
  const int chunks = (n + chunk_rows - 1) / chunk_rows;
  std::exception_ptr err;
#pragma omp parallel num_threads(threads)
  {
    BemOperator::Workspace ws(op);
    std::vector<double> rows(3L * chunk_rows * N), H(9), G(9);
#pragma omp for schedule(dynamic, 1)
    for (int c = 0; c < chunks; ++c) {
      try {
        const int r0 = c * chunk_rows, r1 = std::min(n, r0 + chunk_rows);
        const std::vector<int> I(all.begin() + r0, all.begin() + r1);
        fill_system_block(op, sel, I, all, rows.data(), N, p.b.data() + 3L * r0, ws);
        for (int i = r0; i < r1; ++i) {
          const double *Ai = rows.data() + 3L * (i - r0) * N;
          if (sample_slot[i] >= 0) std::copy(Ai, Ai + 3 * N, p.sample_rows.begin() + 3L * sample_slot[i] * N);
          // Column (j, c) of A is H(:, j c) + w_j D_i(:, c) when u_j,c is unknown (else -G, without
          // D): recover D_i(:, c) from the heaviest such column; a D_i(:, c) that reaches no
          // column of A is irrelevant and left 0.
          int cols[3];
          double w[3];
          const int nc = op.rigid_body_columns(i, cols, w);
          for (int comp = 0; comp < 3; ++comp) {
            int best = -1;
            for (int t = 0; t < nc; ++t)
              if (!sel.displacement_known[cols[t]][comp] && (best < 0 || w[t] > w[best])) best = t;
            if (best < 0) continue;
            op.fill_hg_without_rigid({i}, {cols[best]}, H.data(), G.data(), 3, nullptr, 0, ws);
            for (int r = 0; r < 3; ++r) D[i][3 * r + comp] = (Ai[r * N + 3L * cols[best] + comp] - H[3 * r + comp]) / w[best];
          }
        }
      } catch (...) {
#pragma omp critical(bench_hmat_prep_error)
        if (!err) err = std::current_exception();
      }
    }
  }
  if (err) std::rethrow_exception(err);
  op.set_rigid_body_terms(std::move(D));

  // Check: the sampled rows through blocks (installed terms) against the sweep (summed terms).
  std::vector<int> cols;
  for (int j = 0; j < n; ++j)
    if (j != n / 2 || n == 1) cols.push_back(j); // not every node, so the installed terms are used
  if (static_cast<int>(cols.size()) < n) {
    std::vector<double> M(3 * p.sample.size() * 3 * cols.size());
    const long ld = 3L * cols.size();
    fill_system_block(op, sel, p.sample, cols, M.data(), ld, nullptr);
    double diff = 0, scale = 0;
    for (std::size_t r = 0; r < 3 * p.sample.size(); ++r)
      for (std::size_t q = 0; q < cols.size(); ++q)
        for (int c = 0; c < 3; ++c) {
          const double a = p.sample_rows[r * N + 3 * cols[q] + c];
          diff = std::max(diff, std::abs(M[r * ld + 3 * q + c] - a));
          scale = std::max(scale, std::abs(a));
        }
    p.check = diff / scale;
  }
  return p;
}

/// ‖(A x − b)(sample)‖ / ‖b(sample)‖ from the true sampled rows.
double sampled_residual(const Prep &p, const std::vector<double> &x)
{
  const long N = static_cast<long>(x.size());
  double e = 0, s = 0;
  for (std::size_t k = 0; k < p.sample.size(); ++k)
    for (int c = 0; c < 3; ++c) {
      const double *a = p.sample_rows.data() + (3 * k + c) * N;
      double y = 0;
      for (long q = 0; q < N; ++q) y += a[q] * x[q];
      const double bi = p.b[3L * p.sample[k] + c];
      e += (y - bi) * (y - bi);
      s += bi * bi;
    }
  return std::sqrt(e / s);
}

/// CPU seconds of this process (all threads, user + system).
double cpu_seconds()
{
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_utime.tv_sec + ru.ru_stime.tv_sec + 1e-6 * (ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

/// Busy CPU seconds of the whole machine so far (/proc/stat), to tell how much other processes ran.
double machine_busy_seconds()
{
  std::ifstream f("/proc/stat");
  std::string cpu;
  double v[8] = {};
  f >> cpu;
  for (double &x : v) f >> x;
  return (v[0] + v[1] + v[2] + v[5] + v[6] + v[7]) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

/// The BLAS that the process actually calls, when it is OpenBLAS (looked up at run time).
std::string blas_description()
{
  using int_fn = int (*)();
  using str_fn = char *(*)();
  const auto parallel = reinterpret_cast<int_fn>(dlsym(RTLD_DEFAULT, "openblas_get_parallel"));
  const auto threads = reinterpret_cast<int_fn>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
  const auto config = reinterpret_cast<str_fn>(dlsym(RTLD_DEFAULT, "openblas_get_config"));
  if (!parallel || !threads || !config) return "not OpenBLAS";
  const int p = parallel();
  return std::string(config()) + ", " + (p == 0 ? "sequential" : p == 1 ? "pthread" : p == 2 ? "OpenMP" : "?") + " build, " +
         std::to_string(threads()) + " threads";
}

void check_rc(int rc, const char *what)
{
  if (rc != 0) throw std::runtime_error(std::string("hmat-oss: ") + what + " failed (" + std::to_string(rc) + ")");
}

} // namespace

int main(int argc, char **argv)
try {
  std::string mesh_path;
  double tol = 1e-4, eta = 2.0;
  int leaf = 200, svd_below = 100;
  bool dense = false, header = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument("missing value after " + a);
      return argv[++i];
    };
    if (a == "--mesh") mesh_path = next();
    else if (a == "--tol") tol = std::stod(next());
    else if (a == "--leaf") leaf = std::stoi(next());
    else if (a == "--eta") eta = std::stod(next());
    else if (a == "--svd-below") svd_below = std::stoi(next());
    else if (a == "--dense") dense = std::stoi(next()) != 0;
    else if (a == "--header") header = true;
    else {
      std::fprintf(stderr, "bench_hmat: unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  if (header)
    std::printf("mesh,N,tol,leaf,eta,kernel_threads,dense_assembly_s,dense_lu_s,prep_s,tree_s,assembly_s,factor_s,solve_s,"
                "hmat_memory_mb,factor_memory_mb,compressed_pct,rk_blocks,full_blocks,peak_rss_mb,rel_diff,sample_res,assembly_cores,factor_cores,"
                "other_cores\n");
  if (mesh_path.empty()) return header ? 0 : 2;
  if (!(tol > 0) || leaf < 2 || !(eta > 0)) throw std::invalid_argument("bench_hmat: need --tol > 0, --leaf >= 2, --eta > 0");

  SurfaceMesh mesh = read_mesh(mesh_path);
  std::vector<std::string> notices;
  validate_and_orient(mesh, notices);
  Discretization disc(mesh, 40.0);
  BemOperator op(disc, Material::from_young(1.0, 0.3));
  const int n = disc.num_nodes();
  const int N = 3 * n;
  const SystemSelection sel = clamped_lower_half(disc, {0, 0, -1});
  const int threads = omp_get_max_threads();

  // Exact right-hand side and rigid-body terms (one sweep over the rows; not hmat-oss's work).
  Timer timer;
  const Prep prep = prepare_system(op, sel, threads);
  const double t_prep = timer.seconds();
  std::fprintf(stderr, "prep: right-hand side, rigid-body terms and %zu sampled rows by one sweep over the rows, %.2f s; "
                       "block entries vs the sweep's rows: max rel diff %.2e\n", prep.sample.size(), t_prep, prep.check);
  if (!(prep.check < 1e-12)) throw std::runtime_error("bench_hmat: block entries disagree with the rows of the system matrix");

  // hmat-oss settings, all explicit.
  hmat_settings_t settings;
  hmat_get_parameters(&settings);
  settings.compressionMinLeafSize = svd_below; // admissible blocks with max(rows, cols) below this: truncated SVD of the full block
  settings.maxLeafSize = leaf;
  settings.coarsening = 0;
  settings.coarseningEpsilon = tol;            // unused without coarsening
  settings.validateNullRowCol = 0;
  settings.validateCompression = 0;
  settings.validationReRun = 0;
  settings.validationDump = 0;
  settings.dumpTrace = 0;
  if (hmat_set_parameters(&settings) != 0) throw std::runtime_error("hmat_set_parameters failed");
  hmat_interface_t hmat;
  hmat_init_default_interface(&hmat, HMAT_DOUBLE_PRECISION);
  check_rc(hmat.init(), "init");
  std::fprintf(stderr, "hmat-oss %s: double precision; clustering median bisection, at most %d dofs per leaf; admissibility "
                       "Hackbusch (standard), eta %g (min(diam) <= eta dist of the bounding boxes); assembly ACA+ at epsilon %g "
                       "(truncated SVD when max(rows, cols) < %d); low-rank (recompression) epsilon %g for the assembly's truncation "
                       "and the H-LU; coarsening off; LU (hmat_factorization_lu); %d dofs at the collocation points (3 per node)\n",
               hmat_get_version(), leaf, eta, tol, svd_below, tol, N);

  // Dofs: 3 i + c, at node i's collocation point.
  std::vector<double> coord(3L * N);
  for (int d = 0; d < N; ++d)
    for (int k = 0; k < 3; ++k) coord[3L * d + k] = disc.node(d / 3).point[k];
  timer.restart();
  hmat_clustering_algorithm_t *median = hmat_create_clustering_median();
  hmat_clustering_algorithm_t *clustering = hmat_create_clustering_max_dof(median, leaf);
  hmat_cluster_tree_t *tree = hmat_create_cluster_tree(coord.data(), 3, N, clustering);
  hmat_delete_clustering(clustering);
  hmat_delete_clustering(median);
  hmat_admissibility_param_t adm_param;
  hmat_init_admissibility_param(&adm_param);
  adm_param.eta = eta;
  hmat_admissibility_t *adm = hmat_create_admissibility(&adm_param);
  hmat_matrix_t *H = hmat.create_empty_hmatrix_admissibility(tree, tree, 0, adm);
  if (!H) throw std::runtime_error("hmat-oss: create_empty_hmatrix_admissibility failed");
  hmat.set_low_rank_epsilon(H, tol);
  hmat_delete_admissibility(adm);
  const double t_tree = timer.seconds();

  // Assembly: ACA+ over the block callback.
  Assembler A(op, sel, threads);
  hmat_assemble_context_t actx;
  hmat_assemble_context_init(&actx);
  actx.compression = hmat_create_compression_aca_plus(tol);
  actx.user_context = &A;
  actx.prepare = prepare_block;
  actx.block_compute = compute_block;
  actx.lower_symmetric = 0;
  actx.factorization = hmat_factorization_none;
  actx.progress = nullptr; // the default progress bar writes to stdout
  const double busy0 = machine_busy_seconds(), cpu0 = cpu_seconds();
  const Timer hmat_timer;
  timer.restart();
  check_rc(hmat.assemble_generic(H, &actx), "assembly");
  const double t_assembly = timer.seconds(), cpu_assembly = cpu_seconds() - cpu0;
  hmat_delete_compression(actx.compression);
  if (A.error) std::rethrow_exception(A.error);
  hmat_info_t info;
  check_rc(hmat.get_info(H, &info), "get_info");
  const std::size_t rk_blocks = info.rk_count, full_blocks = info.full_count;
  const double mem_mb = info.compressed_size * sizeof(double) / 1048576.0;
  const double pct = 100.0 * static_cast<double>(info.compressed_size) / static_cast<double>(info.uncompressed_size);
  std::fprintf(stderr, "assembly: %.2f s, %.2f cores busy on average (CPU / wall) (tree + block structure %.2f s); %zu rk and %zu full leaves, %d block-tree nodes; "
                       "%.1f MB (%.2f %% of dense), full leaves %.1f MB; largest rk block by memory %dx%d of rank %d; "
                       "callbacks: %ld rows, %ld columns (%ld served from node rows/columns already filled), %ld blocks; "
                       "%.3g node pairs = %.2f x n^2 evaluated (%d threads)\n",
               t_assembly, cpu_assembly / t_assembly, t_tree, info.rk_count, info.full_count, info.nr_block_clusters, mem_mb, pct, info.full_size * sizeof(double) / 1048576.0,
               info.largest_rk_mem_rows, info.largest_rk_mem_cols, info.largest_rk_mem_rank, A.row_requests, A.col_requests, A.cache_hits,
               A.block_requests, A.node_pairs, A.node_pairs / (static_cast<double>(n) * n), threads);

  // H-LU.
  hmat_factorization_context_t fctx;
  hmat_factorization_context_init(&fctx);
  fctx.factorization = hmat_factorization_lu;
  fctx.progress = nullptr;
  const double cpu1 = cpu_seconds();
  timer.restart();
  check_rc(hmat.factorize_generic(H, &fctx), "LU factorization");
  const double t_factor = timer.seconds(), cpu_factor = cpu_seconds() - cpu1;
  check_rc(hmat.get_info(H, &info), "get_info");
  const double factor_mb = info.compressed_size * sizeof(double) / 1048576.0;
  std::fprintf(stderr, "H-LU: %.2f s, %.2f cores busy on average; factors %.1f MB (%zu rk and %zu full leaves; largest rk block by memory %dx%d of rank %d)\n", t_factor,
               cpu_factor / t_factor, factor_mb, info.rk_count, info.full_count, info.largest_rk_mem_rows, info.largest_rk_mem_cols, info.largest_rk_mem_rank);

  // Solve (hmat-oss permutes b to its numbering and back).
  std::vector<double> x = prep.b;
  timer.restart();
  check_rc(hmat.solve_systems(H, x.data(), 1), "solve");
  const double t_solve = timer.seconds();
  const double t_hmat = hmat_timer.seconds(), other = (machine_busy_seconds() - busy0 - (cpu_seconds() - cpu0)) / t_hmat;
  const double sample_res = sampled_residual(prep, x);
  const double rss = bench::peak_rss_mb();
  std::fprintf(stderr, "solve: %.3f s; residual on the %zu sampled nodes (true rows) %.3e; peak RSS %.0f MB\n", t_solve, prep.sample.size(),
               sample_res, rss);
  std::fprintf(stderr, "threads: hmat-oss's default engine is sequential (it sets OpenMP to 1 thread during assembly and "
                       "factorization; an OpenMP BLAS follows, a pthread one does not); BLAS: %s; entry callbacks and prep: %d OpenMP "
                       "threads; other processes kept %.2f cores busy during the hmat-oss part\n", blas_description().c_str(), threads, other);
  hmat.destroy(H);
  hmat_delete_cluster_tree(tree);
  hmat.finalize();

  const bench::DenseFigures d = bench::dense_figures(dense, op, sel, x);
  std::printf("%s,%d,%.0e,%d,%g,%d,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.4f,%.1f,%.1f,%.2f,%zu,%zu,%.0f,%.3e,%.3e,%.2f,%.2f,%.2f\n",
              mesh_path.substr(mesh_path.find_last_of('/') + 1).c_str(), N, tol, leaf, eta, threads, d.t_assembly, d.t_lu, t_prep, t_tree, t_assembly,
              t_factor, t_solve, mem_mb, factor_mb, pct, rk_blocks, full_blocks, rss, d.rel_diff, sample_res,
              cpu_assembly / t_assembly, cpu_factor / t_factor, other);
  return 0;
} catch (const std::exception &e) {
  std::fprintf(stderr, "bench_hmat: %s\n", e.what());
  return 1;
}
