// A small bounding-volume hierarchy over triangles (triangle_bvh.hpp); the closest point on one
// triangle is core/geometry.hpp's.
#include "hssbem/contact/triangle_bvh.hpp"

#include <algorithm>
#include <numeric>
#include <queue>
#include <utility>

namespace hssbem {

namespace {

constexpr int k_leaf = 4; // triangles per leaf

} // namespace

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
  Box box;
  for (int i = begin; i < end; ++i)
    for (const Vec3 &p : m_corners[i]) box.add(p);
  const Vec3 &lo = box.lo, &hi = box.hi;
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
      const TrianglePoint q = closest_point_on_triangle(x, m_corners[i][0], m_corners[i][1], m_corners[i][2]);
      const double d = norm(x - q.point);
      if (d * d <= bound2 && d < best.distance) {
        best = {m_tri[i], q.point, q.bary, d, q.interior};
        bound2 = d * d;
      }
    }
  }
  return best;
}

} // namespace hssbem
