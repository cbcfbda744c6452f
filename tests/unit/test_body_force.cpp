/// \file test_body_force.cpp
/// The particular solution of a uniform body force (bem/body_force.hpp): Navier's equation by
/// finite differences (exact for a quadratic field up to round-off), Hooke's law between its
/// strain and its stress, and the load it puts on a closed surface (∫ σ_p n dA = −b V).
#include "hssbem/bem/body_force.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

using namespace hssbem;

namespace {

/// ∂u_i/∂x_j by central differences (exact for a quadratic u, but for round-off).
std::array<Vec3, 3> gradient(const UniformBodyForce &f, const Vec3 &x, double h)
{
  std::array<Vec3, 3> g{}; // g[i][j] = ∂u_i/∂x_j
  for (int j = 0; j < 3; ++j) {
    Vec3 xp = x, xm = x;
    xp[j] += h, xm[j] -= h;
    const Vec3 d = (1.0 / (2 * h)) * (f.displacement(xp) - f.displacement(xm));
    for (int i = 0; i < 3; ++i) g[i][j] = d[i];
  }
  return g;
}

Voigt hooke(const Material &m, const std::array<Vec3, 3> &g)
{
  const double tr = g[0][0] + g[1][1] + g[2][2], l = m.lambda(), mu = m.mu();
  return {l * tr + 2 * mu * g[0][0], l * tr + 2 * mu * g[1][1], l * tr + 2 * mu * g[2][2], mu * (g[1][2] + g[2][1]), mu * (g[0][2] + g[2][0]), mu * (g[0][1] + g[1][0])};
}

} // namespace

TEST(BodyForce, TheParticularSolutionSatisfiesHookeAndNavier)
{
  for (const double nu : {0.0, 0.3, 0.49}) {
    const Material m = Material::from_young(3000, nu);
    const Vec3 b{0.4, -1.2, -9.81};
    const UniformBodyForce f(m, b, {0.1, 0.2, -0.3});
    const double scale = norm(b) * 2; // |σ| at |r| ~ 2
    for (const Vec3 &x : {Vec3{0.5, -0.7, 1.1}, Vec3{-1.3, 0.2, 0.4}, Vec3{0.1, 0.2, -0.3}}) {
      const Voigt s = f.stress(x), h = hooke(m, gradient(f, x, 1e-3));
      const std::array<Vec3, 3> fd = gradient(f, x, 1e-3);
      const Mat3 g = f.gradient(x); // the exact ∇u_p the surface stress adds
      for (int k = 0; k < 9; ++k) EXPECT_NEAR(g[k], fd[k / 3][k % 3], 1e-9 * scale / m.mu()) << "gradient " << k;
      for (int k = 0; k < 6; ++k) EXPECT_NEAR(s[k], h[k], 1e-9 * scale) << "nu " << nu << " component " << k;
      // div σ + b = 0: σ_p is linear, so a difference of stresses is exact.
      const double e = 0.25;
      Vec3 div{0, 0, 0};
      for (int j = 0; j < 3; ++j) {
        Vec3 xp = x, xm = x;
        xp[j] += e, xm[j] -= e;
        const Voigt sp = f.stress(xp), sm = f.stress(xm);
        const int col[3][3] = {{0, 5, 4}, {5, 1, 3}, {4, 3, 2}}; // Voigt index of σ_ij
        for (int i = 0; i < 3; ++i) div[i] += (sp[col[i][j]] - sm[col[i][j]]) / (2 * e);
      }
      for (int i = 0; i < 3; ++i) EXPECT_NEAR(div[i] + b[i], 0.0, 1e-12 * norm(b));
    }
  }
}

TEST(BodyForce, TheTractionOnAClosedSurfaceCarriesTheWeight)
{
  // The box [0, 1] x [0, 2] x [0, 3] as 12 outward triangles; σ_p is linear, so the midpoint
  // rule integrates σ_p n exactly: ∫ t_p dA = −b V.
  const Vec3 size{1, 2, 3};
  std::vector<Vec3> v;
  for (int k = 0; k < 8; ++k) v.push_back({size[0] * (k & 1), size[1] * ((k >> 1) & 1), size[2] * ((k >> 2) & 1)});
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  const Vec3 b{0, 0, -9.81 * 1.05};
  const UniformBodyForce f(Material::from_young(1e4, 0.45), b, {0.3, 0.8, 1.2});
  Vec3 total{0, 0, 0};
  for (const auto &q : quads)
    for (const std::array<int, 3> t : {std::array<int, 3>{q[0], q[1], q[2]}, std::array<int, 3>{q[0], q[2], q[3]}}) {
      const Vec3 a = v[t[0]], c = v[t[1]], d = v[t[2]];
      const Vec3 area_normal = 0.5 * cross(c - a, d - a), mid = (1.0 / 3) * (a + c + d);
      total = total + norm(area_normal) * f.traction(mid, normalized(area_normal));
    }
  const double volume = size[0] * size[1] * size[2];
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(total[i], -b[i] * volume, 1e-12 * norm(b) * volume);
  EXPECT_GT(std::abs(total[2]), 50.0); // the weight is there: 6 m³ at 10.3 N/m³
}

TEST(BodyForce, BadInputIsRefused)
{
  const Material m = Material::from_young(1, 0.3);
  EXPECT_THROW(UniformBodyForce(m, {0, NAN, 0}, {0, 0, 0}), std::invalid_argument);
  EXPECT_THROW(UniformBodyForce(m, {0, 0, 0}, {INFINITY, 0, 0}), std::invalid_argument);
  EXPECT_TRUE(UniformBodyForce(m, {0, 0, 0}, {0, 0, 0}).zero());
}
