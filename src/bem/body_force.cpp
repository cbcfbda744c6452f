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

Voigt UniformBodyForce::stress(const Vec3 &x) const
{
  const double p = -dot(m_b, x - m_origin);
  return {p, p, p, 0, 0, 0};
}

Vec3 UniformBodyForce::traction(const Vec3 &x, const Vec3 &n) const { return -dot(m_b, x - m_origin) * n; }

} // namespace hssbem
