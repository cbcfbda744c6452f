// Contact points of a frame (contact_points.hpp): per candidate vertex the closest obstacle
// within reach, and node-to-surface pairs between bodies.
#include "contact_points.hpp"

#include <algorithm>
#include <cstdint>
#include <cmath>
#include <limits>

namespace hssbem::contact_detail {

std::array<Vec3, 3> local_frame(const Vec3 &n)
{
  int axis = 0;
  for (int d = 1; d < 3; ++d)
    if (std::abs(n[d]) < std::abs(n[axis])) axis = d;
  Vec3 e{};
  e[axis] = 1;
  const Vec3 t1 = normalized(e - dot(e, n) * n);
  return {n, t1, cross(n, t1)};
}

int facing_node(const Discretization &disc, int v, const Vec3 &n)
{
  int best = disc.first_node(v);
  for (int i = best + 1; i < disc.first_node(v) + disc.node_count(v); ++i)
    if (dot(disc.node(i).normal, n) < dot(disc.node(best).normal, n)) best = i;
  return best;
}

namespace {

/// The slave node's displacement along n is not all prescribed: the point can close.
bool movable(const Geometry &g, int node, const Vec3 &n)
{
  double free = 0;
  for (int a = 0; a < 3; ++a)
    if (!(*g.pattern)[3 * node + a]) free += n[a] * n[a];
  return free > 1e-12;
}

/// The points of vertex v against normal n: one per movable dof node, the facing node first.
std::vector<ContactPoint> vertex_points(const Geometry &g, int v, const Vec3 &n, double gap)
{
  const Discretization &disc = *g.disc;
  const int facing = facing_node(disc, v, n);
  std::vector<ContactPoint> out;
  std::vector<int> nodes{facing};
  for (int i = disc.first_node(v); i < disc.first_node(v) + disc.node_count(v); ++i)
    if (i != facing) nodes.push_back(i);
  for (int node : nodes) {
    if (!movable(g, node, n)) continue;
    ContactPoint p;
    p.vertex = v;
    p.node = node;
    p.facing = node == facing;
    p.body = g.bodies.of_vertex[v];
    p.terms = 1;
    p.term_node[0] = node;
    p.mw[0] = p.lw[0] = 1;
    p.frame = local_frame(n);
    p.g0 = gap;
    p.area = g.area[node];
    out.push_back(p);
  }
  return out;
}

/// The closest obstacle point of vertex v (within reach, or at any distance when forced).
bool closest_obstacle(const Geometry &g, int v, const std::vector<Vec3> &offsets, bool forced, int &which, ObstacleGap &best)
{
  const double reach = forced ? std::numeric_limits<double>::infinity() : g.reach;
  which = -1;
  for (std::size_t o = 0; o < g.obstacles.size(); ++o) {
    ObstacleGap h;
    if (g.obstacles[o].gap(g.disc->mesh().vertices[v], offsets[o], reach, h) && (which < 0 || h.gap < best.gap)) which = static_cast<int>(o), best = h;
  }
  return which >= 0;
}

/// Node-to-surface points of the candidate vertices of body a against the surface of body b.
std::vector<ContactPoint> pass(const Geometry &g, int a, int b)
{
  const Discretization &disc = *g.disc;
  const SurfaceMesh &mesh = disc.mesh();
  std::vector<ContactPoint> out;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (!g.candidate[v] || g.bodies.of_vertex[v] != a) continue;
    const TriangleHit h = g.body_bvh[b].closest(mesh.vertices[v], g.reach);
    if (h.triangle < 0) continue;
    const Vec3 nt = mesh.triangle_normal(h.triangle), d = mesh.vertices[v] - h.point;
    const double dist = norm(d);
    Vec3 n = nt;
    double gap = dot(d, nt);
    if (!h.interior && dist > 1e-12 * g.reach) {
      const double side = gap >= 0 ? 1.0 : -1.0;
      n = (side / dist) * d, gap = side * dist;
    }
    std::array<int, 3> master;
    for (int k = 0; k < 3; ++k) master[k] = facing_node(disc, mesh.triangles[h.triangle][k], -1.0 * n); // the master group whose normal is n: it faces the slave
    for (ContactPoint p : vertex_points(g, v, n, gap)) {
      p.other = b;
      p.terms = 4;
      for (int k = 0; k < 3; ++k) {
        p.term_node[k + 1] = master[k];
        p.mw[k + 1] = -h.bary[k];
        p.lw[k + 1] = -h.bary[k] * p.area / g.area[master[k]];
      }
      p.mu = g.friction;
      out.push_back(p);
    }
  }
  return out;
}

} // namespace

std::vector<ContactPoint> obstacle_points(const Geometry &g, const std::vector<Vec3> &offsets, const std::vector<char> &forced)
{
  std::vector<ContactPoint> out;
  const int nv = g.disc->mesh().num_vertices();
  for (int v = 0; v < nv; ++v) {
    if (!g.candidate[v]) continue;
    int o = -1;
    ObstacleGap h;
    if (!closest_obstacle(g, v, offsets, !forced.empty() && forced[v], o, h)) continue;
    const double own = g.obstacles[o].obstacle().friction;
    for (ContactPoint p : vertex_points(g, v, h.normal, h.gap)) {
      p.obstacle = o;
      p.mu = std::isnan(own) ? g.friction : own;
      out.push_back(p);
    }
  }
  return out;
}

std::vector<ContactPoint> body_points(const Geometry &g)
{
  std::vector<ContactPoint> out;
  if (!g.bodies_touch) return out;
  for (int a = 0; a < g.bodies.count; ++a)
    for (int b = a + 1; b < g.bodies.count; ++b) {
      std::vector<ContactPoint> ab = pass(g, a, b), ba = pass(g, b, a);
      // One pass per pair: the side with more vertices near the other (the finer mesh there) is
      // the slave; both passes at once would constrain matching meshes twice (a singular D).
      const std::vector<ContactPoint> &slave = ba.size() > ab.size() ? ba : ab;
      out.insert(out.end(), slave.begin(), slave.end());
    }
  return out;
}

std::vector<ContactPoint> merge_points(std::vector<ContactPoint> a, const std::vector<ContactPoint> &b, int num_vertices, const std::vector<int> &position)
{
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> gap_a(num_vertices, inf), gap_b(num_vertices, inf);
  for (const ContactPoint &p : a) gap_a[p.vertex] = p.g0;
  for (const ContactPoint &p : b) gap_b[p.vertex] = p.g0;
  std::vector<ContactPoint> out;
  for (const ContactPoint &p : a)
    if (gap_a[p.vertex] <= gap_b[p.vertex]) out.push_back(p);
  for (const ContactPoint &p : b)
    if (gap_b[p.vertex] < gap_a[p.vertex]) out.push_back(p);
  if (!position.empty())
    std::stable_sort(out.begin(), out.end(), [&](const ContactPoint &x, const ContactPoint &y) { return position[x.node] < position[y.node]; });
  return out;
}

namespace {

/// Spreads the low 21 bits of x so that two zero bits follow each (Morton interleaving).
std::uint64_t spread(std::uint64_t x)
{
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

} // namespace

std::vector<int> spatial_row_order(const Discretization &disc)
{
  const int nn = disc.num_nodes();
  Vec3 lo = disc.node_position(0), hi = lo;
  for (int i = 0; i < nn; ++i)
    for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], disc.node_position(i)[d]), hi[d] = std::max(hi[d], disc.node_position(i)[d]);
  std::vector<std::pair<std::uint64_t, int>> key(nn);
  for (int i = 0; i < nn; ++i) {
    std::uint64_t code = 0;
    for (int d = 0; d < 3; ++d) {
      const double t = hi[d] > lo[d] ? (disc.node_position(i)[d] - lo[d]) / (hi[d] - lo[d]) : 0.0;
      code |= spread(static_cast<std::uint64_t>(t * ((1 << 21) - 1))) << d;
    }
    key[i] = {code, i};
  }
  std::sort(key.begin(), key.end());
  std::vector<int> order(3 * static_cast<std::size_t>(nn));
  for (int k = 0; k < nn; ++k)
    for (int a = 0; a < 3; ++a) order[3 * k + a] = 3 * key[k].second + a;
  return order;
}

} // namespace hssbem::contact_detail
