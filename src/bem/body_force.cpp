// A uniform body force's particular solution (body_force.hpp).
#include "hssbem/bem/body_force.hpp"

#include <cmath>
#include <stdexcept>

namespace hssbem {

namespace {

bool finite(const Vec3 &v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

} // namespace

UniformBodyForce::UniformBodyForce(const Material &material, const Vec3 &force_per_volume, const Vec3 &origin)
    : m_b(force_per_volume), m_origin(origin)
{
  if (!finite(force_per_volume)) throw std::invalid_argument("the body force per volume must be finite");
  if (!finite(origin)) throw std::invalid_argument("the body force's origin must be finite");
  const double bulk = material.lambda() + 2.0 * material.mu() / 3.0;
  m_inv_3k = 1.0 / (3.0 * bulk);
}

Vec3 UniformBodyForce::displacement(const Vec3 &x) const
{
  const Vec3 r = x - m_origin;
  const double br = dot(m_b, r), rr = dot(r, r);
  return -m_inv_3k * (br * r - 0.5 * rr * m_b);
}

Mat3 UniformBodyForce::gradient(const Vec3 &x) const
{
  // ∂u_i/∂x_j = −(1/3K) [b_j r_i + (b·r) δ_ij − r_j b_i]
  const Vec3 r = x - m_origin;
  const double br = dot(m_b, r);
  Mat3 g{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) g[3 * i + j] = -m_inv_3k * (m_b[j] * r[i] + (i == j ? br : 0.0) - r[j] * m_b[i]);
  return g;
}

Voigt UniformBodyForce::stress(const Vec3 &x) const
{
  const double p = -dot(m_b, x - m_origin);
  return {p, p, p, 0, 0, 0};
}

Vec3 UniformBodyForce::traction(const Vec3 &x, const Vec3 &n) const { return -dot(m_b, x - m_origin) * n; }

ParticularTraces particular_traces(const Discretization &disc, const UniformBodyForce &force)
{
  ParticularTraces p;
  if (force.zero()) return p;
  p.u.resize(disc.num_nodes());
  p.t.resize(disc.num_nodes());
  for (int i = 0; i < disc.num_nodes(); ++i) {
    const Vec3 &x = disc.node_position(i);
    p.u[i] = force.displacement(x);
    p.t[i] = force.traction(x, disc.node(i).normal);
  }
  return p;
}

SystemSelection homogeneous_selection(SystemSelection sel, const Discretization &disc, const UniformBodyForce &force)
{
  if (force.zero()) return sel;
  const ParticularTraces p = particular_traces(disc, force);
  for (int i = 0; i < disc.num_nodes(); ++i) {
    for (int c = 0; c < 3; ++c) sel.known[i][c] -= sel.displacement_known[i][c] ? p.u[i][c] : p.t[i][c];
    if (!sel.pressure.empty() && !std::isnan(sel.pressure[i])) sel.pressure[i] -= dot(force.force_per_volume(), disc.node_position(i) - force.origin());
  }
  return sel;
}

} // namespace hssbem
