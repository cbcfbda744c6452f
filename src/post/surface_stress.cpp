// The stress tensor at the dof nodes from the traction and the tangential gradient of the
// displacement (see surface_stress.hpp).
#include "hssbem/post/surface_stress.hpp"

#include "hssbem/core/lapack.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hssbem {

namespace {

constexpr double nan_value = std::numeric_limits<double>::quiet_NaN();

/// A unit vector orthogonal to n, and the third of the right-handed frame (e1, e2, n).
void tangent_frame(const Vec3 &n, Vec3 &e1, Vec3 &e2)
{
  const Vec3 a = std::abs(n[0]) < 0.6 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  e1 = normalized(a - dot(a, n) * n);
  e2 = cross(n, e1);
}

/// One neighbour of a node: its position in the tangent frame and its displacement minus the node's.
struct Sample {
  double xi, eta, w; ///< offset along e1, e2 and the normal
  Vec3 du;
};

/// Rings of neighbours a smooth node's fit reaches over, and the polynomial's degree there.
constexpr int k_fit_rings = 3, k_fit_degree = 4;

/// The nodes within `rings` edges of node i over its triangles, i excluded, each once (mark: a
/// per-node workspace of num_nodes() entries and a stamp; a call takes a new stamp).
std::vector<int> patch_nodes(const Discretization &disc, int i, int rings, std::vector<int> &mark)
{
  const int stamp = ++mark.back(); // the workspace's last entry counts the calls
  std::vector<int> out;
  mark[i] = stamp;
  std::vector<int> front{i};
  for (int r = 0; r < rings; ++r) {
    const std::size_t size = out.size();
    for (int j : front)
      for (const int *t = disc.support_begin(j); t != disc.support_end(j); ++t)
        for (int c = 0; c < 3; ++c) {
          const int k = disc.element_node(*t, c);
          if (mark[k] != stamp) mark[k] = stamp, out.push_back(k);
        }
    front.assign(out.begin() + static_cast<std::ptrdiff_t>(size), out.end());
  }
  return out;
}

/// The samples of node i's fit in its tangent frame, and the fit's degree: for a smooth node
/// whose k_fit_rings rings are all smooth (the patch crosses no sharp edge), those rings and
/// degree k_fit_degree; else the corners of its own triangles, quadratic for a smooth node and
/// linear for one of a sharp vertex's nodes (its fan is open).
std::vector<Sample> fit_samples(const Discretization &disc, int i, const std::vector<Vec3> &u, const Vec3 &e1, const Vec3 &e2, const Vec3 &n, std::vector<int> &mark, int &degree)
{
  const auto smooth = [&](int k) { return disc.node_count(disc.node(k).vertex) == 1; };
  std::vector<int> nodes;
  degree = smooth(i) ? 2 : 1;
  if (smooth(i)) {
    nodes = patch_nodes(disc, i, k_fit_rings, mark);
    if (std::all_of(nodes.begin(), nodes.end(), smooth)) degree = k_fit_degree;
    else nodes.clear();
  }
  if (nodes.empty()) nodes = patch_nodes(disc, i, 1, mark);
  std::vector<Sample> out;
  const Vec3 &x0 = disc.node_position(i);
  for (int j : nodes) {
    const Vec3 d = disc.node_position(j) - x0;
    out.push_back({dot(d, e1), dot(d, e2), dot(d, n), u[j] - u[i]});
  }
  return out;
}

/// The tangential derivatives' weights of a least-squares fit: ∂f/∂e1 ≈ Σ_r g1[r] f_r, ∂f/∂e2
/// ≈ Σ_r g2[r] f_r over the samples' values f_r (changes from the node's value).
struct TangentFit {
  std::vector<double> g1, g2;
};

/// Rows 0 and 1 of the pseudo-inverse of A (m × k, column-major, m ≥ k; overwritten) into p0,
/// p1: A = QR by Householder reflections, then row i = (Q R⁻ᵀ e_i)ᵀ, the reflections applied to
/// one vector each (4 k m flops, not the k m² of solving for every column of the identity).
/// False when A is numerically rank deficient (its columns are scaled to about unit size).
bool pinv_rows(std::vector<double> &A, int m, int k, std::vector<double> &p0, std::vector<double> &p1)
{
  std::vector<double> vn(k), diag(k);
  for (int j = 0; j < k; ++j) {
    double *a = &A[static_cast<std::size_t>(j) * m];
    double s = 0;
    for (int i = j; i < m; ++i) s += a[i] * a[i];
    const double alpha = a[j] > 0 ? -std::sqrt(s) : std::sqrt(s);
    if (std::abs(alpha) < 1e-10) return false;
    a[j] -= alpha; // the reflector v = a(j:m) − α e_j stays in place below R's strict upper part
    for (int i = j; i < m; ++i) vn[j] += a[i] * a[i];
    diag[j] = alpha;
    for (int c = j + 1; c < k; ++c) {
      double *col = &A[static_cast<std::size_t>(c) * m];
      double d = 0;
      for (int i = j; i < m; ++i) d += a[i] * col[i];
      d *= 2.0 / vn[j];
      for (int i = j; i < m; ++i) col[i] -= d * a[i];
    }
  }
  for (int row = 0; row < 2; ++row) {
    std::vector<double> y(m, 0.0); // w = R⁻ᵀ e_row by forward substitution, then Q [w; 0]
    for (int j = 0; j < k; ++j) {
      double t = j == row ? 1.0 : 0.0;
      for (int l = 0; l < j; ++l) t -= A[static_cast<std::size_t>(j) * m + l] * y[l];
      y[j] = t / diag[j];
    }
    for (int j = k - 1; j >= 0; --j) {
      const double *v = &A[static_cast<std::size_t>(j) * m];
      double d = 0;
      for (int i = j; i < m; ++i) d += v[i] * y[i];
      d *= 2.0 / vn[j];
      for (int i = j; i < m; ++i) y[i] -= d * v[i];
    }
    (row == 0 ? p0 : p1) = std::move(y);
  }
  return true;
}

/// The fit of the samples by a polynomial of the given degree (≤ 4) in the tangent frame, where
/// the samples are enough for it (6, 14 and 22 for degrees 2 to 4: about 1.5 per term) and the
/// fit is well posed, else of lower degree down to linear: the first two rows of the
/// pseudo-inverse. False when even the linear fit is not.
bool tangent_fit(const std::vector<Sample> &s, int degree, TangentFit &fit)
{
  const int m = static_cast<int>(s.size());
  double h = 0;
  for (const Sample &p : s) h += std::sqrt(p.xi * p.xi + p.eta * p.eta);
  if (m < 2 || !(h > 0)) return false;
  h /= m; // scale: columns of about unit size
  constexpr int terms[5] = {0, 2, 5, 9, 14}, least[5] = {0, 2, 6, 14, 22}; // monomials of degree 1 .. d in two variables
  for (int d = std::min(degree, 4); d >= 1; --d) {
    const int k = terms[d];
    if (m < least[d]) continue;
    std::vector<double> A(static_cast<std::size_t>(m) * k);
    for (int r = 0; r < m; ++r) {
      const double a = s[r].xi / h, b = s[r].eta / h;
      const double col[14] = {a, b, a * a, a * b, b * b, a * a * a, a * a * b, a * b * b, b * b * b, a * a * a * a, a * a * a * b, a * a * b * b, a * b * b * b, b * b * b * b};
      for (int c = 0; c < k; ++c) A[static_cast<std::size_t>(c) * m + r] = col[c];
    }
    if (!pinv_rows(A, m, k, fit.g1, fit.g2)) continue;
    for (int r = 0; r < m; ++r) fit.g1[r] /= h, fit.g2[r] /= h;
    return true;
  }
  return false;
}

/// ∂u/∂e1 and ∂u/∂e2 at the node from the fit of its samples, each sample's change of u less
/// w · dun (its normal offset times ∂u/∂n).
void fit_gradient(const std::vector<Sample> &s, const TangentFit &fit, const Vec3 &dun, Vec3 &du1, Vec3 &du2)
{
  du1 = du2 = Vec3{0, 0, 0};
  for (std::size_t r = 0; r < s.size(); ++r) {
    const Vec3 f = s[r].du - s[r].w * dun;
    du1 = du1 + fit.g1[r] * f;
    du2 = du2 + fit.g2[r] * f;
  }
}

/// σ and the displacement gradient from the traction t on the plane of normal n and the
/// tangential derivatives du1 = ∂u/∂e1, du2 = ∂u/∂e2.
NodeStress stress_from_surface(const Material &mat, const Vec3 &n, const Vec3 &e1, const Vec3 &e2, const Vec3 &t, const Vec3 &du1, const Vec3 &du2)
{
  const double lambda = mat.lambda(), mu = mat.mu();
  const Vec3 frame[3] = {e1, e2, n};
  double s[3][3];
  const double e11 = dot(du1, e1), e22 = dot(du2, e2), e12 = 0.5 * (dot(du1, e2) + dot(du2, e1));
  for (int k = 0; k < 3; ++k) s[2][k] = s[k][2] = dot(t, frame[k]);
  const double e33 = (s[2][2] - lambda * (e11 + e22)) / (lambda + 2 * mu), tr = e11 + e22 + e33;
  s[0][0] = lambda * tr + 2 * mu * e11;
  s[1][1] = lambda * tr + 2 * mu * e22;
  s[0][1] = s[1][0] = 2 * mu * e12;
  // ∂u/∂n from σ_13 = μ (∂u_1/∂n + ∂u_n/∂e1), likewise for e2, and ε_33.
  const Vec3 dun = (s[0][2] / mu - dot(du1, n)) * e1 + (s[1][2] / mu - dot(du2, n)) * e2 + e33 * n;
  const Vec3 dloc[3] = {du1, du2, dun};
  NodeStress out;
  for (int v = 0; v < 6; ++v) {
    const int i = voigt_row[v], j = voigt_col[v];
    double sum = 0;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) sum += frame[a][i] * s[a][b] * frame[b][j];
    out.stress[v] = sum;
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int a = 0; a < 3; ++a) out.gradient[3 * i + j] += dloc[a][i] * frame[a][j];
  return out;
}

} // namespace

std::array<double, 3> principal_stresses(const Voigt &s)
{
  double a[9] = {s[0], s[5], s[4], s[5], s[1], s[3], s[4], s[3], s[2]}, w[3];
  if (!std::isfinite(s[0] + s[1] + s[2] + s[3] + s[4] + s[5]) || lapack::syev(3, a, w) != 0) return {nan_value, nan_value, nan_value};
  return {w[2], w[1], w[0]};
}

Voigt hooke_stress(const Material &m, const Mat3 &G)
{
  const double tr = G[0] + G[4] + G[8];
  Voigt s;
  for (int v = 0; v < 6; ++v) {
    const int i = voigt_row[v], j = voigt_col[v];
    s[v] = m.mu() * (G[3 * i + j] + G[3 * j + i]) + (i == j ? m.lambda() * tr : 0.0);
  }
  return s;
}

namespace {

/// The stress at dof node i (mark: patch_nodes' workspace).
NodeStress node_stress(const Discretization &disc, const Material &material, const std::vector<Vec3> &u, const std::vector<Vec3> &t, int i, std::vector<int> &mark)
{
  const Vec3 &n = disc.node(i).normal;
  Vec3 e1, e2, du1{}, du2{}, dun{};
  tangent_frame(n, e1, e2);
  int degree = 1;
  const std::vector<Sample> samples = fit_samples(disc, i, u, e1, e2, n, mark, degree);
  NodeStress out;
  TangentFit fit;
  if (!tangent_fit(samples, degree, fit)) {
    out.stress.fill(nan_value);
    out.gradient.fill(nan_value);
    return out;
  }
  // The neighbours of a curved surface lie off the tangent plane by w = O(h²): their change of
  // u holds w ∂u/∂n, which the traction gives once the tangential gradient is known: a fixed
  // point that gains a factor ~h/R a round and makes a linear field exact on any surface.
  for (int round = 0; round < 10; ++round) {
    const Vec3 previous = dun;
    fit_gradient(samples, fit, dun, du1, du2);
    out = stress_from_surface(material, n, e1, e2, t[i], du1, du2);
    const Mat3 &G = out.gradient;
    for (int r = 0; r < 3; ++r) dun[r] = G[3 * r] * n[0] + G[3 * r + 1] * n[1] + G[3 * r + 2] * n[2];
    if (norm(dun - previous) <= 1e-14 * (norm(dun) + norm(du1) + norm(du2))) break;
  }
  return out;
}

} // namespace

std::vector<NodeStress> node_stresses(const Discretization &disc, const Material &material, const std::vector<Vec3> &u, const std::vector<Vec3> &t)
{
  std::vector<NodeStress> out(disc.num_nodes());
#pragma omp parallel
  {
    std::vector<int> mark(disc.num_nodes() + 1, 0); // patch_nodes' workspace and stamp, per thread
#pragma omp for schedule(dynamic, 64)
    for (int i = 0; i < disc.num_nodes(); ++i) out[i] = node_stress(disc, material, u, t, i, mark);
  }
  return out;
}

std::vector<NodeStress> with_particular(std::vector<NodeStress> nodes, const Discretization &disc, const UniformBodyForce &force)
{
  if (force.zero()) return nodes;
  for (int i = 0; i < disc.num_nodes(); ++i) {
    const Vec3 &x = disc.node_position(i);
    const Voigt s = force.stress(x);
    const Mat3 g = force.gradient(x);
    for (int k = 0; k < 6; ++k) nodes[i].stress[k] += s[k];
    for (int k = 0; k < 9; ++k) nodes[i].gradient[k] += g[k];
  }
  return nodes;
}

std::vector<Voigt> vertex_stress(const Discretization &disc, const std::vector<NodeStress> &nodes)
{
  Voigt none;
  none.fill(nan_value);
  std::vector<Voigt> out(disc.mesh().vertices.size(), none);
  for (int v = 0; v < disc.mesh().num_vertices(); ++v) {
    const int k = disc.node_count(v);
    if (k == 0) continue;
    Voigt sum{};
    for (int i = disc.first_node(v); i < disc.first_node(v) + k; ++i)
      for (int c = 0; c < 6; ++c) sum[c] += nodes[i].stress[c] / k;
    out[v] = sum;
  }
  return out;
}

std::vector<std::array<Voigt, 3>> corner_stress(const Discretization &disc, const std::vector<NodeStress> &nodes)
{
  std::vector<std::array<Voigt, 3>> out(disc.mesh().triangles.size());
  for (std::size_t t = 0; t < out.size(); ++t)
    for (int c = 0; c < 3; ++c) out[t][c] = nodes[disc.element_node(static_cast<int>(t), c)].stress;
  return out;
}

std::vector<double> von_mises_of(const std::vector<Voigt> &stress)
{
  std::vector<double> out(stress.size());
  for (std::size_t i = 0; i < stress.size(); ++i) out[i] = von_mises(stress[i]);
  return out;
}

std::vector<Vec3> principal_of(const std::vector<Voigt> &stress)
{
  std::vector<Vec3> out(stress.size());
  for (std::size_t i = 0; i < stress.size(); ++i) {
    const auto p = principal_stresses(stress[i]);
    out[i] = {p[0], p[1], p[2]};
  }
  return out;
}

} // namespace hssbem
