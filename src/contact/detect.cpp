// Contact points of a frame (contact_points.hpp): per candidate vertex every obstacle within
// reach, node-to-surface pairs between bodies, and the points' local frames per node.
#include "contact_points.hpp"

#include <algorithm>
#include <cstdint>
#include <cmath>
#include <limits>
#include <unordered_map>

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

/// The point of vertex v against partner `partner` with normal n: at the node facing n (every
/// node of a vertex shares its pattern); false when its displacement along n is all prescribed.
bool vertex_point(const Geometry &g, int v, const Vec3 &n, double gap, int partner, ContactPoint &p)
{
  const int node = facing_node(*g.disc, v, n);
  if (!movable(g, node, n)) return false;
  p = ContactPoint{};
  p.vertex = v;
  p.node = node;
  p.body = g.bodies.of_vertex[v];
  p.partner = partner;
  p.key = node * g.partners + partner;
  p.terms = 1;
  p.term_node[0] = node;
  p.mw[0] = p.lw[0] = Vec3{1, 1, 1};
  p.frame = local_frame(n);
  p.g0 = gap;
  p.area = g.area[node];
  return true;
}

/// On moved bodies, a slave vertex within this fraction of the reach of a master edge or corner
/// takes the normal of the master's faces there that face it (pass(), facing_normal()).
constexpr double k_edge_band = 0.1;

/// The normal, at positions x, of the master triangle at the closest feature of hit h (its
/// triangles: those of the feature's vertices) that faces slave vertex v best (most opposite one
/// of v's nodes' normals): two faces that lie on each other press along their normals, whichever
/// triangle at a shared edge the search met.
Vec3 facing_normal(const Geometry &g, const BodyPlacement &at, const TriangleHit &h, int v)
{
  const Discretization &disc = *g.disc;
  const SurfaceMesh &mesh = disc.mesh();
  const auto normal = [&](int t) {
    const std::array<int, 3> &q = mesh.triangles[t];
    return normalized(cross(at.vertices[q[1]] - at.vertices[q[0]], at.vertices[q[2]] - at.vertices[q[0]]));
  };
  Vec3 best = normal(h.triangle);
  double score = 2;
  for (int k = 0; k < 3; ++k) {
    if (h.bary[k] < 1e-9) continue; // not a vertex of the feature
    const int w = mesh.triangles[h.triangle][k];
    for (int t : at.triangles_of[w]) {
      const Vec3 n = normal(t);
      for (int i = disc.first_node(v); i < disc.first_node(v) + disc.node_count(v); ++i)
        if (dot(n, disc.node(i).normal) < score) score = dot(n, disc.node(i).normal), best = n;
    }
  }
  return best;
}

/// Node-to-surface points of the candidate vertices of body a against the surface of body b, in
/// the configuration `at` (BodyPlacement: the undeformed one when its displacement is empty).
std::vector<ContactPoint> pass(const Geometry &g, const BodyPlacement &at, int a, int b)
{
  const Discretization &disc = *g.disc;
  const SurfaceMesh &mesh = disc.mesh();
  const std::vector<Vec3> &x = at.u.empty() ? mesh.vertices : at.vertices;
  std::vector<ContactPoint> out;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (!g.candidate[v] || g.bodies.of_vertex[v] != a) continue;
    const TriangleHit h = (at.u.empty() ? g.body_bvh : at.bvh)[b].closest(x[v], g.reach);
    if (h.triangle < 0) continue;
    const std::array<int, 3> &tri = mesh.triangles[h.triangle];
    const Vec3 nt = normalized(cross(x[tri[1]] - x[tri[0]], x[tri[2]] - x[tri[0]])), d = x[v] - h.point;
    const double dist = norm(d);
    Vec3 n = nt;
    double gap = dot(d, nt);
    // Beyond the master's edge or corner the normal is the direction to it — where that is
    // defined: on moved bodies a closed pair's offset (its gap near zero) is the deformation's
    // noise, so within k_edge_band of the reach the normal is that of the faces facing it.
    if (!h.interior && !at.u.empty() && dist <= k_edge_band * g.reach) n = facing_normal(g, at, h, v), gap = dot(d, n);
    else if (!h.interior && dist > 1e-12 * g.reach) {
      const double side = gap >= 0 ? 1.0 : -1.0;
      n = (side / dist) * d, gap = side * dist;
    }
    std::array<int, 3> master;
    for (int k = 0; k < 3; ++k) master[k] = facing_node(disc, tri[k], -1.0 * n); // the master group whose normal is n: it faces the slave
    if (!at.loadable.empty() && !(at.loadable[master[0]] && at.loadable[master[1]] && at.loadable[master[2]])) continue;
    ContactPoint p;
    if (!vertex_point(g, v, n, gap, static_cast<int>(g.obstacles.size()) + b, p)) continue;
    p.other = b;
    p.terms = 4;
    for (int k = 0; k < 3; ++k) {
      p.term_node[k + 1] = master[k];
      p.mw[k + 1] = -h.bary[k] * Vec3{1, 1, 1};
      p.lw[k + 1] = (-h.bary[k] * p.area / g.area[master[k]]) * Vec3{1, 1, 1};
    }
    // The gap of the configuration, linearised about its displacement: g = g0 + n · (relative
    // displacement) equals it there.
    if (!at.u.empty())
      for (int i = 0; i < p.terms; ++i) p.g0 -= p.mw[i][0] * dot(n, at.u[p.term_node[i]]);
    p.mu = g.friction;
    out.push_back(p);
  }
  return out;
}

/// A normal row within this fraction of the span of a node's earlier rows depends on them.
constexpr double k_dependent = 1e-3;

/// v without its components along the orthonormal rows R.
Vec3 residual(Vec3 v, const std::vector<Vec3> &R)
{
  for (const Vec3 &q : R) v = v - dot(v, q) * q;
  return v;
}

/// v with the node's prescribed components zeroed: its row on the node's free directions.
Vec3 free_part(const Geometry &g, int node, Vec3 v)
{
  for (int a = 0; a < 3; ++a)
    if ((*g.pattern)[3 * node + a]) v[a] = 0;
  return v;
}

/// The node's free directions orthogonal to the rows R (orthonormal).
std::vector<Vec3> complement(const Geometry &g, int node, const std::vector<Vec3> &R)
{
  std::vector<Vec3> basis = R, out;
  for (int a = 0; a < 3; ++a) {
    if ((*g.pattern)[3 * node + a]) continue;
    Vec3 e{};
    e[a] = 1;
    const Vec3 r = residual(e, basis);
    if (norm(r) > 1e-6) basis.push_back(normalized(r)), out.push_back(normalized(r));
  }
  return out;
}

/// The local frames of one vertex's leading points (`pts`, nearest first; the vertex's nodes share
/// its pattern and follow its leads while it touches) and which of them to drop: the normals
/// take the vertex's free directions first (an obstacle's normal parallel to a nearer obstacle's is
/// implied by it: that point is dropped), then each point with friction takes tangents among the
/// free directions left (both when its normal is the vertex's only row, else the one left, else
/// none: held).
void vertex_frames(const Geometry &g, const std::vector<ContactPoint *> &pts, std::vector<char> &drop)
{
  const int node = pts[0]->node;
  std::vector<Vec3> R;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Vec3 n = pts[i]->frame[0], r = free_part(g, node, n), res = residual(r, R);
    if (norm(res) > k_dependent * norm(r)) {
      R.push_back(normalized(res));
      continue;
    }
    for (std::size_t j = 0; j < i; ++j)
      if (!drop[j] && pts[i]->obstacle >= 0 && pts[j]->obstacle >= 0 && dot(pts[j]->frame[0], n) > 1 - k_dependent) drop[i] = 1;
  }
  for (std::size_t i = 0; i < pts.size(); ++i) {
    ContactPoint &p = *pts[i];
    p.held = {false, true, true};
    if (drop[i] || p.mu <= 0) continue;
    const std::vector<Vec3> G = complement(g, node, R);
    if (G.size() >= 2) {
      p.held = {false, false, false};
      R.push_back(p.frame[1]), R.push_back(p.frame[2]);
    } else if (G.size() == 1) {
      p.frame = {p.frame[0], G[0], cross(p.frame[0], G[0])};
      p.held = {false, false, true};
      R.push_back(G[0]);
    }
  }
}

/// The followers of leading point `lead` at its vertex's other dof nodes: the lead's measure and
/// load at the node (its normal row bound to the partner); for the vertex's anchor (its nearest
/// partner, with friction) the tangential rows tie the node to the anchor's node instead, along the
/// anchor's friction tangents (relative displacement u_node − u_anchor, equal and opposite forces).
void add_followers(const Geometry &g, const ContactPoint &lead, bool anchor, std::vector<ContactPoint> &out)
{
  const Discretization &disc = *g.disc;
  for (int node = disc.first_node(lead.vertex); node < disc.first_node(lead.vertex) + disc.node_count(lead.vertex); ++node) {
    if (node == lead.node) continue;
    ContactPoint f = lead;
    f.node = node;
    f.key = node * g.partners + lead.partner;
    f.facing = false;
    f.term_node[0] = node;
    f.area = g.area[node];
    f.motion = Vec3{0, 0, 0};
    f.held = {false, true, true};
    for (int i = 1; i < f.terms; ++i) f.lw[i] = (g.area[node] / lead.area) * lead.lw[i];
    if (anchor && lead.mu > 0 && !(lead.held[1] && lead.held[2])) {
      for (int i = 1; i < f.terms; ++i) f.mw[i][1] = f.mw[i][2] = f.lw[i][1] = f.lw[i][2] = 0;
      f.term_node[f.terms] = lead.node;
      f.mw[f.terms] = {0, -1, -1};
      f.lw[f.terms] = (-g.area[node] / lead.area) * Vec3{0, 1, 1};
      ++f.terms;
      f.held = lead.held;
    }
    out.push_back(f);
  }
}

/// Frames per vertex (vertex_frames) and the followers at its other nodes; returns the points kept
/// (ContactPoint::lead is set by merge_points).
std::vector<ContactPoint> assign_frames(const Geometry &g, std::vector<ContactPoint> points)
{
  std::vector<int> order(points.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int x, int y) {
    const ContactPoint &a = points[x], &b = points[y];
    return a.vertex != b.vertex ? a.vertex < b.vertex : a.g0 != b.g0 ? a.g0 < b.g0 : a.partner < b.partner;
  });
  std::vector<ContactPoint> out;
  for (std::size_t s = 0; s < order.size();) {
    std::size_t e = s;
    std::vector<ContactPoint *> pts;
    while (e < order.size() && points[order[e]].vertex == points[order[s]].vertex) pts.push_back(&points[order[e++]]);
    std::vector<char> drop(pts.size(), 0);
    vertex_frames(g, pts, drop);
    for (std::size_t k = 0; k < pts.size(); ++k)
      if (!drop[k]) out.push_back(*pts[k]), add_followers(g, *pts[k], k == 0, out);
    s = e;
  }
  return out;
}

} // namespace

std::vector<ContactPoint> obstacle_points(const Geometry &g, const std::vector<Pose> &poses, const std::vector<char> &forced)
{
  std::vector<ContactPoint> out;
  const int nv = g.disc->mesh().num_vertices(), no = static_cast<int>(g.obstacles.size());
  for (int v = 0; v < nv; ++v) {
    if (!g.candidate[v]) continue;
    for (int o = 0; o < no; ++o) {
      const bool far = !forced.empty() && forced[static_cast<std::size_t>(v) * no + o];
      ObstacleGap h;
      if (!g.obstacles[o].gap(g.disc->mesh().vertices[v], poses[o], far ? std::numeric_limits<double>::infinity() : g.reach, h)) continue;
      const double own = g.obstacles[o].obstacle().friction;
      ContactPoint p;
      if (!vertex_point(g, v, h.normal, h.gap, o, p)) continue;
      p.obstacle = o;
      p.mu = std::isnan(own) ? g.friction : own;
      out.push_back(p);
    }
  }
  return out;
}

BodyPlacement::BodyPlacement(const Geometry &g, std::vector<Vec3> displacement, std::vector<char> loadable_nodes)
    : u(std::move(displacement)), loadable(std::move(loadable_nodes))
{
  if (u.empty()) return;
  const Discretization &disc = *g.disc;
  const SurfaceMesh &mesh = disc.mesh();
  vertices = mesh.vertices;
  for (int v = 0; v < mesh.num_vertices(); ++v) { // a vertex moves by its nodes' mean (displacement is continuous)
    Vec3 s{0, 0, 0};
    for (int i = disc.first_node(v); i < disc.first_node(v) + disc.node_count(v); ++i) s = s + u[i];
    if (disc.node_count(v) > 0) vertices[v] = vertices[v] + (1.0 / disc.node_count(v)) * s;
  }
  if (!g.bodies_touch) return;
  for (int b = 0; b < g.bodies.count; ++b) {
    std::vector<int> tris;
    for (int t = 0; t < mesh.num_triangles(); ++t)
      if (g.bodies.of_triangle[t] == b) tris.push_back(t);
    bvh.emplace_back(vertices, mesh.triangles, tris);
  }
  triangles_of.resize(vertices.size());
  for (int t = 0; t < mesh.num_triangles(); ++t)
    for (int k = 0; k < 3; ++k) triangles_of[mesh.triangles[t][k]].push_back(t);
}

std::vector<ContactPoint> body_points(const Geometry &g, const BodyPlacement &at, std::vector<signed char> *slave_of)
{
  std::vector<ContactPoint> out;
  if (!g.bodies_touch) return out;
  const int nb = g.bodies.count;
  if (slave_of && slave_of->size() != static_cast<std::size_t>(nb) * nb) slave_of->assign(static_cast<std::size_t>(nb) * nb, 0);
  for (int a = 0; a < nb; ++a)
    for (int b = a + 1; b < nb; ++b) {
      signed char *kept = slave_of ? &(*slave_of)[static_cast<std::size_t>(a) * nb + b] : nullptr;
      if (kept && *kept) { // the slave chosen before (the pairs' keys and history stay on its side)
        const std::vector<ContactPoint> one = *kept == 1 ? pass(g, at, a, b) : pass(g, at, b, a);
        out.insert(out.end(), one.begin(), one.end());
        continue;
      }
      std::vector<ContactPoint> ab = pass(g, at, a, b), ba = pass(g, at, b, a);
      // One pass per pair: the side with more vertices near the other (the finer mesh there) is
      // the slave; both passes at once would constrain matching meshes twice (a singular D).
      const bool b_slave = ba.size() > ab.size();
      const std::vector<ContactPoint> &slave = b_slave ? ba : ab;
      if (kept && !slave.empty()) *kept = b_slave ? 2 : 1;
      out.insert(out.end(), slave.begin(), slave.end());
    }
  return out;
}

std::vector<ContactPoint> merge_points(const Geometry &g, std::vector<ContactPoint> a, const std::vector<ContactPoint> &b, const std::vector<int> &position)
{
  a.insert(a.end(), b.begin(), b.end());
  std::vector<ContactPoint> out = assign_frames(g, std::move(a));
  std::stable_sort(out.begin(), out.end(), [&](const ContactPoint &x, const ContactPoint &y) {
    const int px = position.empty() ? x.node : position[x.node], py = position.empty() ? y.node : position[y.node];
    return px != py ? px < py : x.partner < y.partner;
  });
  // A follower's lead: the leading point of its vertex and partner.
  std::unordered_map<long long, int> anchor;
  for (std::size_t c = 0; c < out.size(); ++c)
    if (out[c].facing) anchor[static_cast<long long>(out[c].vertex) * g.partners + out[c].partner] = static_cast<int>(c);
  for (ContactPoint &p : out) p.lead = p.facing ? -1 : anchor.at(static_cast<long long>(p.vertex) * g.partners + p.partner);
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
  Box box;
  for (int i = 0; i < nn; ++i) box.add(disc.node_position(i));
  const Vec3 &lo = box.lo, &hi = box.hi;
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
