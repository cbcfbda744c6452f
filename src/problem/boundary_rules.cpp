/// \file boundary_rules.cpp
/// Boundary rules meet the mesh: selection, per-vertex conditions, and per-dof-node conditions.
#include "hssbem/problem/problem.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <set>
#include <stdexcept>

namespace hssbem {
namespace {

constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();

/// Names the file and the rule in messages: `list` is the JSON path of the rule list
/// ("boundary", "frames[3].boundary"), `index` the rule's place in it.
struct RuleContext {
  const std::string &origin;
  const std::string &list;
  std::size_t index;

  [[noreturn]] void fail(const std::string &what) const
  {
    const std::string item = index == std::string::npos ? list : list + "[" + std::to_string(index) + "]"; // npos: not a list item
    throw ProblemError((origin.empty() ? std::string() : origin + ": ") + item + ": " + what);
  }
};

/// What every rule needs to know about the mesh, computed once.
struct MeshView {
  const SurfaceMesh &mesh;
  std::vector<char> used; ///< vertex is a corner of some triangle
  double tolerance;       ///< slack on inclusive box / sphere bounds
};

/// Coordinates written by meshers carry round-off (0.30000000000000004): a vertex meant to sit on
/// a box face or sphere should still be selected, so bounds get a slack relative to the mesh size.
double geometric_tolerance(const SurfaceMesh &mesh)
{
  return 1e-10 * Box::of(mesh.vertices).diagonal();
}

MeshView make_view(const SurfaceMesh &mesh)
{
  MeshView view{mesh, std::vector<char>(mesh.vertices.size(), 0), geometric_tolerance(mesh)};
  for (const auto &tri : mesh.triangles)
    for (int v : tri)
      view.used[v] = 1;
  return view;
}

const char *value_key(BoundaryRule::Kind kind)
{
  switch (kind) {
  case BoundaryRule::Kind::Displacement: return "displacement";
  case BoundaryRule::Kind::Traction: return "traction";
  default: return "pressure";
  }
}

std::size_t value_count(const BoundaryRule &rule)
{
  return rule.kind == BoundaryRule::Kind::Pressure ? rule.pressure.size() : rule.rows.size();
}

/// Known names, or the known tags when the mesh names none, for "unknown region" messages.
std::string known_regions(const SurfaceMesh &mesh)
{
  std::string s;
  for (const auto &[name, tag] : mesh.region_tags)
    s += (s.empty() ? "" : ", ") + name;
  if (!s.empty())
    return "known: " + s;
  std::set<int> tags(mesh.triangle_region.begin(), mesh.triangle_region.end());
  tags.erase(-1);
  for (int t : tags)
    s += (s.empty() ? "" : ", ") + std::to_string(t);
  return s.empty() ? "the mesh has no physical groups" : "known tags: " + s;
}

int region_tag(const Selector &s, const SurfaceMesh &mesh, const RuleContext &ctx)
{
  if (!s.region_name.empty()) {
    const auto it = mesh.region_tags.find(s.region_name);
    if (it == mesh.region_tags.end())
      ctx.fail("unknown region '" + s.region_name + "' (" + known_regions(mesh) + ")");
    return it->second;
  }
  const bool named = std::any_of(mesh.region_tags.begin(), mesh.region_tags.end(),
                                 [&](const auto &nt) { return nt.second == s.region_tag; });
  const bool used = std::find(mesh.triangle_region.begin(), mesh.triangle_region.end(),
                              s.region_tag) != mesh.triangle_region.end();
  if (s.region_tag <= 0 || !(named || used))
    ctx.fail("unknown region " + std::to_string(s.region_tag) + " (" + known_regions(mesh) + ")");
  return s.region_tag;
}

std::vector<int> select_region(const Selector &s, const MeshView &view, const RuleContext &ctx)
{
  const SurfaceMesh &mesh = view.mesh;
  const int tag = region_tag(s, mesh, ctx);
  std::vector<char> in(mesh.vertices.size(), 0);
  for (std::size_t t = 0; t < mesh.triangles.size() && t < mesh.triangle_region.size(); ++t)
    if (mesh.triangle_region[t] == tag)
      for (int v : mesh.triangles[t])
        in[v] = 1;
  std::vector<int> sel;
  for (int v = 0; v < mesh.num_vertices(); ++v)
    if (in[v])
      sel.push_back(v);
  return sel;
}

/// Used vertices (ascending) whose position satisfies `inside`.
template <class Inside> std::vector<int> select_where(const MeshView &view, Inside inside)
{
  std::vector<int> sel;
  for (int v = 0; v < view.mesh.num_vertices(); ++v)
    if (view.used[v] && inside(view.mesh.vertices[v]))
      sel.push_back(v);
  return sel;
}

std::vector<int> select_box(const Selector &s, const MeshView &view)
{
  const double tol = view.tolerance;
  return select_where(view, [&](const Vec3 &p) {
    for (int c = 0; c < 3; ++c)
      if (p[c] < s.lo[c] - tol || p[c] > s.hi[c] + tol)
        return false;
    return true;
  });
}

std::vector<int> select_sphere(const Selector &s, const MeshView &view)
{
  const double r = s.radius + view.tolerance;
  return select_where(view, [&](const Vec3 &p) { return dot(p - s.center, p - s.center) <= r * r; });
}

/// Listed vertices, ascending. Rows follow ascending vertex index, so a list in another order
/// with one row per vertex would silently pair rows with the wrong vertices: refuse it.
std::vector<int> select_listed(const BoundaryRule &rule, const MeshView &view, const RuleContext &ctx)
{
  const int nv = view.mesh.num_vertices();
  for (int v : rule.where.vertices)
    if (v < 0 || v >= nv)
      ctx.fail("vertex index " + std::to_string(v) + " out of range (mesh has " + std::to_string(nv) +
               " vertices)");
  std::vector<int> sel = rule.where.vertices;
  const bool ascending = std::is_sorted(sel.begin(), sel.end());
  std::sort(sel.begin(), sel.end());
  const auto dup = std::adjacent_find(sel.begin(), sel.end());
  if (dup != sel.end())
    ctx.fail("vertex index " + std::to_string(*dup) + " listed twice in 'vertices'");
  if (!ascending && value_count(rule) > 1)
    ctx.fail(std::string("'vertices' must be in ascending order when '") + value_key(rule.kind) +
             "' gives one row per vertex (rows follow ascending vertex index)");
  return sel;
}

std::vector<int> select(const BoundaryRule &rule, const MeshView &view, const RuleContext &ctx)
{
  const Selector &s = rule.where;
  switch (s.kind) {
  case Selector::Kind::Region: return select_region(s, view, ctx);
  case Selector::Kind::Box: return select_box(s, view);
  case Selector::Kind::Sphere: return select_sphere(s, view);
  case Selector::Kind::Vertices: return select_listed(rule, view, ctx);
  default: {
    std::vector<int> all(view.mesh.vertices.size());
    std::iota(all.begin(), all.end(), 0);
    return all;
  }
  }
}

void check_value_count(const BoundaryRule &rule, std::size_t selected, const RuleContext &ctx)
{
  const std::size_t n = value_count(rule);
  const std::string key = value_key(rule.kind);
  if (n == 0)
    ctx.fail("'" + key + "' has no value");
  if (n != 1 && n != selected)
    ctx.fail("'" + key + "' has " + std::to_string(n) +
             (rule.kind == BoundaryRule::Kind::Pressure ? " values" : " rows") +
             " but the selection has " + std::to_string(selected) + " vertices");
}

VertexConditions traction_free(int num_vertices)
{
  VertexConditions vc;
  vc.displacement_prescribed.assign(num_vertices, {false, false, false});
  vc.value.assign(num_vertices, {0, 0, 0});
  vc.pressure.assign(num_vertices, k_nan);
  vc.from_pressure.assign(num_vertices, {false, false, false});
  return vc;
}

/// NaN is "null": the component keeps what earlier rules gave it.
void set_component(VertexConditions &vc, int v, int c, bool displacement, double x)
{
  if (std::isnan(x))
    return;
  vc.displacement_prescribed[v][c] = displacement;
  vc.value[v][c] = x;
  vc.from_pressure[v][c] = false;
  const auto &fp = vc.from_pressure[v];
  if (!fp[0] && !fp[1] && !fp[2])
    vc.pressure[v] = k_nan;
}

void apply_rows(const BoundaryRule &rule, const std::vector<int> &sel, VertexConditions &vc)
{
  const bool displacement = rule.kind == BoundaryRule::Kind::Displacement;
  const bool broadcast = rule.rows.size() == 1;
  for (std::size_t k = 0; k < sel.size(); ++k) {
    const Vec3 &row = rule.rows[broadcast ? 0 : k];
    for (int c = 0; c < 3; ++c)
      set_component(vc, sel[k], c, displacement, row[c]);
  }
}

void apply_pressure(const BoundaryRule &rule, const std::vector<int> &sel, VertexConditions &vc)
{
  const bool broadcast = rule.pressure.size() == 1;
  for (std::size_t k = 0; k < sel.size(); ++k) {
    const double p = rule.pressure[broadcast ? 0 : k];
    if (std::isnan(p))
      continue;
    const int v = sel[k];
    vc.displacement_prescribed[v] = {false, false, false};
    vc.value[v] = {0, 0, 0}; // the traction -p n needs the node normal: node_conditions
    vc.from_pressure[v] = {true, true, true};
    vc.pressure[v] = p;
  }
}

} // namespace

VertexConditions apply_rules(const std::vector<BoundaryRule> &rules, const SurfaceMesh &mesh,
                             const std::string &origin, const std::string &list)
{
  const MeshView view = make_view(mesh);
  VertexConditions vc = traction_free(mesh.num_vertices());
  for (std::size_t i = 0; i < rules.size(); ++i) {
    const RuleContext ctx{origin, list, i};
    const std::vector<int> sel = select(rules[i], view, ctx);
    if (sel.empty())
      ctx.fail("selects no vertex");
    check_value_count(rules[i], sel.size(), ctx);
    if (rules[i].kind == BoundaryRule::Kind::Pressure)
      apply_pressure(rules[i], sel, vc);
    else
      apply_rows(rules[i], sel, vc);
  }
  return vc;
}

std::vector<int> select_vertices(const Selector &where, const SurfaceMesh &mesh, const std::string &origin, const std::string &what)
{
  const MeshView view = make_view(mesh);
  BoundaryRule rule;
  rule.where = where;
  rule.rows = {Vec3{0, 0, 0}};
  const RuleContext ctx{origin, what, std::string::npos};
  std::vector<int> sel = select(rule, view, ctx);
  if (sel.empty())
    ctx.fail("selects no vertex");
  return sel;
}

NodeConditions node_conditions(const VertexConditions &vc, const Discretization &disc)
{
  const std::size_t nv = disc.mesh().vertices.size();
  if (vc.value.size() != nv || vc.displacement_prescribed.size() != nv || vc.pressure.size() != nv ||
      vc.from_pressure.size() != nv)
    throw std::invalid_argument("node_conditions: vertex conditions do not match the mesh");
  NodeConditions nc;
  nc.displacement_prescribed.resize(disc.num_nodes());
  nc.value.resize(disc.num_nodes());
  for (int i = 0; i < disc.num_nodes(); ++i) {
    const DofNode &node = disc.node(i);
    const int v = node.vertex;
    nc.displacement_prescribed[i] = vc.displacement_prescribed[v];
    for (int c = 0; c < 3; ++c)
      nc.value[i][c] = vc.from_pressure[v][c] ? -vc.pressure[v] * node.normal[c] : vc.value[v][c];
  }
  return nc;
}

namespace {

/// Whether a rule reaches dof node i of a selected vertex. Displacement is continuous, so it
/// reaches every node of the vertex; a traction given on a region acts only on the nodes whose
/// smooth group has a triangle in that region (the copy of an edge vertex on a neighbouring face
/// keeps its own traction).
bool reaches(const BoundaryRule &rule, int region, const Discretization &disc, int i)
{
  if (rule.kind == BoundaryRule::Kind::Displacement || region < 0) return true;
  const auto &tr = disc.mesh().triangle_region;
  for (const int *t = disc.support_begin(i); t != disc.support_end(i); ++t)
    if (*t < static_cast<int>(tr.size()) && tr[*t] == region) return true;
  return false;
}

void apply_to_node(const BoundaryRule &rule, std::size_t k, const DofNode &node, NodeConditions &nc, int i)
{
  if (rule.kind == BoundaryRule::Kind::Pressure) {
    const double p = rule.pressure[rule.pressure.size() == 1 ? 0 : k];
    if (std::isnan(p)) return;
    nc.displacement_prescribed[i] = {false, false, false};
    nc.value[i] = -p * node.normal;
    nc.pressure[i] = p;
    return;
  }
  const Vec3 &row = rule.rows[rule.rows.size() == 1 ? 0 : k];
  for (int c = 0; c < 3; ++c)
    if (!std::isnan(row[c])) {
      nc.pressure[i] = k_nan; // no longer a pure pressure node: its nodal traction stands
      nc.displacement_prescribed[i][c] = rule.kind == BoundaryRule::Kind::Displacement;
      nc.value[i][c] = row[c];
    }
}

NodeConditions traction_free_nodes(const Discretization &disc)
{
  NodeConditions nc;
  nc.displacement_prescribed.assign(disc.num_nodes(), {false, false, false});
  nc.value.assign(disc.num_nodes(), {0, 0, 0});
  nc.pressure.assign(disc.num_nodes(), k_nan);
  return nc;
}

/// Applies `rules` on top of what `nc` holds, so that a frame's rules follow the base rules.
void apply_to_nodes(const std::vector<BoundaryRule> &rules, const MeshView &view, const Discretization &disc,
                    const std::string &origin, const std::string &list, NodeConditions &nc)
{
  for (std::size_t r = 0; r < rules.size(); ++r) {
    const RuleContext ctx{origin, list, r};
    const std::vector<int> sel = select(rules[r], view, ctx);
    if (sel.empty()) ctx.fail("selects no vertex");
    check_value_count(rules[r], sel.size(), ctx);
    const int region = rules[r].where.kind == Selector::Kind::Region ? region_tag(rules[r].where, view.mesh, ctx) : -1;
    for (std::size_t k = 0; k < sel.size(); ++k)
      for (int i = disc.first_node(sel[k]); i < disc.first_node(sel[k]) + disc.node_count(sel[k]); ++i)
        if (reaches(rules[r], region, disc, i)) apply_to_node(rules[r], k, disc.node(i), nc, i);
  }
}

} // namespace

NodeConditions apply_rules(const std::vector<BoundaryRule> &rules, const Discretization &disc, const std::string &origin,
                           const std::string &list)
{
  NodeConditions nc = traction_free_nodes(disc);
  apply_to_nodes(rules, make_view(disc.mesh()), disc, origin, list, nc);
  return nc;
}

NodeConditions frame_conditions(const ProblemSpec &spec, std::size_t frame, const Discretization &disc)
{
  if (frame >= spec.frames.size())
    throw std::out_of_range("frame_conditions: frame " + std::to_string(frame) + " of " +
                            std::to_string(spec.frames.size()));
  const MeshView view = make_view(disc.mesh());
  NodeConditions nc = traction_free_nodes(disc);
  apply_to_nodes(spec.rules, view, disc, spec.file, "boundary", nc);
  const std::string list = "frames[" + std::to_string(frame) + "].boundary";
  apply_to_nodes(spec.frames[frame].rules, view, disc, spec.file, list, nc);
  return nc;
}

int NodeConditions::num_displacement_prescribed() const
{
  int n = 0;
  for (const auto &dp : displacement_prescribed)
    n += int(dp[0]) + int(dp[1]) + int(dp[2]);
  return n;
}

std::vector<char> NodeConditions::unknown_pattern() const
{
  std::vector<char> p(3 * displacement_prescribed.size());
  for (std::size_t i = 0; i < displacement_prescribed.size(); ++i)
    for (int c = 0; c < 3; ++c) p[3 * i + c] = displacement_prescribed[i][c];
  return p;
}

} // namespace hssbem
