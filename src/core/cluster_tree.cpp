#include "hssbem/core/cluster_tree.hpp"
#include "hssbem/core/lapack.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace hssbem {

namespace {

/// Projection of a point on the splitting axis, its node index (which breaks ties, so that the
/// order is strict and the median split unique even for coincident points) and its offset in the
/// cluster being split.
struct Key {
  double proj;
  int node;
  int offset;
  bool operator<(const Key &o) const { return proj < o.proj || (proj == o.proj && node < o.node); }
};

/// Scratch of the construction. The coordinates are kept in cluster order, moved along with the
/// permutation, so that every pass over a cluster streams through memory instead of gathering
/// through the permutation (twice as fast at 10^6 points in random order).
struct Workspace {
  std::vector<Vec3> x;   ///< x[k] = points[perm[k]]
  std::vector<Key> keys; ///< projections of the cluster being split
  std::vector<Vec3> tmp; ///< its coordinates while they are reordered
};

void check_points(const std::vector<Vec3> &points, const ClusterTreeOptions &opts)
{
  if (points.empty()) throw std::invalid_argument("ClusterTree: no points");
  if (points.size() > static_cast<std::size_t>(INT_MAX))
    throw std::invalid_argument("ClusterTree: more points than an int can index");
  if (opts.leaf_size < 1)
    throw std::invalid_argument("ClusterTree: leaf_size must be >= 1, got " + std::to_string(opts.leaf_size));
  for (std::size_t i = 0; i < points.size(); ++i)
    for (double x : points[i])
      if (!std::isfinite(x)) throw std::invalid_argument("ClusterTree: point " + std::to_string(i) + " is not finite");
}

/// Start of each part's block in cluster order (size nparts + 1). Throws for a malformed
/// partition: wrong length, a label outside [0, nparts) or an empty part.
std::vector<int> part_offsets(const std::vector<int> &part, int nparts, std::size_t n)
{
  if (nparts < 1) throw std::invalid_argument("ClusterTree: nparts must be >= 1, got " + std::to_string(nparts));
  if (part.size() != n)
    throw std::invalid_argument("ClusterTree: partition has " + std::to_string(part.size()) + " entries for " +
                                std::to_string(n) + " points");
  std::vector<int> offsets(nparts + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (part[i] < 0 || part[i] >= nparts)
      throw std::invalid_argument("ClusterTree: point " + std::to_string(i) + " has part " + std::to_string(part[i]) +
                                  ", outside [0, " + std::to_string(nparts) + ")");
    ++offsets[part[i] + 1];
  }
  for (int p = 0; p < nparts; ++p) {
    if (offsets[p + 1] == 0) throw std::invalid_argument("ClusterTree: part " + std::to_string(p) + " is empty");
    offsets[p + 1] += offsets[p];
  }
  return offsets;
}

/// Nodes grouped by part (counting sort: parts in numbering order, ascending node index within).
std::vector<int> order_by_part(const std::vector<int> &part, std::vector<int> next)
{
  std::vector<int> perm(part.size());
  for (std::size_t i = 0; i < part.size(); ++i) perm[next[part[i]]++] = static_cast<int>(i);
  return perm;
}

bool is_power_of_two(int k) { return k > 0 && (k & (k - 1)) == 0; }

/// Where to cut the parts [p0, p1) into two non-empty halves: in the middle for a power-of-two
/// count (so that 2^k parts form one complete level), else where the point counts of the halves
/// differ least (the first such cut).
int split_parts(const std::vector<int> &offsets, int p0, int p1)
{
  if (is_power_of_two(p1 - p0)) return p0 + (p1 - p0) / 2;
  int best = p0 + 1;
  long long best_gap = LLONG_MAX;
  for (int k = p0 + 1; k < p1; ++k) {
    const long long gap = std::llabs(2LL * offsets[k] - offsets[p0] - offsets[p1]);
    if (gap < best_gap) best = k, best_gap = gap;
  }
  return best;
}

Vec3 mean_of(const Vec3 *x, int m)
{
  Vec3 mean{};
  for (int i = 0; i < m; ++i) mean = mean + x[i];
  return (1.0 / m) * mean;
}

/// Unit eigenvector of the largest eigenvalue of the points' covariance, signed so that its
/// largest component is positive (LAPACK's sign is arbitrary; this keeps "left" meaningful).
/// For a degenerate set (coincident points) any unit vector is returned; the split then falls
/// back on node indices.
Vec3 principal_axis(const Vec3 *x, int m, const Vec3 &mean)
{
  double a[9] = {}; // column-major, upper triangle used
  for (int i = 0; i < m; ++i) {
    const Vec3 d = x[i] - mean;
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r <= c; ++r) a[r + 3 * c] += d[r] * d[c];
  }
  double w[3];
  if (lapack::syev(3, a, w) != 0) throw std::runtime_error("ClusterTree: dsyev failed on a 3x3 covariance");
  Vec3 v = {a[6], a[7], a[8]}; // eigenvalues ascend: the last column is the principal axis
  int big = 0;
  for (int k = 1; k < 3; ++k)
    if (std::abs(v[k]) > std::abs(v[big])) big = k;
  return v[big] < 0 ? -1.0 * v : v;
}

/// Centroid and inertia (Σ |x − centroid|²) of the points keys[b, e) refer to.
std::pair<Vec3, double> centroid_and_inertia(const Vec3 *x, const std::vector<Key> &keys, int b, int e)
{
  Vec3 mean{};
  for (int i = b; i < e; ++i) mean = mean + x[keys[i].offset];
  mean = (1.0 / (e - b)) * mean;
  double sum = 0;
  for (int i = b; i < e; ++i) sum += dot(x[keys[i].offset] - mean, x[keys[i].offset] - mean);
  return {mean, sum};
}

/// Where to cut keys[0, m), split at its median m/2 on the splitting axis: at the median, or
/// within m/4 of it where the two sides' total inertia is at least 1 % lower (keys then sorted
/// there). The cut moves to a gap along the axis, e.g. between the two faces of a thin body whose
/// point counts differ, which no cut at the median can part: the points of one face left on the
/// other's side stay together down to a leaf that holds both faces. On the 20k disk organ such
/// leaves had up to 33 near leaves (the others 7-11); with the cut at the gap the most is 13, and
/// the first level of PC h2's factorization runs 22 % faster.
int best_cut(const Vec3 *x, int m, Workspace &ws)
{
  const int w = m / 4, lo = m / 2 - w, hi = m / 2 + w;
  if (w < 2) return m / 2;
  auto &k = ws.keys;
  std::nth_element(k.begin(), k.begin() + lo, k.begin() + m / 2);
  std::nth_element(k.begin() + m / 2, k.begin() + hi, k.begin() + m);
  std::sort(k.begin() + lo, k.begin() + hi);
  Vec3 s_all{}, s_left{};
  double q_all = 0, q_left = 0;
  for (int i = 0; i < m; ++i) {
    const Vec3 &p = x[k[i].offset];
    s_all = s_all + p;
    q_all += dot(p, p);
    if (i < lo) s_left = s_left + p, q_left += dot(p, p);
  }
  // inertia of the sides of a cut before position c: Σ|x|² − |Σx|²/n on each side
  const auto inertia_at = [&](int c, const Vec3 &sl, double ql) {
    const Vec3 sr = s_all - sl;
    return (ql - dot(sl, sl) / c) + ((q_all - ql) - dot(sr, sr) / (m - c));
  };
  int best = m / 2;
  double at_median = 0, lowest = HUGE_VAL;
  for (int c = lo; c <= hi; ++c) {
    const double h = inertia_at(c, s_left, q_left);
    if (c == m / 2) at_median = h;
    if (h < lowest) lowest = h, best = c;
    if (c < hi) {
      const Vec3 &p = x[k[c].offset];
      s_left = s_left + p;
      q_left += dot(p, p);
    }
  }
  return lowest < 0.99 * at_median ? best : m / 2;
}

/// Reorder the m points x[0, m) of a cluster, with their node indices idx[0, m), so that the first
/// `cut` (returned) are those with the smallest projections on the splitting axis (ties by node
/// index); without `refine` the axis is the principal one and the cut the median, m/2.
///
/// With `refine` the axis starts as the principal one and is then refined as in a two-means
/// clustering with halves of equal size: the axis through the two halves' centroids, split at its
/// median again, kept while it lowers the halves' total inertia (at most 10 rounds; the principal
/// split is the first candidate, so a cluster only gets more compact halves); the cut may then
/// move to a gap (best_cut). A principal axis is a poor cut where a cluster is not one round blob:
/// both faces of a thin body, tilted where they converge towards the rim, or a curved strip. On
/// the (1, 0.8, 0.3) disk organ of 80k unknowns the leaves' near blocks fell from 13.1 to 11.0 per
/// leaf with the axis alone (sphere: 10.4 to 10.0), and the 300k disk organ's H² matrix by 5 %.
int median_split(Vec3 *x, int *idx, int m, bool refine, Workspace &ws)
{
  const Vec3 mean = mean_of(x, m);
  const auto split_on = [&](const Vec3 &a) {
    for (int i = 0; i < m; ++i) ws.keys[i] = {dot(x[i] - mean, a), idx[i], i};
    std::nth_element(ws.keys.begin(), ws.keys.begin() + m / 2, ws.keys.begin() + m);
  };
  // The halves' total inertia and the unit vector from the first half's centroid to the second's.
  const auto halves = [&](Vec3 &towards) {
    const auto [c0, i0] = centroid_and_inertia(x, ws.keys, 0, m / 2);
    const auto [c1, i1] = centroid_and_inertia(x, ws.keys, m / 2, m);
    const double len = norm(c1 - c0);
    towards = len > 0 ? (1.0 / len) * (c1 - c0) : Vec3{};
    return i0 + i1;
  };
  Vec3 axis = principal_axis(x, m, mean), next;
  split_on(axis);
  if (refine && m >= 4) {
    double best = halves(next);
    for (int round = 0; round < 10 && norm(next) > 0 && dot(next, axis) < 1 - 1e-12; ++round) {
      const Vec3 tried = next;
      split_on(tried);
      const double h = halves(next);
      if (!(h < best * (1 - 1e-9))) {
        split_on(axis); // no better: back to the last axis kept
        break;
      }
      best = h;
      axis = tried;
    }
  }
  const int split = refine ? best_cut(x, m, ws) : m / 2;
  for (int i = 0; i < m; ++i) {
    idx[i] = ws.keys[i].node;
    ws.tmp[i] = x[ws.keys[i].offset];
  }
  std::copy_n(ws.tmp.begin(), m, x);
  return split;
}

} // namespace

ClusterTree::ClusterTree(const std::vector<Vec3> &points, const ClusterTreeOptions &opts) : m_opts(opts)
{
  check_points(points, opts);
  build(points, std::vector<int>(points.size(), 0), 1);
}

ClusterTree::ClusterTree(const std::vector<Vec3> &points, const std::vector<int> &part, int nparts,
                         const ClusterTreeOptions &opts)
    : m_opts(opts)
{
  check_points(points, opts);
  build(points, part, nparts);
}

void ClusterTree::build(const std::vector<Vec3> &points, const std::vector<int> &part, int nparts)
{
  const std::vector<int> offsets = part_offsets(part, nparts, points.size());
  m_perm = order_by_part(part, offsets);
  m_part_cluster.assign(nparts, -1);
  Workspace ws{std::vector<Vec3>(points.size()), std::vector<Key>(points.size()), std::vector<Vec3>(points.size())};
  for (std::size_t k = 0; k < points.size(); ++k) ws.x[k] = points[m_perm[k]];
  // Breadth first: children are appended behind the clusters still to be visited, so levels come
  // out consecutive. parts[c] is the range of parts under cluster c, empty below a part.
  m_clusters.assign(1, Cluster{0, static_cast<int>(points.size())});
  std::vector<std::pair<int, int>> parts{{0, nparts}};
  for (int c = 0; c < num_clusters(); ++c) {
    fit_bounds(c, ws.x.data());
    const auto [p0, p1] = parts[c];
    if (p1 - p0 > 1) {
      const int k = split_parts(offsets, p0, p1);
      add_children(c, offsets[k]);
      parts.push_back({p0, k});
      parts.push_back({k, p1});
      continue;
    }
    if (p1 - p0 == 1) m_part_cluster[p0] = c;
    const Cluster &cl = m_clusters[c];
    if (cl.size() <= m_opts.leaf_size) {
      finish_leaf(c);
      continue;
    }
    const int cut = median_split(ws.x.data() + cl.begin, m_perm.data() + cl.begin, cl.size(), m_opts.refine_splits, ws);
    add_children(c, cl.begin + cut);
    parts.push_back({p0, p0});
    parts.push_back({p0, p0});
  }
  m_iperm.assign(m_perm.size(), 0);
  for (int k = 0; k < num_points(); ++k) m_iperm[m_perm[k]] = k;
  index_levels_and_leaves();
}

/// Append the children [begin, split) and [split, end) of cluster c.
void ClusterTree::add_children(int c, int split)
{
  const int left = num_clusters();
  const Cluster parent = m_clusters[c]; // copy: push_back may reallocate
  for (auto [b, e] : {std::pair<int, int>{parent.begin, split}, std::pair<int, int>{split, parent.end}}) {
    Cluster child;
    child.begin = b;
    child.end = e;
    child.parent = c;
    child.level = parent.level + 1;
    m_clusters.push_back(child);
  }
  m_clusters[c].left = left;
  m_clusters[c].right = left + 1;
}

/// Bounding box, its centre and the radius of the sphere around that centre holding the points
/// (x: coordinates in cluster order).
void ClusterTree::fit_bounds(int c, const Vec3 *x)
{
  Cluster &cl = m_clusters[c];
  cl.lo = cl.hi = x[cl.begin];
  for (int k = cl.begin + 1; k < cl.end; ++k)
    for (int d = 0; d < 3; ++d) {
      cl.lo[d] = std::min(cl.lo[d], x[k][d]);
      cl.hi[d] = std::max(cl.hi[d], x[k][d]);
    }
  cl.centre = 0.5 * (cl.lo + cl.hi);
  double r2 = 0;
  for (int k = cl.begin; k < cl.end; ++k) r2 = std::max(r2, dot(x[k] - cl.centre, x[k] - cl.centre));
  cl.radius = std::sqrt(r2);
}

/// Within a leaf the order is free; ascending node index makes the permutation independent of how
/// nth_element arranged the halves, and keeps mesh neighbours close in memory. (The coordinates
/// in the workspace are not reordered along: a leaf's are no longer read.)
void ClusterTree::finish_leaf(int c)
{
  const Cluster &cl = m_clusters[c];
  std::sort(m_perm.begin() + cl.begin, m_perm.begin() + cl.end);
}

void ClusterTree::index_levels_and_leaves()
{
  m_levels.clear();
  m_leaves.clear();
  for (int c = 0; c < num_clusters(); ++c) {
    const int l = m_clusters[c].level;
    if (l >= levels()) m_levels.resize(l + 1);
    m_levels[l].push_back(c);
    if (is_leaf(c)) m_leaves.push_back(c);
  }
  std::sort(m_leaves.begin(), m_leaves.end(),
            [this](int a, int b) { return m_clusters[a].begin < m_clusters[b].begin; });
}

void ClusterTree::to_cluster_order(const double *in, double *out, int block) const
{
  if (block < 1) throw std::invalid_argument("ClusterTree::to_cluster_order: block must be >= 1");
  const std::size_t b = static_cast<std::size_t>(block);
  for (std::size_t k = 0; k < m_perm.size(); ++k) std::copy_n(in + b * m_perm[k], b, out + b * k);
}

void ClusterTree::to_mesh_order(const double *in, double *out, int block) const
{
  if (block < 1) throw std::invalid_argument("ClusterTree::to_mesh_order: block must be >= 1");
  const std::size_t b = static_cast<std::size_t>(block);
  for (std::size_t k = 0; k < m_perm.size(); ++k) std::copy_n(in + b * k, b, out + b * m_perm[k]);
}

bool ClusterTree::admissible(int a, int b, double eta) const
{
  if (!(eta >= 0)) throw std::invalid_argument("ClusterTree::admissible: eta must be >= 0");
  const Cluster &ca = m_clusters[a], &cb = m_clusters[b];
  return norm(ca.centre - cb.centre) > (1 + eta) * (ca.radius + cb.radius);
}

std::vector<int> ClusterTree::leaf_of_positions() const
{
  std::vector<int> leaf(num_points());
  for (int c : m_leaves)
    for (int k = m_clusters[c].begin; k < m_clusters[c].end; ++k) leaf[k] = c;
  return leaf;
}

} // namespace hssbem
