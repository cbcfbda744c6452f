// Cluster tree: permutation, structure invariants, geometry, degenerate sets, top-level parts.
#include "hssbem/core/cluster_tree.hpp"
#include "hssbem/core/lapack.hpp"
#include "test_shapes.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>
#include <set>
#include <stdexcept>

using namespace hssbem;

namespace {

std::vector<Vec3> sphere_points(int levels, double r = 1.0, Vec3 centre = {0, 0, 0})
{
  return test::icosphere(levels, r, centre).vertices;
}

std::vector<Vec3> concat(std::vector<Vec3> a, const std::vector<Vec3> &b)
{
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

/// n random points in a rotated ellipse (semi-axes 10 along u and 1 along v) of the plane z = 0.
std::vector<Vec3> elongated_cloud(int n, Vec3 u, Vec3 v, unsigned seed = 7)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  std::vector<Vec3> x;
  while (static_cast<int>(x.size()) < n) {
    const double a = uni(rng), b = uni(rng);
    if (a * a + b * b <= 1) x.push_back(10 * a * u + b * v);
  }
  return x;
}

std::vector<Vec3> random_on_sphere(int n, unsigned seed = 3)
{
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  std::vector<Vec3> x(n);
  for (auto &p : x) p = normalized(Vec3{g(rng), g(rng), g(rng)});
  return x;
}

int ceil_log2(double q) { return q <= 1 ? 0 : static_cast<int>(std::ceil(std::log2(q) - 1e-12)); }

/// Every structural and geometric invariant that must hold for any tree.
void expect_valid_tree(const ClusterTree &t, const std::vector<Vec3> &x, int leaf_size)
{
  const int n = static_cast<int>(x.size());
  ASSERT_EQ(t.num_points(), n);
  // perm is a bijection and iperm its inverse
  std::vector<int> seen(n, 0);
  for (int k = 0; k < n; ++k) {
    ASSERT_GE(t.perm()[k], 0);
    ASSERT_LT(t.perm()[k], n);
    ++seen[t.perm()[k]];
    ASSERT_EQ(t.iperm()[t.perm()[k]], k);
  }
  for (int i = 0; i < n; ++i) ASSERT_EQ(seen[i], 1) << "node " << i;
  const Cluster &root = t.cluster(0);
  EXPECT_EQ(root.begin, 0);
  EXPECT_EQ(root.end, n);
  EXPECT_EQ(root.parent, -1);
  EXPECT_EQ(root.level, 0);
  // ASSERT: one broken cluster is reported once, not once per point
  for (int c = 0; c < t.num_clusters(); ++c) {
    const Cluster &cl = t.cluster(c);
    ASSERT_GE(cl.size(), 1) << "cluster " << c;
    if (t.is_leaf(c)) {
      ASSERT_EQ(cl.right, -1);
      ASSERT_LE(cl.size(), leaf_size) << "leaf " << c;
    } else {
      const Cluster &l = t.cluster(cl.left), &r = t.cluster(cl.right);
      ASSERT_GT(cl.size(), leaf_size);
      ASSERT_EQ(l.begin, cl.begin) << "cluster " << c;
      ASSERT_EQ(l.end, r.begin) << "cluster " << c;
      ASSERT_EQ(r.end, cl.end) << "cluster " << c;
      ASSERT_TRUE(l.parent == c && r.parent == c) << "cluster " << c;
      ASSERT_TRUE(l.level == cl.level + 1 && r.level == cl.level + 1) << "cluster " << c;
    }
    // the box is the tightest around the points; the sphere holds them and touches one
    double rmax = 0;
    Vec3 lo = x[t.perm()[cl.begin]], hi = lo;
    for (int k = cl.begin; k < cl.end; ++k) {
      const Vec3 &p = x[t.perm()[k]];
      for (int d = 0; d < 3; ++d) {
        lo[d] = std::min(lo[d], p[d]);
        hi[d] = std::max(hi[d], p[d]);
      }
      rmax = std::max(rmax, norm(p - cl.centre));
    }
    ASSERT_EQ(cl.lo, lo) << "cluster " << c;
    ASSERT_EQ(cl.hi, hi) << "cluster " << c;
    for (int d = 0; d < 3; ++d) ASSERT_DOUBLE_EQ(cl.centre[d], 0.5 * (lo[d] + hi[d])) << "cluster " << c;
    ASSERT_DOUBLE_EQ(cl.radius, rmax) << "cluster " << c;
  }
  // levels list every cluster once, left to right; leaves tile [0, n)
  int listed = 0;
  for (int l = 0; l < t.levels(); ++l) {
    int prev_end = -1;
    for (int c : t.clusters_at_level(l)) {
      EXPECT_EQ(t.cluster(c).level, l);
      EXPECT_GE(t.cluster(c).begin, prev_end);
      prev_end = t.cluster(c).end;
      ++listed;
    }
  }
  EXPECT_EQ(listed, t.num_clusters());
  int pos = 0;
  for (int c : t.leaves()) {
    EXPECT_TRUE(t.is_leaf(c));
    EXPECT_EQ(t.cluster(c).begin, pos);
    pos = t.cluster(c).end;
  }
  EXPECT_EQ(pos, n);
}

/// Children of a geometric split: with plain median splits they differ in size by at most one, the
/// left one not larger; with refined splits the cut lies within m/4 of the median (it moves off
/// the median only to a gap along the axis).
void expect_median_splits(const ClusterTree &t, int from_level = 0)
{
  for (int c = 0; c < t.num_clusters(); ++c) {
    const Cluster &cl = t.cluster(c);
    if (t.is_leaf(c) || cl.level < from_level) continue;
    const int m = cl.size(), a = t.cluster(cl.left).size(), b = t.cluster(cl.right).size();
    ASSERT_EQ(a + b, m);
    if (t.options().refine_splits) {
      ASSERT_GE(a, m / 2 - m / 4) << "cluster " << c << ": " << a << " + " << b;
      ASSERT_LE(a, m / 2 + m / 4) << "cluster " << c << ": " << a << " + " << b;
    } else {
      ASSERT_TRUE(b == a || b == a + 1) << "cluster " << c << ": " << a << " + " << b;
    }
  }
}

/// Depth of a tree of median splits: leaves at levels d-1 or d, d = ceil(log2(n / leaf)). With
/// refined splits (children between 1/4 and 3/4 of their parent) the leaves lie between the levels
/// a cut of 1/4 and one of 3/4 at every level would reach.
void expect_depth(const ClusterTree &t, int n, int leaf_size)
{
  const int d = ceil_log2(double(n) / leaf_size);
  if (!t.options().refine_splits) {
    EXPECT_EQ(t.levels(), d + 1) << "n = " << n << ", leaf = " << leaf_size;
    for (int c : t.leaves()) EXPECT_GE(t.cluster(c).level, d - 1);
    return;
  }
  const double q = std::log(double(n) / leaf_size);
  EXPECT_LE(t.levels() - 1, static_cast<int>(std::ceil(q / std::log(4.0 / 3.0))) + 1) << "n = " << n << ", leaf = " << leaf_size;
  for (int c : t.leaves()) EXPECT_GE(t.cluster(c).level, static_cast<int>(std::floor(q / std::log(4.0)))) << "n = " << n << ", leaf = " << leaf_size;
  EXPECT_GE(t.levels(), d) << "n = " << n << ", leaf = " << leaf_size;
}

/// The cluster whose points are exactly those with part[i] == p, or -1.
int cluster_of_part(const ClusterTree &t, const std::vector<int> &part, int p)
{
  const long count = std::count(part.begin(), part.end(), p);
  for (int c = 0; c < t.num_clusters(); ++c) {
    const Cluster &cl = t.cluster(c);
    if (cl.size() != count) continue;
    bool all = true;
    for (int k = cl.begin; k < cl.end && all; ++k) all = part[t.perm()[k]] == p;
    if (all) return c;
  }
  return -1;
}

bool same_tree(const ClusterTree &a, const ClusterTree &b)
{
  if (a.perm() != b.perm() || a.num_clusters() != b.num_clusters()) return false;
  for (int c = 0; c < a.num_clusters(); ++c) {
    const Cluster &p = a.cluster(c), &q = b.cluster(c);
    if (p.begin != q.begin || p.end != q.end || p.left != q.left || p.right != q.right || p.lo != q.lo ||
        p.hi != q.hi || p.radius != q.radius)
      return false;
  }
  return true;
}

} // namespace

TEST(ClusterTree, SphereSatisfiesAllInvariants)
{
  const auto x = sphere_points(4); // 2562 points
  for (int leaf : {1, 7, 32, 64}) {
    const ClusterTree t(x, ClusterTreeOptions{leaf});
    expect_valid_tree(t, x, leaf);
    expect_median_splits(t);
    expect_depth(t, static_cast<int>(x.size()), leaf);
  }
}

TEST(ClusterTree, CubeSatisfiesAllInvariants)
{
  const auto x = test::unit_cube(12).vertices;
  const ClusterTree t(x, ClusterTreeOptions{40});
  expect_valid_tree(t, x, 40);
  expect_median_splits(t);
  expect_depth(t, static_cast<int>(x.size()), 40);
}

TEST(ClusterTree, PointsOfALeafAreInNodeOrder)
{
  const auto x = sphere_points(3);
  const ClusterTree t(x, ClusterTreeOptions{16});
  for (int c : t.leaves())
    EXPECT_TRUE(std::is_sorted(t.perm().begin() + t.cluster(c).begin, t.perm().begin() + t.cluster(c).end));
}

TEST(ClusterTree, SplitsAlongThePrincipalAxis)
{
  // an ellipse elongated along u, not along a coordinate axis: only a split along u separates
  // the projections on u
  const Vec3 u = normalized(Vec3{1, 1, 1}), v = normalized(Vec3{1, -1, 0});
  const auto x = elongated_cloud(2000, u, v);
  const ClusterTree t(x, ClusterTreeOptions{50});
  const Cluster &root = t.cluster(0), &l = t.cluster(root.left), &r = t.cluster(root.right);
  double left_max = -1e300, right_min = 1e300;
  for (int k = l.begin; k < l.end; ++k) left_max = std::max(left_max, dot(x[t.perm()[k]], u));
  for (int k = r.begin; k < r.end; ++k) right_min = std::min(right_min, dot(x[t.perm()[k]], u));
  EXPECT_LE(left_max, right_min);
  EXPECT_NEAR(left_max, 0.0, 0.5); // the median of a symmetric cloud
  // the halves are the two ends of the ellipse: each spans about half its length
  EXPECT_LT(l.radius, 6.0);
  EXPECT_LT(r.radius, 6.0);
}

TEST(ClusterTree, DeterministicForTheSameInput)
{
  const auto x = concat(sphere_points(3), random_on_sphere(3000));
  const ClusterTree a(x, ClusterTreeOptions{20}), b(x, ClusterTreeOptions{20});
  EXPECT_TRUE(same_tree(a, b));
  std::vector<int> part(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) part[i] = int(i % 3);
  const ClusterTree c(x, part, 3, ClusterTreeOptions{20}), d(x, part, 3, ClusterTreeOptions{20});
  EXPECT_TRUE(same_tree(c, d));
  EXPECT_FALSE(same_tree(a, c));
}

TEST(ClusterTree, SinglePointIsARootLeaf)
{
  const std::vector<Vec3> x = {{1, 2, 3}};
  const ClusterTree t(x);
  expect_valid_tree(t, x, 64);
  EXPECT_EQ(t.num_clusters(), 1);
  EXPECT_EQ(t.levels(), 1);
  EXPECT_TRUE(t.is_leaf(0));
  EXPECT_EQ(t.leaves(), std::vector<int>{0});
  EXPECT_EQ(t.perm(), std::vector<int>{0});
  EXPECT_EQ(t.cluster(0).radius, 0.0);
  EXPECT_EQ(t.cluster(0).centre, (Vec3{1, 2, 3}));
}

TEST(ClusterTree, FewerPointsThanALeafIsARootLeaf)
{
  const auto x = sphere_points(1); // 42 points
  const ClusterTree t(x, ClusterTreeOptions{64});
  expect_valid_tree(t, x, 64);
  EXPECT_EQ(t.num_clusters(), 1);
  EXPECT_EQ(t.clusters_at_level(0), std::vector<int>{0});
  EXPECT_NEAR(t.cluster(0).radius, 1.0, 1e-12);
  const ClusterTree exact(x, ClusterTreeOptions{42});
  EXPECT_EQ(exact.num_clusters(), 1);
  const ClusterTree split(x, ClusterTreeOptions{41});
  EXPECT_EQ(split.num_clusters(), 3);
}

TEST(ClusterTree, CoincidentPointsStillSplitInBalance)
{
  const std::vector<Vec3> x(1000, Vec3{0.1, -0.3, 0.7});
  const ClusterTree t(x, ClusterTreeOptions{64});
  expect_valid_tree(t, x, 64);
  expect_median_splits(t);
  expect_depth(t, 1000, 64);
  for (int c = 0; c < t.num_clusters(); ++c) EXPECT_EQ(t.cluster(c).radius, 0.0);
  // ties fall back on node index: leaves are consecutive index ranges
  for (int k = 0; k < 1000; ++k) EXPECT_EQ(t.perm()[k], k);
}

TEST(ClusterTree, CollinearPoints)
{
  std::vector<Vec3> x;
  for (int i = 0; i < 777; ++i) x.push_back(Vec3{1, 2, 3} + (std::sin(0.37 * i) * 5) * normalized(Vec3{2, -1, 0.5}));
  const ClusterTree t(x, ClusterTreeOptions{10});
  expect_valid_tree(t, x, 10);
  expect_median_splits(t);
  expect_depth(t, 777, 10);
  // along a line, the leaves are disjoint segments: their spheres only touch between neighbours
  const auto &leaves = t.leaves();
  for (std::size_t i = 0; i + 2 < leaves.size(); i += 5) {
    const Cluster &a = t.cluster(leaves[i]), &b = t.cluster(leaves[i + 2]);
    if (a.radius > 0 && b.radius > 0) {
      EXPECT_GE(norm(a.centre - b.centre), a.radius + b.radius - 1e-12);
    }
  }
}

TEST(ClusterTree, FlatDisk)
{
  std::vector<Vec3> x;
  for (int i = 0; i < 60; ++i)
    for (int j = 0; j < 60; ++j) {
      const double r = (i + 0.5) / 60, a = 2 * M_PI * j / 60;
      x.push_back({r * std::cos(a), r * std::sin(a), 1e-9 * r});
    }
  const ClusterTree t(x, ClusterTreeOptions{32});
  expect_valid_tree(t, x, 32);
  expect_median_splits(t);
  expect_depth(t, 3600, 32);
  // splits follow the disk, not its thickness: each quarter is about a quarter disk
  for (int c : t.clusters_at_level(2)) EXPECT_LT(t.cluster(c).radius, 0.9);
}

TEST(ClusterTree, VeryElongatedAndVeryFlatBodies)
{
  auto x = test::unit_cube(8).vertices;
  for (auto &p : x) p = Vec3{1e3 * p[0], p[1], 1e-3 * p[2]};
  const ClusterTree t(x, ClusterTreeOptions{24});
  expect_valid_tree(t, x, 24);
  expect_median_splits(t);
  // the first splits cut the long direction
  const Cluster &l = t.cluster(t.cluster(0).left);
  EXPECT_LT(l.hi[0] - l.lo[0], 0.51e3);
}

/// n random points on the ellipsoid with semi-axes (1, 0.8, 0.3), a thin organ; a share `fewer`
/// of the lower face's points left out, so that the faces' point counts differ as a mesher's do.
std::vector<Vec3> thin_ellipsoid(int n, double fewer = 0, unsigned seed = 11)
{
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::vector<Vec3> x;
  while (static_cast<int>(x.size()) < n) {
    const Vec3 d = normalized(Vec3{g(rng), g(rng), g(rng)});
    if (d[2] < 0 && uni(rng) < fewer) continue;
    x.push_back({d[0], 0.8 * d[1], 0.3 * d[2]});
  }
  return x;
}

/// Σ |x − centroid|² over points[idx].
double inertia_of(const std::vector<Vec3> &points, const std::vector<int> &idx)
{
  Vec3 mean{};
  for (int i : idx) mean = mean + points[i];
  mean = (1.0 / idx.size()) * mean;
  double s = 0;
  for (int i : idx) s += dot(points[i] - mean, points[i] - mean);
  return s;
}

/// The halves' total inertia when points[idx] are split at the median of their principal axis.
double principal_split_inertia(const std::vector<Vec3> &points, std::vector<int> idx)
{
  Vec3 mean{};
  for (int i : idx) mean = mean + points[i];
  mean = (1.0 / idx.size()) * mean;
  double a[9] = {}, w[3];
  for (int i : idx)
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r <= c; ++r) a[r + 3 * c] += (points[i][r] - mean[r]) * (points[i][c] - mean[c]);
  EXPECT_EQ(lapack::syev(3, a, w), 0);
  const Vec3 axis{a[6], a[7], a[8]};
  const std::size_t half = idx.size() / 2;
  std::nth_element(idx.begin(), idx.begin() + half, idx.end(),
                   [&](int p, int q) { return dot(points[p] - mean, axis) < dot(points[q] - mean, axis); });
  return inertia_of(points, std::vector<int>(idx.begin(), idx.begin() + half)) + inertia_of(points, std::vector<int>(idx.begin() + half, idx.end()));
}

/// Per leaf, its radius over the square root of its point count (how compact it is, whatever its
/// size), sorted.
std::vector<double> leaf_compactness(const ClusterTree &t)
{
  std::vector<double> r;
  for (int c : t.leaves()) r.push_back(t.cluster(c).radius / std::sqrt(t.cluster(c).size()));
  std::sort(r.begin(), r.end());
  return r;
}

TEST(ClusterTree, RefinedSplitsAreMoreCompactThanThePrincipalAxis)
{
  // Each split starts on the principal axis, moves to the axis through its halves' centroids while
  // that lowers their inertia (two-means with equal halves), then cuts at a gap within m/4 of the
  // median if that lowers it by 1 %. On a thin body (the (1, 0.8, 0.3) ellipsoid of the disk
  // organ) that gives more compact clusters, hence fewer near pairs.
  const auto x = thin_ellipsoid(26000);
  const ClusterTree t(x, ClusterTreeOptions{64}), plain(x, ClusterTreeOptions{64, false});
  expect_valid_tree(t, x, 64);
  expect_median_splits(t);
  expect_depth(t, 26000, 64);
  // every split no worse than the principal axis's median split (within 2 %: where two eigenvalues
  // nearly coincide, the principal axis itself hangs on the rounding of the covariance)
  for (int c = 0; c < t.num_clusters(); ++c) {
    const Cluster &cl = t.cluster(c);
    if (cl.left < 0) continue;
    const auto points_of = [&](const Cluster &q) { return std::vector<int>(t.perm().begin() + q.begin, t.perm().begin() + q.end); };
    const double split = inertia_of(x, points_of(t.cluster(cl.left))) + inertia_of(x, points_of(t.cluster(cl.right)));
    EXPECT_LE(split, principal_split_inertia(x, points_of(cl)) * 1.02) << "cluster " << c;
  }
  // and the leaves more compact than the principal axis's alone, on average and at the 90th percentile
  const std::vector<double> rt = leaf_compactness(t), rp = leaf_compactness(plain);
  const auto mean = [](const std::vector<double> &r) { return std::accumulate(r.begin(), r.end(), 0.0) / r.size(); };
  const double t90 = rt[9 * rt.size() / 10], p90 = rp[9 * rp.size() / 10];
  std::printf("leaf radius / sqrt(points) with / without refinement: mean %.5f / %.5f, 90th percentile %.5f / %.5f\n", mean(rt), mean(rp), t90, p90);
  EXPECT_LT(mean(rt), 0.98 * mean(rp));
  EXPECT_LT(t90, 0.97 * p90);
}

TEST(ClusterTree, ThinBodyLeavesHoldOneFace)
{
  // The faces of a thin body hold different numbers of points (here 4 % fewer below): a cluster
  // that holds both can only be parted by a cut off its median, at the gap between the faces.
  // Median splits leave leaves with both faces, several times the others' radius (on the disk
  // organ, 53-88 near blocks against 13).
  const auto x = thin_ellipsoid(26000, 0.04);
  const ClusterTree t(x, ClusterTreeOptions{64}), plain(x, ClusterTreeOptions{64, false});
  expect_valid_tree(t, x, 64);
  expect_median_splits(t);
  const auto straddling = [](const ClusterTree &tr) {
    int n = 0;
    for (int c : tr.leaves())
      if (tr.cluster(c).lo[2] < -0.1 && tr.cluster(c).hi[2] > 0.1) ++n; // both faces, away from the rim
    return n;
  };
  const std::vector<double> rt = leaf_compactness(t), rp = leaf_compactness(plain);
  std::printf("leaves holding both faces: %d with refinement, %d without; largest radius / sqrt(points) %.4f / %.4f\n", straddling(t), straddling(plain), rt.back(),
              rp.back());
  EXPECT_GT(straddling(plain), 0); // the case arises
  EXPECT_EQ(straddling(t), 0);
  EXPECT_LT(rt.back(), 2.5 * rt[rt.size() / 2]);
}

TEST(ClusterTree, HollowSphere)
{
  const auto x = concat(sphere_points(2), sphere_points(2, 0.5));
  const ClusterTree t(x, ClusterTreeOptions{16});
  expect_valid_tree(t, x, 16);
  expect_median_splits(t);
  expect_depth(t, static_cast<int>(x.size()), 16);
}

TEST(ClusterTree, FarApartSpheresAreNeverMixedInALeaf)
{
  const auto a = sphere_points(2), b = sphere_points(2, 0.5, {10, 0, 0});
  const auto x = concat(a, b);
  const int na = static_cast<int>(a.size());
  const ClusterTree t(x, ClusterTreeOptions{16});
  expect_valid_tree(t, x, 16);
  for (int c : t.leaves()) {
    const Cluster &cl = t.cluster(c);
    const bool first = t.perm()[cl.begin] < na;
    for (int k = cl.begin; k < cl.end; ++k) EXPECT_EQ(t.perm()[k] < na, first) << "leaf " << c;
  }
  // the root splits exactly between the spheres, which are then admissible
  const Cluster &root = t.cluster(0);
  EXPECT_EQ(t.cluster(root.left).size(), na);
  EXPECT_TRUE(t.admissible(root.left, root.right, 1.0));
}

TEST(ClusterTree, AdmissibilitySeparatesNearFromFar)
{
  const auto x = concat(sphere_points(3), sphere_points(3, 1.0, {10, 0, 0}));
  const ClusterTree t(x, ClusterTreeOptions{16});
  const Cluster &root = t.cluster(0);
  const int a = root.left, b = root.right;
  EXPECT_TRUE(t.admissible(a, b, 1.0));
  EXPECT_TRUE(t.admissible(b, a, 1.0));
  EXPECT_FALSE(t.admissible(a, b, 4.0)); // 10 < 5 * (1 + 1)
  EXPECT_FALSE(t.admissible(0, 0, 0.0));
  EXPECT_FALSE(t.admissible(a, a, 0.5));
  EXPECT_FALSE(t.admissible(0, a, 0.5)); // ancestor
  const Cluster &ca = t.cluster(a);
  EXPECT_FALSE(t.admissible(ca.left, ca.right, 0.5)); // two halves of one sphere touch
  EXPECT_THROW(t.admissible(a, b, -0.1), std::invalid_argument);
  // the documented guarantee: points of b lie outside a's proxy sphere of radius (1 + eta) r_a
  const double eta = 0.7;
  int far_pairs = 0;
  for (int p : t.leaves())
    for (int q : t.leaves()) {
      if (!t.admissible(p, q, eta)) continue;
      ++far_pairs;
      EXPECT_TRUE(t.admissible(q, p, eta));
      const Cluster &cp = t.cluster(p), &cq = t.cluster(q);
      for (int k = cq.begin; k < cq.end; ++k) EXPECT_GT(norm(x[t.perm()[k]] - cp.centre), (1 + eta) * cp.radius);
    }
  EXPECT_GT(far_pairs, 0);
}

TEST(ClusterTree, CoincidentClustersAreNotAdmissible)
{
  const std::vector<Vec3> x(10, Vec3{1, 1, 1});
  const ClusterTree t(x, ClusterTreeOptions{4});
  EXPECT_FALSE(t.admissible(t.cluster(0).left, t.cluster(0).right, 0.0));
}

TEST(ClusterTree, TwoPartsAreTheRootsChildren)
{
  const auto x = sphere_points(3);
  std::vector<int> part(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) part[i] = x[i][0] > 0;
  const ClusterTree t(x, part, 2, ClusterTreeOptions{16});
  expect_valid_tree(t, x, 16);
  const Cluster &root = t.cluster(0);
  EXPECT_EQ(cluster_of_part(t, part, 0), root.left);
  EXPECT_EQ(cluster_of_part(t, part, 1), root.right);
  EXPECT_EQ(t.num_parts(), 2);
  EXPECT_EQ(t.part_cluster(0), root.left);
  EXPECT_EQ(t.part_cluster(1), root.right);
  expect_median_splits(t, 1);
}

TEST(ClusterTree, FourPartsAreLevelTwo)
{
  const auto x = random_on_sphere(5000);
  std::vector<int> part(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) part[i] = (x[i][0] > 0) + 2 * (x[i][1] > 0);
  const ClusterTree t(x, part, 4, ClusterTreeOptions{64});
  expect_valid_tree(t, x, 64);
  ASSERT_EQ(t.clusters_at_level(2).size(), 4u);
  for (int p = 0; p < 4; ++p) {
    EXPECT_EQ(cluster_of_part(t, part, p), t.clusters_at_level(2)[p]) << "part " << p;
    EXPECT_EQ(t.part_cluster(p), t.clusters_at_level(2)[p]);
  }
  expect_median_splits(t, 2);
}

TEST(ClusterTree, EightUnevenPartsAreLevelThree)
{
  const auto x = random_on_sphere(4000);
  std::vector<int> part(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) part[i] = std::min(7, int(std::pow(double(i % 97) / 97, 2) * 8)); // uneven sizes
  const ClusterTree t(x, part, 8, ClusterTreeOptions{32});
  expect_valid_tree(t, x, 32);
  for (int p = 0; p < 8; ++p) {
    EXPECT_EQ(cluster_of_part(t, part, p), t.part_cluster(p));
    EXPECT_EQ(t.cluster(t.part_cluster(p)).level, 3);
  }
}

TEST(ClusterTree, ThreePartsAreOneClusterEach)
{
  const auto x = sphere_points(4);
  std::vector<int> part(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double a = std::atan2(x[i][1], x[i][0]) + M_PI; // [0, 2 pi]
    part[i] = std::min(2, int(a / (2 * M_PI / 3)));
  }
  const ClusterTree t(x, part, 3, ClusterTreeOptions{32});
  expect_valid_tree(t, x, 32);
  std::set<int> clusters;
  for (int p = 0; p < 3; ++p) {
    const int c = cluster_of_part(t, part, p);
    EXPECT_GE(c, 0) << "part " << p;
    EXPECT_EQ(t.part_cluster(p), c);
    clusters.insert(c);
  }
  EXPECT_EQ(clusters.size(), 3u);
  // parts are laid out in their numbering order, so part p is the p-th block of positions
  EXPECT_LT(t.cluster(t.part_cluster(0)).begin, t.cluster(t.part_cluster(1)).begin);
  EXPECT_LT(t.cluster(t.part_cluster(1)).begin, t.cluster(t.part_cluster(2)).begin);
}

TEST(ClusterTree, NonPowerOfTwoPartsSplitByPointCount)
{
  const auto x = random_on_sphere(1000);
  std::vector<int> part(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) part[i] = i < 100 ? 0 : i < 200 ? 1 : 2; // 100, 100, 800
  const ClusterTree t(x, part, 3, ClusterTreeOptions{64});
  expect_valid_tree(t, x, 64);
  const Cluster &root = t.cluster(0);
  EXPECT_EQ(t.cluster(root.left).size(), 200); // {0, 1} | {2} beats {0} | {1, 2}
  EXPECT_EQ(t.part_cluster(2), root.right);
  EXPECT_EQ(t.cluster(t.part_cluster(0)).parent, root.left);
}

TEST(ClusterTree, OnePartIsTheRoot)
{
  const auto x = sphere_points(2);
  const ClusterTree t(x, std::vector<int>(x.size(), 0), 1, ClusterTreeOptions{16});
  EXPECT_EQ(t.part_cluster(0), 0);
  EXPECT_TRUE(same_tree(t, ClusterTree(x, ClusterTreeOptions{16})));
}

TEST(ClusterTree, RejectsBadInput)
{
  const auto x = sphere_points(1);
  EXPECT_THROW(ClusterTree(std::vector<Vec3>{}), std::invalid_argument);
  EXPECT_THROW(ClusterTree(x, ClusterTreeOptions{0}), std::invalid_argument);
  auto bad = x;
  bad[5][1] = std::nan("");
  EXPECT_THROW(ClusterTree{bad}, std::invalid_argument);
  EXPECT_THROW(ClusterTree(x, std::vector<int>(x.size() - 1, 0), 1), std::invalid_argument);
  EXPECT_THROW(ClusterTree(x, std::vector<int>(x.size(), 2), 2), std::invalid_argument); // out of range
  EXPECT_THROW(ClusterTree(x, std::vector<int>(x.size(), 1), 2), std::invalid_argument); // part 0 empty
  EXPECT_THROW(ClusterTree(x, std::vector<int>(x.size(), 0), 0), std::invalid_argument);
}

TEST(ClusterTree, PermuteVectorsRoundTrip)
{
  const auto x = sphere_points(3);
  const int n = static_cast<int>(x.size());
  const ClusterTree t(x, ClusterTreeOptions{16});
  std::vector<double> mesh(3 * n), cluster(3 * n), back(3 * n);
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) mesh[3 * i + d] = x[i][d]; // values = coordinates of their node
  t.to_cluster_order(mesh.data(), cluster.data(), 3);
  for (int k = 0; k < n; ++k)
    for (int d = 0; d < 3; ++d) ASSERT_EQ(cluster[3 * k + d], x[t.perm()[k]][d]) << "position " << k;
  t.to_mesh_order(cluster.data(), back.data(), 3);
  EXPECT_EQ(back, mesh);
  // block 1 and a scalar check that the tree did reorder something
  std::vector<double> ids(n), perm_ids(n);
  for (int i = 0; i < n; ++i) ids[i] = i;
  t.to_cluster_order(ids.data(), perm_ids.data(), 1);
  for (int k = 0; k < n; ++k) EXPECT_EQ(perm_ids[k], t.perm()[k]);
  EXPECT_NE(perm_ids, ids);
  EXPECT_THROW(t.to_mesh_order(ids.data(), perm_ids.data(), 0), std::invalid_argument);
}

TEST(ClusterTree, MovedTreeKeepsItsContents)
{
  const auto x = sphere_points(2);
  ClusterTree a(x, ClusterTreeOptions{8});
  const std::vector<int> perm = a.perm();
  const int nc = a.num_clusters();
  ClusterTree b(std::move(a));
  EXPECT_EQ(b.perm(), perm);
  EXPECT_EQ(b.num_clusters(), nc);
}

// A million points: a quadratic step would not finish within the test's timeout (no wall-clock
// bound here: the load of the machine sets that, not the code).
TEST(ClusterTree, LargeTreeIsValid)
{
  const int n = 1000000;
  const auto x = random_on_sphere(n, 11);
  const ClusterTree t(x, ClusterTreeOptions{64});
  expect_depth(t, n, 64);
  expect_median_splits(t);
  std::vector<char> seen(n, 0);
  for (int k = 0; k < n; ++k) seen[t.perm()[k]] = 1;
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), n);
  for (int c : t.leaves()) EXPECT_LE(t.cluster(c).size(), 64);
}
