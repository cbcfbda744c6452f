// Entries-only HSS compression of K = [H, G(, Gn)] with proxy spheres (see bem_compression.hpp).
#include "hssbem/hss/bem_compression.hpp"

#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/interpolative.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/core/phase.hpp"
#include "hssbem/hss/kernel_blocks.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace hssbem {

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

int thread_index()
{
#ifdef _OPENMP
  return omp_get_thread_num();
#else
  return 0;
#endif
}

int max_threads()
{
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

/// n nearly uniform points on the unit sphere (Fibonacci lattice).
std::vector<Vec3> unit_sphere_points(int n)
{
  std::vector<Vec3> p(n);
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / n, r = std::sqrt(std::max(0.0, 1.0 - z * z)), phi = golden * i;
    p[i] = {r * std::cos(phi), r * std::sin(phi), z};
  }
  return p;
}

/// Where each cluster's quadrature reaches (DESIGN §5, "near field"): the balls that decide which
/// rows and columns a proxy sphere may stand in for.
struct Reach {
  std::vector<double> sigma;    ///< per node (mesh order): every support triangle's near ball lies within this distance of the vertex
  std::vector<double> h;        ///< per node: largest support triangle diameter
  std::vector<double> row_r;    ///< per cluster: radius of its collocation points around the centre
  std::vector<double> src_r;    ///< per cluster: radius of its support triangles around the centre
  std::vector<double> reach_r;  ///< per cluster: radius of its support triangles' near balls
};

Reach compute_reach(const BemOperator &op, const ClusterTree &tree)
{
  const Discretization &disc = op.discretization();
  const double ratio = op.quadrature_options().near_ratio * (1.0 + 1e-9) + 1e-12;
  const int nn = disc.num_nodes();
  Reach r;
  r.sigma.assign(nn, 0.0);
  r.h.assign(nn, 0.0);
  for (int j = 0; j < nn; ++j) {
    const Vec3 &s = disc.node_position(j);
    for (const int *t = disc.support_begin(j); t != disc.support_end(j); ++t) {
      const Triangle &tri = op.triangle(*t);
      const Vec3 c = (1.0 / 3) * (tri.p[0] + tri.p[1] + tri.p[2]);
      const double d = std::max({norm(tri.p[1] - tri.p[0]), norm(tri.p[2] - tri.p[1]), norm(tri.p[0] - tri.p[2])});
      r.h[j] = std::max(r.h[j], d);
      r.sigma[j] = std::max(r.sigma[j], norm(c - s) + ratio * d);
    }
  }
  const int nc = tree.num_clusters();
  r.row_r.assign(nc, 0.0);
  r.src_r.assign(nc, 0.0);
  r.reach_r.assign(nc, 0.0);
  for (int c = 0; c < nc; ++c) {
    const Cluster &cl = tree.cluster(c);
    for (int k = cl.begin; k < cl.end; ++k) {
      const int j = tree.perm()[k];
      const double d = norm(disc.node_position(j) - cl.centre);
      r.row_r[c] = std::max(r.row_r[c], norm(disc.node(j).point - cl.centre));
      r.src_r[c] = std::max(r.src_r[c], d + r.h[j]);
      r.reach_r[c] = std::max(r.reach_r[c], d + r.sigma[j]);
    }
  }
  return r;
}

/// Rigid-body coupling structure: the columns (nodes) of each row's term and the rows of each column.
struct RigidPattern {
  std::vector<std::vector<int>> cols_of_row, rows_of_col;
};

RigidPattern rigid_pattern(const BemOperator &op)
{
  const int nn = op.num_nodes();
  RigidPattern p;
  p.cols_of_row.resize(nn);
  p.rows_of_col.resize(nn);
  for (int i = 0; i < nn; ++i) {
    int cols[3];
    double w[3];
    const int n = op.rigid_body_columns(i, cols, w);
    for (int a = 0; a < n; ++a) {
      p.cols_of_row[i].push_back(cols[a]);
      p.rows_of_col[cols[a]].push_back(i);
    }
  }
  return p;
}

/// A skeleton chosen from candidates: local indices and the interpolation matrix (candidates × k).
struct Skeleton {
  std::vector<int> local; ///< forced candidates first
  DenseMatrix W;
  int forced = 0;
};

/// Column ID of X (features × candidates, column-major) with the `forced` candidates always in
/// the skeleton (and interpolating nothing): the others are interpolated from the other skeleton
/// candidates only, so a forced candidate's exceptional entries never leak into its neighbours.
Skeleton select_skeleton(std::vector<double> &X, int nfeat, int ncand, const std::vector<char> &forced, const IdOptions &id)
{
  std::vector<int> free_idx, forced_idx;
  for (int q = 0; q < ncand; ++q) (forced[q] ? forced_idx : free_idx).push_back(q);
  const int nfree = static_cast<int>(free_idx.size()), nforced = static_cast<int>(forced_idx.size());
  ColumnId cid;
  if (nfree > 0 && nfeat > 0) {
    // Gather the free columns.
    std::vector<double> Xf(static_cast<std::size_t>(nfeat) * nfree);
    for (int q = 0; q < nfree; ++q) std::copy(&X[static_cast<std::size_t>(free_idx[q]) * nfeat], &X[static_cast<std::size_t>(free_idx[q] + 1) * nfeat], &Xf[static_cast<std::size_t>(q) * nfeat]);
    cid = column_id(Xf.data(), nfeat, nfree, nfeat, id);
  } else if (nfree > 0) {
    cid.redundant.resize(nfree);
    for (int q = 0; q < nfree; ++q) cid.redundant[q] = q;
  }
  const int k = nforced + cid.rank();
  Skeleton s;
  s.forced = nforced;
  s.W = DenseMatrix(ncand, k);
  for (int t = 0; t < nforced; ++t) {
    s.local.push_back(forced_idx[t]);
    s.W(forced_idx[t], t) = 1.0;
  }
  for (int t = 0; t < cid.rank(); ++t) {
    s.local.push_back(free_idx[cid.skeleton[t]]);
    s.W(free_idx[cid.skeleton[t]], nforced + t) = 1.0;
  }
  for (std::size_t j = 0; j < cid.redundant.size(); ++j)
    for (int t = 0; t < cid.rank(); ++t) s.W(free_idx[cid.redundant[j]], nforced + t) = cid.T[t + j * static_cast<std::size_t>(cid.rank())];
  return s;
}

std::vector<double> col_scales(const HssMatrix &K)
{
  std::vector<double> s(K.col_block());
  for (int q = 0; q < K.col_block(); ++q) s[q] = K.col_scale(q);
  return s;
}

class Compressor {
public:
  Compressor(const BemOperator &op, const HssOptions &opt, HssMatrix &K)
    : m_op(op), m_opt(opt), m_K(K), m_tree(K.tree()), m_w(K.col_block()),
      m_eval(op, K.tree(), K.col_block(), col_scales(K)), m_reach(compute_reach(op, K.tree())),
      m_rigid(rigid_pattern(op))
  {
    const int np = opt.proxy_points > 0 ? opt.proxy_points : default_proxy_points(opt.rel_tol);
    m_sphere = unit_sphere_points(np);
    m_K.stats().proxy_points = np;
    double area = 0;
    for (int t = 0; t < op.discretization().mesh().num_triangles(); ++t) area += op.triangle(t).area;
    m_node_area = area / std::max(1, op.num_nodes());
    for (int t = 0; t < max_threads(); ++t) m_ws.push_back(std::make_unique<BemOperator::Workspace>(op));
    m_entries.assign(max_threads(), 0);
    m_t_near.assign(max_threads(), 0.0);
    m_t_id.assign(max_threads(), 0.0);
  }

  /// Skeletons and couplings, level by level from the leaves up.
  void skeletonize()
  {
    for (int l = m_tree.levels() - 1; l >= 1; --l) {
      skeletonize_level(l);
      const auto t0 = std::chrono::steady_clock::now();
      for_each_cluster(m_tree.clusters_at_level(l - 1), [this](int c) { couple_children(c); });
      m_K.stats().time_couplings += seconds_since(t0);
    }
  }

  /// The leaves' diagonal blocks (true entries), then the totals of the per-thread counters.
  void fill_leaves()
  {
    const auto t0 = std::chrono::steady_clock::now();
    for_each_cluster(m_tree.leaves(), [this](int c) { fill_leaf(c); });
    m_K.stats().time_leaves = seconds_since(t0);
    for (int t = 0; t < max_threads(); ++t) {
      m_K.stats().entries_evaluated += m_entries[t];
      m_K.stats().time_near_field += m_t_near[t];
      m_K.stats().time_ids += m_t_id[t];
    }
  }

private:
  BemOperator::Workspace &ws() { return *m_ws[thread_index()]; }

  bool inside(int c, int pos) const { return pos >= m_tree.cluster(c).begin && pos < m_tree.cluster(c).end; }

  /// A row (node) is forced into c's skeleton when its rigid-body term reaches a column outside c.
  bool row_forced(int c, int node) const
  {
    for (int j : m_rigid.cols_of_row[node])
      if (!inside(c, m_tree.iperm()[j])) return true;
    return false;
  }
  bool col_forced(int c, int node) const
  {
    for (int i : m_rigid.rows_of_col[node])
      if (!inside(c, m_tree.iperm()[i])) return true;
    return false;
  }

  /// The clusters whose candidates are active while level l is skeletonized: those of level l and
  /// the leaves above it.
  std::vector<int> frontier(int l) const
  {
    std::vector<int> f = m_tree.clusters_at_level(l);
    for (int c : m_tree.leaves())
      if (m_tree.cluster(c).level < l) f.push_back(c);
    return f;
  }

  void skeletonize_level(int l)
  {
    const std::vector<int> front = frontier(l);
    m_active_rows.assign(m_tree.num_clusters(), {});
    m_active_cols.assign(m_tree.num_clusters(), {});
    for (int c : front) {
      m_active_rows[c] = m_K.candidate_rows(c);
      m_active_cols[c] = m_K.candidate_cols(c);
    }
    for_each_cluster(m_tree.clusters_at_level(l), [this, &front](int c) { skeletonize(c, front); });
  }

  void skeletonize(int c, const std::vector<int> &front)
  {
    const Discretization &disc = m_op.discretization();
    const Cluster &cl = m_tree.cluster(c);
    const auto &perm = m_tree.perm();
    const std::vector<int> &rows = m_active_rows[c], &cols = m_active_cols[c];
    const int nrow = static_cast<int>(rows.size()), ncol = static_cast<int>(cols.size());
    double h_max = 0;
    for (int k = cl.begin; k < cl.end; ++k) h_max = std::max(h_max, m_reach.h[perm[k]]);
    const double r_row = m_opt.proxy_ratio * std::max(m_reach.row_r[c], h_max);
    const double r_col = std::max(m_opt.proxy_ratio * m_reach.src_r[c], m_reach.reach_r[c]);
    const int np = static_cast<int>(m_sphere.size());
    const double w_row = std::sqrt(4 * M_PI * r_row * r_row / np / m_node_area) * m_node_area;
    const double w_col = std::sqrt(4 * M_PI * r_col * r_col / np / m_node_area);

    auto t0 = std::chrono::steady_clock::now();
    // Near columns (for the row skeleton) and near rows (for the column skeleton).
    std::vector<int> near_cols, near_rows;
    for (int o : front) {
      if (o == c) continue;
      const Cluster &oc = m_tree.cluster(o);
      const double d = norm(oc.centre - cl.centre);
      if (d - m_reach.reach_r[o] < r_row)
        for (int q : m_active_cols[o]) {
          const int j = perm[q / m_w];
          if (norm(disc.node_position(j) - cl.centre) - m_reach.sigma[j] < r_row) near_cols.push_back(q);
        }
      if (d - m_reach.row_r[o] < r_col)
        for (int r : m_active_rows[o])
          if (norm(disc.node(perm[r / 3]).point - cl.centre) < r_col) near_rows.push_back(r);
    }
    // Row skeleton: features of candidate row r = proxy sources, then near columns.
    const int nfr = 3 * np + static_cast<int>(near_cols.size());
    std::vector<double> X(static_cast<std::size_t>(nfr) * nrow);
    {
      const Material &mat = m_op.material();
      const double cu = 1.0 / (16 * M_PI * mat.mu() * (1 - mat.nu)), diag = 3 - 4 * mat.nu;
      for (int q = 0; q < nrow; ++q) {
        const Vec3 &x = disc.node(perm[rows[q] / 3]).point;
        const int a = rows[q] % 3;
        double *f = &X[static_cast<std::size_t>(q) * nfr];
        for (int p = 0; p < np; ++p) {
          const Vec3 d = x - (cl.centre + r_row * m_sphere[p]);
          const double r2 = dot(d, d), ir = 1.0 / std::sqrt(r2);
          for (int b = 0; b < 3; ++b) f[3 * p + b] = w_row * cu * ir * ((a == b ? diag : 0.0) + d[a] * d[b] / r2);
        }
      }
      m_eval.block(rows, near_cols, X.data() + 3 * np, nfr, 1, ws());
      m_entries[thread_index()] += static_cast<long long>(nrow) * (nfr - 3 * np);
    }
    // Column skeleton: features of candidate column q = fields at the proxy points, then near rows.
    const int nfc = 3 * np + static_cast<int>(near_rows.size());
    std::vector<double> Y(static_cast<std::size_t>(nfc) * ncol);
    {
      std::vector<Vec3> P(np);
      for (int p = 0; p < np; ++p) P[p] = cl.centre + r_col * m_sphere[p];
      m_eval.at_points(P, cols, Y.data(), 1, nfc, ws());
      for (int q = 0; q < ncol; ++q)
        for (int f = 0; f < 3 * np; ++f) Y[f + static_cast<std::size_t>(q) * nfc] *= w_col;
      m_eval.block(near_rows, cols, Y.data() + 3 * np, 1, nfc, ws());
      m_entries[thread_index()] += static_cast<long long>(nfc) * ncol;
    }
    m_t_near[thread_index()] += seconds_since(t0);

    t0 = std::chrono::steady_clock::now();
    const IdOptions id{m_opt.rel_tol, m_opt.max_rank};
    std::vector<char> forced(nrow);
    for (int q = 0; q < nrow; ++q) forced[q] = row_forced(c, perm[rows[q] / 3]);
    Skeleton rs = select_skeleton(X, nfr, nrow, forced, id);
    forced.assign(ncol, 0);
    for (int q = 0; q < ncol; ++q) forced[q] = cols[q] % m_w < 3 && col_forced(c, perm[cols[q] / m_w]);
    Skeleton cs = select_skeleton(Y, nfc, ncol, forced, id);
    HssCluster &h = m_K.cluster(c);
    h.row_skel.clear();
    for (int q : rs.local) h.row_skel.push_back(rows[q]);
    h.col_skel.clear();
    for (int q : cs.local) h.col_skel.push_back(cols[q]);
    h.U = std::move(rs.W);
    h.V = std::move(cs.W);
    h.row_forced = rs.forced;
    h.col_forced = cs.forced;
    m_t_id[thread_index()] += seconds_since(t0);
  }

  void couple_children(int c)
  {
    const Cluster &cl = m_tree.cluster(c);
    if (cl.left < 0) return;
    HssCluster &h = m_K.cluster(c);
    const HssCluster &a = m_K.cluster(cl.left), &b = m_K.cluster(cl.right);
    h.B12 = DenseMatrix(static_cast<int>(a.row_skel.size()), static_cast<int>(b.col_skel.size()));
    h.B21 = DenseMatrix(static_cast<int>(b.row_skel.size()), static_cast<int>(a.col_skel.size()));
    m_eval.block(a.row_skel, b.col_skel, h.B12.data(), 1, h.B12.ld(), ws());
    m_eval.block(b.row_skel, a.col_skel, h.B21.data(), 1, h.B21.ld(), ws());
    m_entries[thread_index()] += static_cast<long long>(h.B12.a.size() + h.B21.a.size());
  }

  void fill_leaf(int c)
  {
    HssCluster &h = m_K.cluster(c);
    const std::vector<int> rows = m_K.candidate_rows(c), cols = m_K.candidate_cols(c);
    h.D = DenseMatrix(static_cast<int>(rows.size()), static_cast<int>(cols.size()));
    m_eval.block(rows, cols, h.D.data(), 1, h.D.ld(), ws());
    m_entries[thread_index()] += static_cast<long long>(h.D.a.size());
  }

  const BemOperator &m_op;
  const HssOptions &m_opt;
  HssMatrix &m_K;
  const ClusterTree &m_tree;
  const int m_w;
  KernelBlocks m_eval;
  Reach m_reach;
  RigidPattern m_rigid;
  std::vector<Vec3> m_sphere;
  double m_node_area = 1;
  std::vector<std::unique_ptr<BemOperator::Workspace>> m_ws;
  std::vector<long long> m_entries;
  std::vector<double> m_t_near, m_t_id;
  std::vector<std::vector<int>> m_active_rows, m_active_cols;
};

/// Rigid-body terms by a fast matvec (D_i = −Σ_j H⁰(i, j)), then added where they belong: a
/// leaf's diagonal block, or the skeleton coupling of the two clusters that separate row and column.
void add_rigid_body_terms(const BemOperator &op, HssMatrix &K)
{
  const ClusterTree &tree = K.tree();
  const int n = tree.num_points(), w = K.col_block();
  std::vector<double> X(static_cast<std::size_t>(w) * n * 3, 0.0), Y(static_cast<std::size_t>(3) * n * 3);
  for (int k = 0; k < n; ++k)
    for (int c = 0; c < 3; ++c) X[static_cast<std::size_t>(w) * k + c + static_cast<std::size_t>(c) * w * n] = 1.0;
  K.apply(X.data(), w * n, Y.data(), 3 * n, 3);
  std::vector<int> leaf_of(n);
  for (int c : tree.leaves())
    for (int k = tree.cluster(c).begin; k < tree.cluster(c).end; ++k) leaf_of[k] = c;
  auto position = [](const std::vector<int> &list, int value) {
    const auto it = std::find(list.begin(), list.end(), value);
    if (it == list.end()) throw std::logic_error("HSS compression: a rigid-body coupling is missing from a skeleton");
    return static_cast<int>(it - list.begin());
  };
  for (int i = 0; i < op.num_nodes(); ++i) {
    const int pi = tree.iperm()[i];
    double Dm[3][3];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) Dm[r][c] = -Y[3 * static_cast<std::size_t>(pi) + r + static_cast<std::size_t>(c) * 3 * n];
    int cols[3];
    double wts[3];
    const int nc = op.rigid_body_columns(i, cols, wts);
    for (int a = 0; a < nc; ++a) {
      const int pj = tree.iperm()[cols[a]];
      int ci = leaf_of[pi];
      if (leaf_of[pj] == ci) {
        const Cluster &cl = tree.cluster(ci);
        DenseMatrix &D = K.cluster(ci).D;
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) D(3 * (pi - cl.begin) + r, w * (pj - cl.begin) + c) += wts[a] * Dm[r][c];
        continue;
      }
      // Climb to the child of the lowest common ancestor that holds the row.
      while (true) {
        const int p = tree.cluster(ci).parent;
        if (pj >= tree.cluster(p).begin && pj < tree.cluster(p).end) break;
        ci = p;
      }
      const int parent = tree.cluster(ci).parent;
      const bool left = tree.cluster(parent).left == ci;
      const int cj = left ? tree.cluster(parent).right : tree.cluster(parent).left;
      DenseMatrix &B = left ? K.cluster(parent).B12 : K.cluster(parent).B21;
      for (int r = 0; r < 3; ++r) {
        const int row = position(K.cluster(ci).row_skel, 3 * pi + r);
        for (int c = 0; c < 3; ++c) B(row, position(K.cluster(cj).col_skel, w * pj + c)) += wts[a] * Dm[r][c];
      }
    }
  }
}

/// Column scales that give the G (and Gn) part of K the Frobenius norm of the H part on a sample
/// of rows and columns spread over the mesh: G ~ 1/(μ r) and H ~ 1/r² differ by orders of
/// magnitude, and one relative tolerance should resolve both.
std::vector<double> balancing_scales(const BemOperator &op, int w)
{
  const int n = op.num_nodes();
  std::vector<int> rows, cols;
  for (int i = 0; i < n; i += std::max(1, n / 40)) rows.push_back(i);
  for (int j = 0; j < n; j += std::max(1, n / 400)) cols.push_back(j);
  const std::size_t ld = 3 * cols.size();
  std::vector<double> H(3 * rows.size() * ld), G(H.size()), Gn(w > 6 ? 3 * rows.size() * cols.size() : 0);
  BemOperator::Workspace ws(op);
  op.fill_hg_without_rigid(rows, cols, H.data(), G.data(), static_cast<long>(ld), w > 6 ? Gn.data() : nullptr, static_cast<long>(cols.size()), ws);
  double h2 = 0, g2 = 0, gn2 = 0;
  for (std::size_t k = 0; k < H.size(); ++k) h2 += H[k] * H[k], g2 += G[k] * G[k];
  for (double v : Gn) gn2 += v * v;
  std::vector<double> s(w, 1.0);
  for (int q = 3; q < 6; ++q) s[q] = g2 > 0 ? std::sqrt(h2 / g2) : 1.0;
  if (w > 6) s[6] = gn2 > 0 ? std::sqrt(h2 / (3 * gn2)) : 1.0; // one Gn column per node against three of H
  return s;
}

} // namespace

int default_proxy_points(double rel_tol)
{
  // Enough points to resolve the far field's spherical harmonics up to the degree where they
  // fall below the tolerance (they decay like (1/proxy_ratio)^degree); measured on the test meshes.
  const double digits = std::max(1.0, -std::log10(rel_tol));
  return std::clamp(static_cast<int>(std::lround(6.0 * digits * digits + 40)), 64, 1024);
}

HssMatrix compress_bem_operator(const BemOperator &op, const HssOptions &options)
{
  if (!(options.rel_tol > 0 && options.rel_tol < 1)) throw std::invalid_argument("HSS: the relative tolerance must lie in (0, 1)");
  if (options.leaf_size < 1) throw std::invalid_argument("HSS: the leaf size must be at least 1");
  if (!(options.proxy_ratio > 1)) throw std::invalid_argument("HSS: the proxy ratio must exceed 1");
  if (options.max_rank == 0 || options.max_rank < -1) throw std::invalid_argument("HSS: the rank cap must be positive (or -1 for none)");
  if (op.quadrature_options().far_ratio > 0)
    throw std::invalid_argument("HSS: the 3-point far rule (-mat_bem_far_ratio) breaks the smooth far field the compression relies on; set it to 0");
  auto t0 = std::chrono::steady_clock::now();
  const Discretization &disc = op.discretization();
  std::vector<Vec3> points(disc.num_nodes());
  for (int i = 0; i < disc.num_nodes(); ++i) points[i] = disc.node(i).point;
  std::optional<PhaseScope> phase(Phase::Tree);
  HssMatrix K(ClusterTree(points, ClusterTreeOptions{options.leaf_size}), 3, k_columns_per_node(options.pressure_columns));
  phase.reset();
  phase.emplace(Phase::Compression);
  K.set_col_scales(balancing_scales(op, K.col_block()));
  K.stats().time_tree = seconds_since(t0);
  Compressor compressor(op, options, K);
  compressor.skeletonize();
  phase.reset();
  phase.emplace(Phase::NearField);
  compressor.fill_leaves();
  t0 = std::chrono::steady_clock::now();
  add_rigid_body_terms(op, K);
  K.stats().time_rigid = seconds_since(t0);
  phase.reset();
  K.update_stats();
  return K;
}

} // namespace hssbem
