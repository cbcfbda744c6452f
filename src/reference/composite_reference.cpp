// The reference of several bodies (composite_reference.hpp): each body a mesh, a discretization,
// an operator and a reference of its own; vectors split by body and scattered back.
#include "hssbem/reference/composite_reference.hpp"

#include "hssbem/core/timer.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hssbem {

/// One body: its own surface (the whole mesh's triangles of the body, vertices renumbered), its
/// dof nodes and operator, its reference, and where its nodes sit in the whole mesh.
struct CompositeReference::Part {
  SurfaceMesh mesh;
  std::unique_ptr<Discretization> disc;
  std::unique_ptr<BemOperator> op;
  std::unique_ptr<ReferenceFactorization> ref;
  std::vector<int> nodes; ///< per own dof node: the whole mesh's
  double seconds = 0;
};

namespace {

/// Body b's triangles of the whole mesh, in their order, over its own vertices (in theirs).
SurfaceMesh body_mesh(const Discretization &disc, const std::vector<int> &node_body, int b, std::vector<int> &vertex_of)
{
  std::vector<int> triangles;
  for (int t = 0; t < disc.mesh().num_triangles(); ++t)
    if (node_body[disc.element_node(t, 0)] == b) triangles.push_back(t);
  return sub_mesh(disc.mesh(), triangles, &vertex_of);
}

/// The whole mesh's dof node of each of the body's own: the node of the same vertex whose
/// collocation point is the same (the smooth groups of a vertex depend on its fan alone).
std::vector<int> match_nodes(const Discretization &whole, const Discretization &own, const std::vector<int> &vertex_of, const std::vector<int> &node_body, int b)
{
  std::vector<int> out(own.num_nodes(), -1);
  for (int k = 0; k < own.num_nodes(); ++k) {
    const int v = vertex_of[own.node(k).vertex];
    double best = 1e300;
    for (int i = whole.first_node(v); i < whole.first_node(v) + whole.node_count(v); ++i) {
      const double d = norm(whole.node(i).point - own.node(k).point);
      if (d < best) best = d, out[k] = i;
    }
    const double size = norm(whole.node(out[k] < 0 ? 0 : out[k]).point) + 1.0;
    if (out[k] < 0 || best > 1e-12 * size || node_body[out[k]] != b)
      throw std::logic_error("CompositeReference: body " + std::to_string(b) + "'s own discretization does not reproduce the mesh's dof nodes at vertex " + std::to_string(v));
  }
  return out;
}

std::vector<char> pick(const std::vector<char> &whole, const std::vector<int> &nodes)
{
  std::vector<char> out(3 * nodes.size());
  for (std::size_t k = 0; k < nodes.size(); ++k)
    for (int c = 0; c < 3; ++c) out[3 * k + c] = whole[3 * static_cast<std::size_t>(nodes[k]) + c];
  return out;
}

} // namespace

CompositeReference::CompositeReference(const BemOperator &op, const std::vector<int> &node_body, std::vector<char> pattern, std::vector<char> kept,
                                       const BodyReferenceFactory &make)
    : m_pattern(std::move(pattern)), m_body(node_body)
{
  const Discretization &disc = op.discretization();
  const int nn = disc.num_nodes();
  if (static_cast<int>(m_body.size()) != nn) throw std::invalid_argument("CompositeReference: node_body needs one entry per dof node");
  if (static_cast<int>(m_pattern.size()) != 3 * nn) throw std::invalid_argument("CompositeReference: the pattern needs one entry per unknown");
  if (!kept.empty() && kept.size() != m_pattern.size()) throw std::invalid_argument("CompositeReference: kept needs one entry per unknown (or none)");
  if (kept.empty()) kept.assign(m_pattern.size(), 1);
  const int bodies = nn == 0 ? 0 : *std::max_element(m_body.begin(), m_body.end()) + 1;
  if (nn > 0 && *std::min_element(m_body.begin(), m_body.end()) < 0) throw std::invalid_argument("CompositeReference: a dof node of no body");
  m_local.assign(nn, -1);
  for (int b = 0; b < bodies; ++b) {
    const Timer timer;
    auto part = std::make_unique<Part>();
    std::vector<int> vertex_of;
    part->mesh = body_mesh(disc, m_body, b, vertex_of);
    part->disc = std::make_unique<Discretization>(part->mesh, disc.feature_angle_deg());
    part->nodes = match_nodes(disc, *part->disc, vertex_of, m_body, b);
    for (std::size_t k = 0; k < part->nodes.size(); ++k) m_local[part->nodes[k]] = static_cast<int>(k);
    part->op = std::make_unique<BemOperator>(*part->disc, op.material(), op.quadrature_options());
    part->ref = make(*part->op, pick(m_pattern, part->nodes), pick(kept, part->nodes), b);
    if (!part->ref || part->ref->num_unknowns() != 3 * part->disc->num_nodes()) throw std::invalid_argument("CompositeReference: the factory's reference does not fit body " + std::to_string(b));
    part->seconds = timer.seconds();
    m_parts.push_back(std::move(part));
  }
  for (int i = 0; i < nn; ++i)
    if (m_local[i] < 0) throw std::logic_error("CompositeReference: dof node " + std::to_string(i) + " is on no body's surface");
}

CompositeReference::~CompositeReference() = default;

const ReferenceFactorization &CompositeReference::body_reference(int b) const { return *m_parts.at(b)->ref; }
const std::vector<int> &CompositeReference::body_nodes(int b) const { return m_parts.at(b)->nodes; }
double CompositeReference::body_seconds(int b) const { return m_parts.at(b)->seconds; }

void CompositeReference::gather(int b, const double *x, double *xb) const
{
  const std::vector<int> &nodes = m_parts[b]->nodes;
  for (std::size_t k = 0; k < nodes.size(); ++k)
    for (int c = 0; c < 3; ++c) xb[3 * k + c] = x[3 * static_cast<std::size_t>(nodes[k]) + c];
}

void CompositeReference::scatter(int b, const double *xb, double *x) const
{
  const std::vector<int> &nodes = m_parts[b]->nodes;
  for (std::size_t k = 0; k < nodes.size(); ++k)
    for (int c = 0; c < 3; ++c) x[3 * static_cast<std::size_t>(nodes[k]) + c] = xb[3 * k + c];
}

void CompositeReference::solve(double *X, int nrhs) const
{
  const std::size_t n = m_pattern.size();
  for (int b = 0; b < num_bodies(); ++b) {
    const std::size_t nb = 3 * m_parts[b]->nodes.size();
    std::vector<double> Xb(nb * nrhs);
    for (int r = 0; r < nrhs; ++r) gather(b, X + r * n, &Xb[r * nb]);
    m_parts[b]->ref->solve(Xb.data(), nrhs);
    for (int r = 0; r < nrhs; ++r) scatter(b, &Xb[r * nb], X + r * n);
  }
}

void CompositeReference::columns(const std::vector<int> &js, double *out) const
{
  const std::size_t n = m_pattern.size(), chunk = 1024; // bounds the body's block beside out
  std::vector<std::vector<int>> local(num_bodies()), where(num_bodies());
  for (std::size_t q = 0; q < js.size(); ++q) {
    const int j = js[q];
    if (j < 0 || static_cast<std::size_t>(j) >= n) throw std::out_of_range("reference: column " + std::to_string(j) + " out of range");
    const int b = m_body[j / 3];
    local[b].push_back(3 * m_local[j / 3] + j % 3), where[b].push_back(static_cast<int>(q));
  }
  std::fill(out, out + n * js.size(), 0.0);
  for (int b = 0; b < num_bodies(); ++b) {
    const std::size_t nb = 3 * m_parts[b]->nodes.size();
    for (std::size_t first = 0; first < local[b].size(); first += chunk) {
      const std::size_t count = std::min(chunk, local[b].size() - first);
      const std::vector<int> part(local[b].begin() + first, local[b].begin() + first + count);
      std::vector<double> block(nb * count);
      m_parts[b]->ref->columns(part, block.data());
      for (std::size_t q = 0; q < count; ++q) scatter(b, &block[q * nb], out + where[b][first + q] * n);
    }
  }
}

void CompositeReference::free_response(const SystemSelection &sel, std::vector<double> &y) const
{
  if (sel.displacement_known.size() * 3 != m_pattern.size() || sel.known.size() * 3 != m_pattern.size())
    throw std::invalid_argument("reference: the values do not match the reference's nodes");
  y.assign(m_pattern.size(), 0.0);
  for (int b = 0; b < num_bodies(); ++b) {
    const std::vector<int> &nodes = m_parts[b]->nodes;
    SystemSelection s;
    bool loaded = false;
    for (int i : nodes) {
      s.displacement_known.push_back(sel.displacement_known[i]);
      s.known.push_back(sel.known[i]);
      if (!sel.pressure.empty()) s.pressure.push_back(sel.pressure[i]);
      loaded = loaded || sel.known[i] != Vec3{0, 0, 0} || (!sel.pressure.empty() && !std::isnan(sel.pressure[i]));
    }
    std::vector<double> yb;
    if (!loaded) { // no load on the body: its response is zero (the pattern is still checked)
      for (std::size_t k = 0; k < nodes.size(); ++k)
        for (int c = 0; c < 3; ++c)
          if (static_cast<char>(s.displacement_known[k][c]) != m_pattern[3 * static_cast<std::size_t>(nodes[k]) + c])
            throw std::invalid_argument("reference: the free response needs the reference pattern (unknown " + std::to_string(3 * nodes[k] + c) + " differs)");
      continue;
    }
    m_parts[b]->ref->free_response(s, yb);
    scatter(b, yb.data(), y.data());
  }
}

std::size_t CompositeReference::memory_bytes() const
{
  std::size_t bytes = 0;
  for (const auto &p : m_parts) bytes += p->ref->memory_bytes();
  return bytes;
}

bool CompositeReference::exact_columns() const
{
  return std::all_of(m_parts.begin(), m_parts.end(), [](const std::unique_ptr<Part> &p) { return p->ref->exact_columns(); });
}

} // namespace hssbem
