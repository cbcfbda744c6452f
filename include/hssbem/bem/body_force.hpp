/// \file body_force.hpp
/// A uniform body force b (force per volume: gravity is b = ρ g) through a particular solution of
/// Navier's equation, so that no volume mesh is needed (docs/problem-file.md, "gravity").
///
/// With K = λ + 2μ/3 the bulk modulus and x₀ an origin (the body's centroid keeps the values small),
///   u_p(x) = −(1/(3K)) [ (b·r) r − ½ |r|² b ],  r = x − x₀,
///   σ_p(x) = −(b·r) I   (a hydrostatic stress, linear in x),
/// satisfies div σ_p + b = 0 and σ_p = λ tr(ε_p) I + 2μ ε_p with ε_p = −(b·r)/(3K) I. The
/// solution of the body's problem is u = u_p + u_h, t = t_p + t_h (t_p = σ_p n), where (u_h, t_h)
/// solve the homogeneous boundary integral equation H u_h = G t_h with the boundary data
/// corrected by the particular solution's traces: u_h = ū − u_p where the displacement is
/// prescribed, t_h = t̄ − t_p where the traction is. Inside, u and σ add u_p and σ_p to the
/// Somigliana fields of (u_h, t_h). The load the body carries is its weight: ∫ t dA = −b V.
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/bem/discretization.hpp"
#include "hssbem/bem/kelvin.hpp"
#include "hssbem/core/geometry.hpp"

#include <vector>

namespace hssbem {

class UniformBodyForce {
public:
  UniformBodyForce() = default;
  /// The force per unit volume b and the origin x₀ of the particular solution. Throws
  /// std::invalid_argument for a non-finite b or origin.
  UniformBodyForce(const Material &material, const Vec3 &force_per_volume, const Vec3 &origin);

  /// b = 0: nothing to add.
  bool zero() const { return m_b[0] == 0 && m_b[1] == 0 && m_b[2] == 0; }
  const Vec3 &force_per_volume() const { return m_b; }
  const Vec3 &origin() const { return m_origin; }

  Vec3 displacement(const Vec3 &x) const;
  /// ∇u_p, row-major (G[3i + j] = ∂u_i/∂x_j).
  Mat3 gradient(const Vec3 &x) const;
  /// σ_p in Voigt order (xx, yy, zz, yz, xz, xy).
  Voigt stress(const Vec3 &x) const;
  /// σ_p n on a surface of unit normal n.
  Vec3 traction(const Vec3 &x, const Vec3 &n) const;

private:
  Vec3 m_b{0, 0, 0}, m_origin{0, 0, 0};
  double m_inv_3k = 0; ///< 1 / (3K)
};

/// The particular solution's traces at every dof node: u_p at the node's vertex (where its values
/// live), t_p = σ_p n with the node's normal. Empty vectors when the force is zero.
struct ParticularTraces {
  std::vector<Vec3> u, t;
};
ParticularTraces particular_traces(const Discretization &disc, const UniformBodyForce &force);

/// The selection of the homogeneous problem: `sel`'s known values less the particular
/// solution's traces (u_h = ū − u_p where u is prescribed, t_h = t̄ − t_p where t is), and a
/// pressure node's pressure less b·r (t_p = −(b·r) n is a pressure b·r, linear over each flat
/// triangle, so the homogeneous pressure stays exact there). `sel` itself when the force is zero.
SystemSelection homogeneous_selection(SystemSelection sel, const Discretization &disc, const UniformBodyForce &force);

} // namespace hssbem
