#include "hssbem/bem/rigid_modes.hpp"
#include "hssbem/bem/discretization.hpp"
#include "hssbem/core/lapack.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace hssbem {

namespace {

struct Frame {
  Vec3 centre{};
  double size = 1; ///< body radius, so rotations and translations are measured alike
};

Frame frame_of(const Discretization &disc)
{
  Frame f;
  for (int i = 0; i < disc.num_nodes(); ++i) f.centre = f.centre + disc.node_position(i);
  f.centre = (1.0 / std::max(1, disc.num_nodes())) * f.centre;
  double r = 0;
  for (int i = 0; i < disc.num_nodes(); ++i) r = std::max(r, norm(disc.node_position(i) - f.centre));
  f.size = r > 0 ? r : 1;
  return f;
}

/// Component c of rigid mode m at x: translations e_m, rotations e_(m-3) × (x - centre) / size.
double mode(const Frame &f, int m, const Vec3 &x, int c)
{
  if (m < 3) return m == c ? 1.0 : 0.0;
  Vec3 axis{};
  axis[m - 3] = 1;
  return cross(axis, (1.0 / f.size) * (x - f.centre))[c];
}

std::string describe(const double *v)
{
  static const char *names[6] = {"translation x", "translation y", "translation z", "rotation about x", "rotation about y", "rotation about z"};
  std::string s;
  for (int m = 0; m < 6; ++m)
    if (std::abs(v[m]) > 0.3) s += (s.empty() ? "" : " + ") + std::string(names[m]);
  return s;
}

} // namespace

ConstraintReport analyse_constraints(const Discretization &disc, const std::vector<std::array<bool, 3>> &known)
{
  std::vector<NodeConstraint> constraints;
  for (int i = 0; i < disc.num_nodes(); ++i)
    for (int c = 0; c < 3; ++c)
      if (known[i][c]) {
        Vec3 axis{};
        axis[c] = 1;
        constraints.push_back({i, axis});
      }
  return analyse_constraints(disc, constraints);
}

ConstraintReport analyse_constraints(const Discretization &disc, const std::vector<NodeConstraint> &constraints)
{
  const Frame f = frame_of(disc);
  double gram[36] = {0}, w[6];
  for (const NodeConstraint &k : constraints) {
    double row[6] = {0};
    for (int m = 0; m < 6; ++m)
      for (int c = 0; c < 3; ++c) row[m] += k.direction[c] * mode(f, m, disc.node_position(k.node), c);
    for (int a = 0; a < 6; ++a)
      for (int b = 0; b < 6; ++b) gram[6 * a + b] += row[a] * row[b];
  }
  lapack::syev(6, gram, w);
  ConstraintReport rep;
  const double top = std::max(w[5], 1e-300);
  for (int m = 0; m < 6; ++m) {
    if (w[m] > 1e-10 * top && w[5] > 0) ++rep.rank;
    else rep.free_modes.push_back(describe(gram + 6 * m));
  }
  return rep;
}

std::vector<double> orthonormal_rigid_modes(const Discretization &disc)
{
  const Frame f = frame_of(disc);
  const int n = 3 * disc.num_nodes();
  std::vector<double> Q(static_cast<std::size_t>(n) * 6);
  for (int i = 0; i < disc.num_nodes(); ++i)
    for (int c = 0; c < 3; ++c)
      for (int m = 0; m < 6; ++m) Q[(3 * static_cast<std::size_t>(i) + c) * 6 + m] = mode(f, m, disc.node_position(i), c);
  // Modified Gram-Schmidt, twice for safety: six columns, any size.
  for (int pass = 0; pass < 2; ++pass)
    for (int m = 0; m < 6; ++m) {
      for (int k = 0; k < m; ++k) {
        double d = 0;
        for (int r = 0; r < n; ++r) d += Q[r * 6 + m] * Q[r * 6 + k];
        for (int r = 0; r < n; ++r) Q[r * 6 + m] -= d * Q[r * 6 + k];
      }
      double s = 0;
      for (int r = 0; r < n; ++r) s += Q[r * 6 + m] * Q[r * 6 + m];
      s = 1.0 / std::sqrt(s);
      for (int r = 0; r < n; ++r) Q[r * 6 + m] *= s;
    }
  return Q;
}

std::array<double, 6> remove_rigid_motion(const Discretization &disc, std::vector<Vec3> &u)
{
  const Frame f = frame_of(disc);
  double normal[36] = {0}, rhs[6] = {0};
  for (int i = 0; i < disc.num_nodes(); ++i)
    for (int c = 0; c < 3; ++c) {
      double row[6];
      for (int m = 0; m < 6; ++m) row[m] = mode(f, m, disc.node_position(i), c);
      for (int a = 0; a < 6; ++a) {
        rhs[a] += row[a] * u[i][c];
        for (int b = 0; b < 6; ++b) normal[6 * a + b] += row[a] * row[b];
      }
    }
  lapack::gesv(6, 1, normal, rhs);
  for (int i = 0; i < disc.num_nodes(); ++i)
    for (int c = 0; c < 3; ++c)
      for (int m = 0; m < 6; ++m) u[i][c] -= rhs[m] * mode(f, m, disc.node_position(i), c);
  return {rhs[0], rhs[1], rhs[2], rhs[3] / f.size, rhs[4] / f.size, rhs[5] / f.size};
}

std::array<double, 2> load_imbalance(const Discretization &disc, const std::vector<Vec3> &t)
{
  const std::vector<double> area = node_areas(disc);
  const Vec3 centre = frame_of(disc).centre;
  Vec3 F{}, M{};
  double fscale = 0, mscale = 0;
  for (int i = 0; i < disc.num_nodes(); ++i) {
    const Vec3 arm = disc.node_position(i) - centre, f = area[i] * t[i];
    F = F + f;
    M = M + cross(arm, f);
    fscale += norm(f);
    mscale += norm(arm) * norm(f);
  }
  return {fscale > 0 ? norm(F) / fscale : 0.0, mscale > 0 ? norm(M) / mscale : 0.0};
}

} // namespace hssbem
