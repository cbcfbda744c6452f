/// \file surface_intersection.cpp
/// The intersection check (see surface_intersection.hpp): a bounding-volume hierarchy over the
/// triangles' boxes (median splits along the longest axis, leaves of a few triangles), queried
/// with each triangle's box; candidate pairs go to triangles_cross().
#include "hssbem/mesh/surface_intersection.hpp"

#include "triangle_crossing.hpp"

#include <algorithm>
#include <atomic>
#include <climits>
#include <cmath>
#include <vector>

namespace hssbem {

namespace {


detail::Triangle corners(const SurfaceMesh &m, int t)
{
  const auto &tri = m.triangles[t];
  return {m.vertices[tri[0]], m.vertices[tri[1]], m.vertices[tri[2]]};
}

Box triangle_box(const SurfaceMesh &m, int t, double pad)
{
  Box b;
  for (const Vec3 &x : corners(m, t)) b.add(x);
  for (int i = 0; i < 3; ++i) b.lo[i] -= pad, b.hi[i] += pad;
  return b;
}

/// The hierarchy over the boxes of a mesh's triangles: nodes in one array, a node's triangles a
/// contiguous range of `order`.
class Bvh {
public:
  Bvh(const SurfaceMesh &m, double pad) : m_boxes(m.triangles.size()), m_order(m.triangles.size())
  {
    for (int t = 0; t < m.num_triangles(); ++t) m_boxes[t] = triangle_box(m, t, pad), m_order[t] = t;
    m_nodes.reserve(2 * m_order.size() / k_leaf + 2);
    if (!m_order.empty()) build(0, static_cast<int>(m_order.size()));
    m_leaf_boxes.resize(m_order.size());
    for (std::size_t i = 0; i < m_order.size(); ++i) m_leaf_boxes[i] = m_boxes[m_order[i]]; // scanned in this order: contiguous
  }

  /// Calls take(t) for every triangle whose box overlaps `q`.
  template <class Take> void query(const Box &q, Take &&take) const
  {
    if (m_nodes.empty()) return;
    int stack[128], top = 0; // depth ≤ log2(n / k_leaf) + 1: median splits
    stack[top++] = 0;
    while (top > 0) {
      const Node &n = m_nodes[stack[--top]];
      if (!n.box.overlaps(q)) continue;
      if (n.left < 0) {
        for (int i = n.begin; i < n.end; ++i)
          if (m_leaf_boxes[i].overlaps(q)) take(m_order[i]);
      } else {
        stack[top++] = n.left;
        stack[top++] = n.right;
      }
    }
  }

  const Box &box(int t) const { return m_boxes[t]; }

private:
  static constexpr int k_leaf = 4;
  struct Node {
    Box box;
    int left = -1, right = -1, begin = 0, end = 0; ///< a leaf: left < 0, triangles order[begin, end)
  };

  /// The node of order[begin, end) and its subtree; returns its index.
  int build(int begin, int end)
  {
    const int id = static_cast<int>(m_nodes.size());
    m_nodes.emplace_back();
    Box box, centres;
    for (int i = begin; i < end; ++i) {
      box.add(m_boxes[m_order[i]]);
      centres.add(centre(m_order[i]));
    }
    m_nodes[id].box = box, m_nodes[id].begin = begin, m_nodes[id].end = end;
    if (end - begin <= k_leaf) return id;
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (centres.hi[k] - centres.lo[k] > centres.hi[axis] - centres.lo[axis]) axis = k;
    const int mid = begin + (end - begin) / 2;
    std::nth_element(m_order.begin() + begin, m_order.begin() + mid, m_order.begin() + end, [&](int a, int b) { return centre(a)[axis] < centre(b)[axis]; });
    const int left  = build(begin, mid);
    const int right = build(mid, end);
    m_nodes[id].left = left, m_nodes[id].right = right;
    return id;
  }
  Vec3 centre(int t) const { return 0.5 * (m_boxes[t].lo + m_boxes[t].hi); }

  std::vector<Box>  m_boxes, m_leaf_boxes; ///< by triangle; by position in m_order
  std::vector<int>  m_order;
  std::vector<Node> m_nodes;
};

bool neighbours(const std::array<int, 3> &a, const std::array<int, 3> &b)
{
  for (int i : a)
    if (i == b[0] || i == b[1] || i == b[2]) return true;
  return false;
}

/// The tolerance of `o` as a distance: relative to the diagonal of everything checked.
double absolute_tolerance(const SurfaceMesh &a, const SurfaceMesh *b, const IntersectionOptions &o)
{
  Box all;
  for (const auto *m : {&a, b})
    if (m)
      for (const auto &tri : m->triangles)
        for (int v : tri) all.add(m->vertices[v]);
  return o.tolerance * all.diagonal();
}

/// The lowest t in [0, n) for which first_partner(t) ≥ 0, with that partner; threads share the
/// t's, and skip those above the lowest found so far (the answer is the serial one).
template <class Partner> std::optional<TrianglePair> lowest_pair(int n, Partner &&first_partner)
{
  std::atomic<long long> best{LLONG_MAX}; // t * 2^32 + partner
#pragma omp parallel for schedule(dynamic, 512) if (n > 8192) // threads only where they pay
  for (int t = 0; t < n; ++t) {
    if ((static_cast<long long>(t) << 32) > best.load(std::memory_order_relaxed)) continue;
    const int u = first_partner(t);
    if (u < 0) continue;
    const long long key = (static_cast<long long>(t) << 32) | u;
    long long       cur = best.load();
    while (key < cur && !best.compare_exchange_weak(cur, key)) {
    }
  }
  if (best.load() == LLONG_MAX) return std::nullopt;
  return TrianglePair{static_cast<int>(best.load() >> 32), static_cast<int>(best.load() & 0xffffffffLL)};
}

} // namespace

std::optional<TrianglePair> find_intersection(const SurfaceMesh &mesh, const IntersectionOptions &o)
{
  const double eps = absolute_tolerance(mesh, nullptr, o);
  const Bvh    bvh(mesh, eps);
  return lowest_pair(mesh.num_triangles(), [&](int t) {
    const detail::Triangle a = corners(mesh, t);
    int                    partner = -1;
    bvh.query(bvh.box(t), [&](int u) {
      if (u <= t || (partner >= 0 && u >= partner) || neighbours(mesh.triangles[t], mesh.triangles[u])) return;
      if (detail::triangles_cross(a, corners(mesh, u), eps)) partner = u;
    });
    return partner;
  });
}

std::optional<TrianglePair> find_intersection(const SurfaceMesh &a, const SurfaceMesh &b, const IntersectionOptions &o)
{
  const double eps = absolute_tolerance(a, &b, o);
  const Bvh    bvh(b, eps);
  return lowest_pair(a.num_triangles(), [&](int t) {
    const detail::Triangle ta = corners(a, t);
    const Box              q  = triangle_box(a, t, eps);
    int                    partner = -1;
    bvh.query(q, [&](int u) {
      if (partner >= 0 && u >= partner) return;
      if (detail::triangles_cross(ta, corners(b, u), eps)) partner = u;
    });
    return partner;
  });
}

} // namespace hssbem
