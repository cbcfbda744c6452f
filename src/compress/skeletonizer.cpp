// Proxy-sphere skeletonization of K = [H, G(, Gn)], one tree level at a time (see skeletonizer.hpp).
#include "hssbem/compress/skeletonizer.hpp"

#include "hssbem/compress/compression.hpp"

#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/interpolative.hpp"
#include "hssbem/core/timer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace hssbem {

namespace {

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
  if (nforced == 0 && nfeat > 0) {
    cid = column_id(X.data(), nfeat, ncand, nfeat, id);
  } else if (nfree > 0 && nfeat > 0) {
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

} // namespace

Skeletonizer::Skeletonizer(const BemOperator &op, const SkeletonizerOptions &opt, const ClusterTree &tree, int col_block, std::vector<double> col_scale,
                           std::vector<NestedBasis *> bases)
  : m_op(op), m_opt(opt), m_tree(tree), m_w(col_block), m_eval(op, tree, col_block, std::move(col_scale)), m_reach(quadrature_reach(op, tree)),
    m_bases(std::move(bases)), m_sphere(unit_sphere_points(opt.proxy_points))
{
  if (opt.force_rigid) {
    const int nn = op.num_nodes();
    m_cols_of_row.resize(nn);
    m_rows_of_col.resize(nn);
    for (int i = 0; i < nn; ++i) {
      int cols[3];
      double w[3];
      const int n = op.rigid_body_columns(i, cols, w);
      for (int a = 0; a < n; ++a) {
        m_cols_of_row[i].push_back(cols[a]);
        m_rows_of_col[cols[a]].push_back(i);
      }
    }
  }
  double area = 0;
  for (int t = 0; t < op.discretization().mesh().num_triangles(); ++t) area += op.triangle(t).area;
  m_node_area = area / std::max(1, op.num_nodes());
  for (int t = 0; t < max_threads(); ++t) m_ws.push_back(std::make_unique<BemOperator::Workspace>(op));
  m_entries.assign(max_threads(), 0);
  m_t_near.assign(max_threads(), 0.0);
  m_t_id.assign(max_threads(), 0.0);
}

Skeletonizer::~Skeletonizer() = default;

BemOperator::Workspace &Skeletonizer::ws() { return *m_ws[thread_index()]; }

long long Skeletonizer::entries() const
{
  long long s = 0;
  for (long long e : m_entries) s += e;
  return s;
}

double Skeletonizer::time_near_field() const
{
  double s = 0;
  for (double t : m_t_near) s += t;
  return s;
}

double Skeletonizer::time_ids() const
{
  double s = 0;
  for (double t : m_t_id) s += t;
  return s;
}

void Skeletonizer::all_others(int c, const std::vector<int> &front, std::vector<int> &out)
{
  for (int o : front)
    if (o != c) out.push_back(o);
}

void Skeletonizer::block(const std::vector<int> &rows, const std::vector<int> &cols, double *out, long rs, long cs)
{
  m_eval.block(rows, cols, out, rs, cs, ws());
  m_entries[thread_index()] += static_cast<long long>(rows.size()) * static_cast<long long>(cols.size());
}

/// A row (node) is forced into c's skeleton when its rigid-body term reaches a column outside c.
bool Skeletonizer::row_forced(int c, int node) const
{
  const Cluster &cl = m_tree.cluster(c);
  for (int j : m_cols_of_row[node]) {
    const int pos = m_tree.iperm()[j];
    if (pos < cl.begin || pos >= cl.end) return true;
  }
  return false;
}

bool Skeletonizer::col_forced(int c, int node) const
{
  const Cluster &cl = m_tree.cluster(c);
  for (int i : m_rows_of_col[node]) {
    const int pos = m_tree.iperm()[i];
    if (pos < cl.begin || pos >= cl.end) return true;
  }
  return false;
}

void Skeletonizer::skeletonize_level(int l, const Sources &sources, const std::vector<char> *need_rows, const std::vector<char> *need_cols, const std::vector<char> *skip,
                                     const LevelSync &sync)
{
  // The frontier: the clusters of level l and the leaves above it.
  std::vector<int> front = m_tree.clusters_at_level(l);
  for (int c : m_tree.leaves())
    if (m_tree.cluster(c).level < l) front.push_back(c);
  m_in_front.assign(m_tree.num_clusters(), 0);
  if (m_col_done.empty()) m_col_done.assign(m_tree.num_clusters(), 0);
  m_active_rows.assign(m_tree.num_clusters(), {});
  m_active_cols.assign(m_tree.num_clusters(), {});
  for (int c : front) {
    m_in_front[c] = 1;
    m_active_rows[c] = basis_candidates(m_tree, m_bases, c, 3, true);
    m_active_cols[c] = basis_candidates(m_tree, m_bases, c, m_w, false);
  }
  // The level's clusters skeletonized here.
  std::vector<int> level;
  for (int c : m_tree.clusters_at_level(l))
    if (!skip || !(*skip)[c]) level.push_back(c);
  std::vector<std::vector<int>> src(level.size());
  std::vector<int> index(level.size());
  std::iota(index.begin(), index.end(), 0);
  for_each_cluster(index, [&](int k) { sources(level[k], front, src[k]); });
  const auto rows = [&](int k) { skeletonize_rows(level[k], src[k], !need_rows || (*need_rows)[level[k]]); };
  const auto cols = [&](int k) { skeletonize_cols(level[k], src[k], !need_cols || (*need_cols)[level[k]]); };
  const auto synced_columns = [&] {
    if (!sync) return;
    sync(l, true);
    if (!m_opt.columns_first) return;
    for (int c : m_tree.clusters_at_level(l)) // as skeletonize_cols marks its own
      if (skip && (*skip)[c]) m_col_done[c] = !need_cols || (*need_cols)[c];
  };
  if (m_opt.columns_first) {
    // All of the level's column skeletons first: the row skeletons are then compressed against
    // the sources' column skeletons instead of their candidates (fewer explicit samples).
    for_each_cluster(index, cols);
    synced_columns();
    for_each_cluster(index, rows);
  } else {
    for_each_cluster(index, [&](int k) {
      cols(k);
      rows(k);
    });
    synced_columns();
  }
  if (sync) sync(l, false);
}

Skeletonizer::Spheres Skeletonizer::spheres(int c) const
{
  const Cluster &cl = m_tree.cluster(c);
  double h_max = 0;
  for (int k = cl.begin; k < cl.end; ++k) h_max = std::max(h_max, m_reach.h[m_tree.perm()[k]]);
  Spheres s;
  s.r_row = m_opt.proxy_ratio * std::max(m_reach.row_r[c], h_max);
  s.r_col = std::max(m_opt.proxy_ratio * m_reach.src_r[c], m_reach.reach_r[c]);
  const int np = static_cast<int>(m_sphere.size());
  s.w_row = std::sqrt(4 * M_PI * s.r_row * s.r_row / np / m_node_area) * m_node_area;
  s.w_col = std::sqrt(4 * M_PI * s.r_col * s.r_col / np / m_node_area);
  return s;
}

void Skeletonizer::skeletonize_rows(int c, const std::vector<int> &sources, bool need)
{
  const Discretization &disc = m_op.discretization();
  const Cluster &cl = m_tree.cluster(c);
  const auto &perm = m_tree.perm();
  const std::vector<int> &rows = m_active_rows[c];
  const int nrow = need ? static_cast<int>(rows.size()) : 0;
  const Spheres sp = spheres(c);
  const int np = static_cast<int>(m_sphere.size());

  Timer timer;
  // Columns of the sources whose quadrature reaches inside the proxy sphere. A source whose
  // columns are skeletonized already offers its skeleton (it stands for all of its columns
  // against anything outside its own proxy spheres), the others their candidates.
  // For the far blocks: per source, its columns' range in near_cols and their places in its list.
  std::vector<int> near_cols, near_place;
  std::vector<std::array<int, 3>> ranges; // source, first, end
  for (int o : sources) {
    if (nrow == 0) break;
    const Cluster &oc = m_tree.cluster(o);
    const std::vector<int> &o_cols = m_in_front[o] && !m_col_done[o] ? m_active_cols[o] : m_bases[o]->col_skel;
    if (norm(oc.centre - cl.centre) - m_reach.reach_r[o] >= sp.r_row) continue;
    const int first = static_cast<int>(near_cols.size());
    for (std::size_t t = 0; t < o_cols.size(); ++t) {
      const int q = o_cols[t], j = perm[q / m_w];
      if (norm(disc.node_position(j) - cl.centre) - m_reach.sigma[j] < sp.r_row) {
        near_cols.push_back(q);
        near_place.push_back(static_cast<int>(t));
      }
    }
    ranges.push_back({o, first, static_cast<int>(near_cols.size())});
  }
  // Features of candidate row r: Kelvin sources at the proxy points, then the near columns.
  const int nfr = 3 * np + static_cast<int>(near_cols.size());
  std::vector<double> X(static_cast<std::size_t>(nfr) * nrow);
  if (nrow > 0) {
    const Material &mat = m_op.material();
    const double cu = 1.0 / (16 * M_PI * mat.mu() * (1 - mat.nu)), diag = 3 - 4 * mat.nu;
    for (int q = 0; q < nrow; ++q) {
      const Vec3 &x = disc.node(perm[rows[q] / 3]).point;
      const int a = rows[q] % 3;
      double *f = &X[static_cast<std::size_t>(q) * nfr];
      for (int p = 0; p < np; ++p) {
        const Vec3 d = x - (cl.centre + sp.r_row * m_sphere[p]);
        const double r2 = dot(d, d), ir = 1.0 / std::sqrt(r2);
        for (int b = 0; b < 3; ++b) f[3 * p + b] = sp.w_row * cu * ir * ((a == b ? diag : 0.0) + d[a] * d[b] / r2);
      }
    }
    block(rows, near_cols, X.data() + 3 * np, nfr, 1);
  }
  m_t_near[thread_index()] += timer.seconds();
  timer.restart();
  std::vector<char> forced(nrow, 0);
  if (m_opt.force_rigid)
    for (int q = 0; q < nrow; ++q) forced[q] = row_forced(c, perm[rows[q] / 3]);
  Skeleton s = select_skeleton(X, nfr, nrow, forced, IdOptions{m_opt.rel_tol, m_opt.max_rank, m_opt.gram_ids});
  NestedBasis &h = *m_bases[c];
  h.row_skel.clear();
  for (int q : s.local) h.row_skel.push_back(rows[q]);
  h.U = need ? std::move(s.W) : DenseMatrix(static_cast<int>(rows.size()), 0);
  h.row_forced = s.forced;
  m_t_id[thread_index()] += timer.seconds();
  if (need && m_far_sink) far_blocks_from_samples(c, X, nfr, 3 * np, s.local, near_place, ranges);
}

void Skeletonizer::far_blocks_from_samples(int a, const std::vector<double> &X, int nfr, int first_col, const std::vector<int> &skel_local,
                                           const std::vector<int> &near_place, const std::vector<std::array<int, 3>> &ranges)
{
  const std::vector<int> &rows = m_bases[a]->row_skel;
  const int ka = static_cast<int>(rows.size());
  std::vector<int> missing, missing_at;
  std::vector<double> tmp;
  for (int b : (*m_far)[a]) {
    if (!m_in_front[b] || !m_col_done[b]) continue;
    const std::vector<int> &cols = m_bases[b]->col_skel;
    const int kb = static_cast<int>(cols.size());
    DenseMatrix M(ka, kb);
    std::vector<char> have(kb, 0);
    const auto r = std::find_if(ranges.begin(), ranges.end(), [b](const std::array<int, 3> &x) { return x[0] == b; });
    if (r != ranges.end())
      for (int pos = (*r)[1]; pos < (*r)[2]; ++pos) {
        const int t = near_place[pos];
        have[t] = 1;
        for (int i = 0; i < ka; ++i) M(i, t) = X[static_cast<std::size_t>(skel_local[i]) * nfr + first_col + pos];
      }
    missing.clear();
    missing_at.clear();
    for (int t = 0; t < kb; ++t)
      if (!have[t]) {
        missing.push_back(cols[t]);
        missing_at.push_back(t);
      }
    if (!missing.empty()) {
      tmp.assign(static_cast<std::size_t>(ka) * missing.size(), 0.0);
      block(rows, missing, tmp.data(), 1, ka);
      for (std::size_t u = 0; u < missing.size(); ++u)
        for (int i = 0; i < ka; ++i) M(i, missing_at[u]) = tmp[u * ka + i];
    }
    m_far_sink(a, b, M);
  }
}

void Skeletonizer::skeletonize_cols(int c, const std::vector<int> &sources, bool need)
{
  const Discretization &disc = m_op.discretization();
  const Cluster &cl = m_tree.cluster(c);
  const auto &perm = m_tree.perm();
  const std::vector<int> &cols = m_active_cols[c];
  const int ncol = need ? static_cast<int>(cols.size()) : 0;
  const Spheres sp = spheres(c);
  const int np = static_cast<int>(m_sphere.size());

  Timer timer;
  // Rows of the sources inside the proxy sphere (frontier sources: candidates; others: skeletons).
  std::vector<int> near_rows;
  for (int o : sources) {
    if (ncol == 0) break;
    const Cluster &oc = m_tree.cluster(o);
    const std::vector<int> &o_rows = m_in_front[o] ? m_active_rows[o] : m_bases[o]->row_skel;
    if (norm(oc.centre - cl.centre) - m_reach.row_r[o] >= sp.r_col) continue;
    for (int r : o_rows)
      if (norm(disc.node(perm[r / 3]).point - cl.centre) < sp.r_col) near_rows.push_back(r);
  }
  // Features of candidate column q: its field at the proxy points, then the near rows.
  const int nfc = 3 * np + static_cast<int>(near_rows.size());
  std::vector<double> Y(static_cast<std::size_t>(nfc) * ncol);
  if (ncol > 0) {
    std::vector<Vec3> P(np);
    for (int p = 0; p < np; ++p) P[p] = cl.centre + sp.r_col * m_sphere[p];
    m_eval.at_points(P, cols, Y.data(), 1, nfc, ws());
    m_entries[thread_index()] += static_cast<long long>(3 * np) * ncol;
    for (int q = 0; q < ncol; ++q)
      for (int f = 0; f < 3 * np; ++f) Y[f + static_cast<std::size_t>(q) * nfc] *= sp.w_col;
    block(near_rows, cols, Y.data() + 3 * np, 1, nfc);
  }
  m_t_near[thread_index()] += timer.seconds();

  timer.restart();
  std::vector<char> forced(ncol, 0);
  if (m_opt.force_rigid)
    for (int q = 0; q < ncol; ++q) forced[q] = cols[q] % m_w < 3 && col_forced(c, perm[cols[q] / m_w]);
  Skeleton s = select_skeleton(Y, nfc, ncol, forced, IdOptions{m_opt.rel_tol, m_opt.max_rank, m_opt.gram_ids});
  NestedBasis &h = *m_bases[c];
  h.col_skel.clear();
  for (int q : s.local) h.col_skel.push_back(cols[q]);
  h.V = need ? std::move(s.W) : DenseMatrix(static_cast<int>(cols.size()), 0);
  h.col_forced = s.forced;
  m_t_id[thread_index()] += timer.seconds();
  m_col_done[c] = m_opt.columns_first && need;
}

} // namespace hssbem
