/// \file interior_stress.hpp
/// Displacement and stress inside the body by Somigliana's identities (stress_kernels.hpp), from
/// the boundary solution: per triangle, the P1 displacement and traction of its corners.
///
/// Quadrature per (point, triangle): Radon's 7-point rule where the point is at least
/// `near_ratio` triangle diameters from the centroid, else the triangle is split 1:4 recursively
/// until every piece satisfies that (or `max_depth` is reached) and each piece takes the 7-point
/// rule. The 7-point rule's points, with the densities folded in, are the triangle's *particles*:
/// far away, a triangle is seven point sources (a force and a double-layer density each), which is
/// what a fast evaluation (interior/interior_evaluation.hpp) compresses.
///
/// Close to the surface the integrands are nearly singular (1/r² and 1/r³ against a smooth
/// density, whose integrals cancel to a result ~ r/L times smaller): points closer than a band of
/// a couple of element sizes are not integrated but interpolated along the normal between the
/// surface stress and two points at the band's depth (near_surface.hpp).
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/bem/discretization.hpp"
#include "hssbem/core/option_table.hpp"
#include "hssbem/post/stress_kernels.hpp"

#include <array>
#include <vector>

namespace hssbem {

struct NodalSolution; // post.hpp

/// Quadrature of the interior identities (options -bem_interior_*).
struct InteriorQuadrature {
  double near_ratio = option_default::bem_interior_near_ratio; ///< split a triangle while the point is closer than this many diameters to its centroid
  int max_depth = option_default::bem_interior_max_depth;      ///< levels of 1:4 splits at most
};

/// The 7-point rule's points of all triangles (7 consecutive per triangle), structure of arrays:
/// position y, force f = w t(y), double-layer density m = w u(y), the triangle's normal n.
struct Particles {
  static constexpr int per_triangle = 7;
  std::vector<double> y[3], f[3], m[3], n[3];
  std::size_t size() const { return y[0].size(); }
};

/// Traction of triangle t at corner c, as the solve loaded it: the node's traction; at a node
/// loaded by a pressure, −p n_t (the triangle's own normal) plus the rest of the node's traction —
/// what it carries beyond the pressure's nodal value (a contact traction; a reaction along a
/// component whose displacement is prescribed).
std::vector<std::array<Vec3, 3>> corner_tractions(const Discretization &disc, const SystemSelection &sel, const NodalSolution &sol);

/// Displacement of triangle t at corner c (its corner's dof node).
std::vector<std::array<Vec3, 3>> corner_displacements(const Discretization &disc, const std::vector<Vec3> &u);

/// A linear elastic field, u(y) = a + G y, σ = Hooke(G) (an exact solution that the identities
/// reproduce), subtracted from the data of a triangle by add_triangle_minus.
struct LinearField {
  Vec3 a{};
  Mat3 G{};
  Voigt stress{};
};

class SomiglianaSources {
public:
  /// u: displacement per dof node; t: traction per triangle corner (corner_tractions).
  SomiglianaSources(const Discretization &disc, const Material &material, const std::vector<Vec3> &u, const std::vector<std::array<Vec3, 3>> &t,
                    const InteriorQuadrature &quad = {});

  int num_triangles() const { return static_cast<int>(m_tri.size()); }
  const SomiglianaConstants &constants() const { return m_k; }
  const InteriorQuadrature &quadrature() const { return m_quad; }
  const Particles &particles() const { return m_particles; }
  const Vec3 &centroid(int e) const { return m_tri[e].centroid; }
  /// The radius around the centroid within which triangle e needs more than its particles.
  double near_radius(int e) const { return m_tri[e].near_radius; }
  /// Radius of the smallest ball around the centroid holding the triangle.
  double radius(int e) const { return m_tri[e].radius; }

  /// Whether the particles of triangle e integrate it at x.
  bool is_regular(const Vec3 &x, int e) const
  {
    const Vec3 d = x - m_tri[e].centroid;
    return dot(d, d) >= m_tri[e].near_radius * m_tri[e].near_radius;
  }
  /// out[0..9) += displacement and stress at x of triangle e, split where x is near.
  void add_triangle(const Vec3 &x, int e, double *out) const;
  /// The same for the triangle's data minus the field f (u − f.a − f.G y, t − f.stress n).
  void add_triangle_minus(const Vec3 &x, int e, const LinearField &f, double *out) const;
  /// out[0..9) += the field at x of every triangle (O(triangles); the reference the fast
  /// evaluation is checked against).
  void add_all(const Vec3 &x, double *out) const;

private:
  struct TriangleData {
    std::array<Vec3, 3> p;
    Vec3 n, centroid;
    double area, diameter, radius, near_radius;
    std::array<Vec3, 3> u, t;
  };
  void add_adaptive(const Vec3 &x, const TriangleData &tri, const std::array<Vec3, 3> &u, const std::array<Vec3, 3> &t, double *out) const;

  SomiglianaConstants m_k;
  InteriorQuadrature m_quad;
  std::vector<TriangleData> m_tri;
  Particles m_particles;
};

} // namespace hssbem
