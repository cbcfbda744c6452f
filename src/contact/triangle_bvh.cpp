// Closest points on triangles (Ericson, Real-Time Collision Detection, 5.1.5) and a small
// bounding-volume hierarchy over them (triangle_bvh.hpp).
#include "hssbem/contact/triangle_bvh.hpp"

#include <algorithm>
#include <numeric>
#include <queue>
#include <utility>

namespace hssbem {

namespace {

constexpr int k_leaf = 4; // triangles per leaf

TriangleHit hit_at(const Vec3 &x, const Vec3 &a, const Vec3 &b, const Vec3 &c, double u, double v, double w, bool interior)
{
  TriangleHit h;
  h.bary = {u, v, w};
  h.point = u * a + v * b + w * c;
  h.distance = norm(x - h.point);
  h.interior = interior;
  return h;
}

} // namespace

TriangleHit closest_point_on_triangle(const Vec3 &x, const Vec3 &a, const Vec3 &b, const Vec3 &c)
{
  const Vec3 ab = b - a, ac = c - a, ap = x - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return hit_at(x, a, b, c, 1, 0, 0, false);
  const Vec3 bp = x - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return hit_at(x, a, b, c, 0, 1, 0, false);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return hit_at(x, a, b, c, 1 - v, v, 0, false);
  }
  const Vec3 cp = x - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return hit_at(x, a, b, c, 0, 0, 1, false);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return hit_at(x, a, b, c, 1 - w, 0, w, false);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return hit_at(x, a, b, c, 0, 1 - w, w, false);
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return hit_at(x, a, b, c, 1 - v - w, v, w, true);
}

TriangleBvh::TriangleBvh(const std::vector<Vec3> &vertices, const std::vector<std::array<int, 3>> &triangles, const std::vector<int> &subset)
{
  m_tri = subset;
  if (m_tri.empty()) {
    m_tri.resize(triangles.size());
    std::iota(m_tri.begin(), m_tri.end(), 0);
  }
  m_corners.resize(m_tri.size());
  for (std::size_t i = 0; i < m_tri.size(); ++i)
    for (int k = 0; k < 3; ++k) m_corners[i][k] = vertices[triangles[m_tri[i]][k]];
  if (!m_tri.empty()) {
    m_nodes.reserve(2 * m_tri.size() / k_leaf + 2);
    build(0, static_cast<int>(m_tri.size()));
  }
}

/// Builds the node over triangles [begin, end) (reordering them) and returns its index.
int TriangleBvh::build(int begin, int end)
{
  const int self = static_cast<int>(m_nodes.size());
  m_nodes.emplace_back();
  Vec3 lo = m_corners[begin][0], hi = lo;
  for (int i = begin; i < end; ++i)
    for (const Vec3 &p : m_corners[i])
      for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], p[d]), hi[d] = std::max(hi[d], p[d]);
  m_nodes[self].lo = lo, m_nodes[self].hi = hi;
  if (end - begin <= k_leaf) {
    m_nodes[self].first = begin, m_nodes[self].count = end - begin;
    return self;
  }
  int axis = 0;
  for (int d = 1; d < 3; ++d)
    if (hi[d] - lo[d] > hi[axis] - lo[axis]) axis = d;
  const int mid = (begin + end) / 2;
  std::vector<int> order(end - begin);
  std::iota(order.begin(), order.end(), begin);
  auto centre = [&](int i) { return m_corners[i][0][axis] + m_corners[i][1][axis] + m_corners[i][2][axis]; };
  std::nth_element(order.begin(), order.begin() + (mid - begin), order.end(), [&](int a, int b) { return centre(a) < centre(b); });
  std::vector<std::array<Vec3, 3>> corners(end - begin);
  std::vector<int> tri(end - begin);
  for (int i = 0; i < end - begin; ++i) corners[i] = m_corners[order[i]], tri[i] = m_tri[order[i]];
  std::copy(corners.begin(), corners.end(), m_corners.begin() + begin);
  std::copy(tri.begin(), tri.end(), m_tri.begin() + begin);
  const int left = build(begin, mid), right = build(mid, end);
  m_nodes[self].first = left;
  m_nodes[self].second = right;
  return self;
}

double TriangleBvh::box_distance2(const Node &n, const Vec3 &x)
{
  double d2 = 0;
  for (int d = 0; d < 3; ++d) {
    const double e = std::max({n.lo[d] - x[d], 0.0, x[d] - n.hi[d]});
    d2 += e * e;
  }
  return d2;
}

TriangleHit TriangleBvh::closest(const Vec3 &x, double max_distance) const
{
  TriangleHit best;
  if (m_nodes.empty()) return best;
  double bound2 = max_distance * max_distance;
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
  open.push({box_distance2(m_nodes[0], x), 0});
  while (!open.empty()) {
    const auto [d2, id] = open.top();
    open.pop();
    if (d2 > bound2) break;
    const Node &n = m_nodes[id];
    if (n.count == 0) {
      for (int c : {n.first, n.second}) open.push({box_distance2(m_nodes[c], x), c});
      continue;
    }
    for (int i = n.first; i < n.first + n.count; ++i) {
      TriangleHit h = closest_point_on_triangle(x, m_corners[i][0], m_corners[i][1], m_corners[i][2]);
      if (h.distance * h.distance <= bound2 && h.distance < best.distance) {
        h.triangle = m_tri[i];
        best = h;
        bound2 = h.distance * h.distance;
      }
    }
  }
  return best;
}

} // namespace hssbem
