// Fast evaluation of Somigliana's identities at many points (see interior_evaluation.hpp).
#include "interior_evaluation_impl.hpp"

#include "hssbem/compress/compression.hpp"
#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/core/timer.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hssbem {

namespace {

/// Singular values below this fraction of the largest are dropped from the fits: rounding in
/// the fitted field is amplified by at most its inverse.
constexpr double pinv_tol = 1e-9;

detail::SpherePoints sphere_points(int n)
{
  detail::SpherePoints s;
  for (const Vec3 &p : unit_sphere_points(n)) s.x.push_back(p[0]), s.y.push_back(p[1]), s.z.push_back(p[2]);
  return s;
}

/// Moore–Penrose pseudo-inverse (truncated SVD) of the m × n column-major matrix A: n × m.
std::vector<double> pseudo_inverse(std::vector<double> A, int m, int n)
{
  const int k = std::min(m, n);
  std::vector<double> s(k), U(static_cast<std::size_t>(m) * k), Vt(static_cast<std::size_t>(k) * n);
  if (lapack::gesvd(m, n, A.data(), m, s.data(), U.data(), m, Vt.data(), k) != 0) throw std::runtime_error("interior evaluation: SVD of a fit failed");
  int kept = 0;
  while (kept < k && s[kept] > pinv_tol * s[0]) ++kept;
  for (int l = 0; l < kept; ++l) // U diag(1/s)
    for (int j = 0; j < m; ++j) U[static_cast<std::size_t>(l) * m + j] /= s[l];
  std::vector<double> P(static_cast<std::size_t>(n) * m, 0.0); // V diag(1/s) Uᵀ
  lapack::gemm('T', 'T', n, m, kept, 1.0, Vt.data(), k, U.data(), m, 0.0, P.data(), n);
  return P;
}

std::vector<Vec3> triangle_centroids(const SomiglianaSources &src)
{
  std::vector<Vec3> c(src.num_triangles());
  for (int e = 0; e < src.num_triangles(); ++e) c[e] = src.centroid(e);
  return c;
}

int check_points(const InteriorEvaluationOptions &o) { return std::max(o.equivalent_points, static_cast<int>(std::lround(o.check_factor * o.equivalent_points))); }

ClusterTreeOptions leaves_of(int n)
{
  ClusterTreeOptions o;
  o.leaf_size = std::max(1, n);
  return o;
}

/// Radii that nest: a parent's ball holds its children's.
void nest_radii(const ClusterTree &tree, std::vector<double> &R)
{
  for (int l = tree.levels() - 1; l >= 0; --l)
    for (int c : tree.clusters_at_level(l)) {
      const Cluster &cl = tree.cluster(c);
      if (cl.left < 0) continue;
      for (int child : {cl.left, cl.right}) R[c] = std::max(R[c], norm(tree.cluster(child).centre - cl.centre) + R[child]);
    }
}

} // namespace

namespace detail {

void add_forces_at(const SomiglianaConstants &k, const Vec3 &x, const Vec3 &centre, double r, const SpherePoints &s, const double *q, double *u)
{
  const int n = s.size();
  double u0 = 0, u1 = 0, u2 = 0;
  const double ox = centre[0] - x[0], oy = centre[1] - x[1], oz = centre[2] - x[2];
  const double *SX = s.x.data(), *SY = s.y.data(), *SZ = s.z.data(), *Q0 = q, *Q1 = q + n, *Q2 = q + 2 * n;
#pragma omp simd reduction(+ : u0, u1, u2)
  for (int j = 0; j < n; ++j) {
    double v0, v1, v2;
    kelvin_displacement_point(k, ox + r * SX[j], oy + r * SY[j], oz + r * SZ[j], Q0[j], Q1[j], Q2[j], v0, v1, v2);
    u0 += v0, u1 += v1, u2 += v2;
  }
  u[0] += u0, u[1] += u1, u[2] += u2;
}

Fit::Fit(const SomiglianaConstants &k, int pe, int pc_, double r_equiv_, double r_check_) : equiv(sphere_points(pe)), check(sphere_points(pc_)), r_equiv(r_equiv_), r_check(r_check_)
{
  const int pc = check.size(), m = 3 * pc, n = 3 * pe;
  std::vector<double> A(static_cast<std::size_t>(m) * n, 0.0);
  for (int j = 0; j < pe; ++j)
    for (int b = 0; b < 3; ++b) {
      double *col = &A[static_cast<std::size_t>(b * pe + j) * m];
      for (int i = 0; i < pc; ++i) {
        const double d0 = r_equiv * equiv.x[j] - r_check * check.x[i], d1 = r_equiv * equiv.y[j] - r_check * check.y[i], d2 = r_equiv * equiv.z[j] - r_check * check.z[i];
        kelvin_displacement_point(k, d0, d1, d2, b == 0, b == 1, b == 2, col[i], col[pc + i], col[2 * pc + i]);
      }
    }
  pinv = pseudo_inverse(std::move(A), m, n);
}

void Fit::solve(double R, const std::vector<double> &field, std::vector<double> &forces) const
{
  forces.assign(3 * pe(), 0.0);
  lapack::gemv('N', 3 * pe(), 3 * pc(), R, pinv.data(), 3 * pe(), field.data(), 0.0, forces.data());
}

void OrderedParticles::add_regular(const SomiglianaConstants &k, const Vec3 &x, std::size_t begin, std::size_t end, double *out) const
{
  double a0 = 0, a1 = 0, a2 = 0, a3 = 0, a4 = 0, a5 = 0, a6 = 0, a7 = 0, a8 = 0;
  const double x0 = x[0], x1 = x[1], x2 = x[2];
  // Raw pointers: the loop below must see plain arrays to vectorise with contiguous loads.
  const double *Y0 = y[0].data(), *Y1 = y[1].data(), *Y2 = y[2].data(), *F0 = f[0].data(), *F1 = f[1].data(), *F2 = f[2].data();
  const double *M0 = m[0].data(), *M1 = m[1].data(), *M2 = m[2].data(), *N0 = n[0].data(), *N1 = n[1].data(), *N2 = n[2].data();
  const double *C0 = c[0].data(), *C1 = c[1].data(), *C2 = c[2].data(), *R2 = r2.data();
#pragma omp simd reduction(+ : a0, a1, a2, a3, a4, a5, a6, a7, a8)
  for (std::size_t j = begin; j < end; ++j) {
    const double c0 = C0[j] - x0, c1 = C1[j] - x1, c2 = C2[j] - x2;
    const double w = c0 * c0 + c1 * c1 + c2 * c2 >= R2[j] ? 1.0 : 0.0; // a triangle near x is split elsewhere
    double v0, v1, v2, v3, v4, v5, v6, v7, v8;
    somigliana_point(k, Y0[j] - x0, Y1[j] - x1, Y2[j] - x2, w * F0[j], w * F1[j], w * F2[j], w * M0[j], w * M1[j], w * M2[j], N0[j], N1[j], N2[j], v0, v1, v2, v3,
                     v4, v5, v6, v7, v8);
    a0 += v0, a1 += v1, a2 += v2, a3 += v3, a4 += v4, a5 += v5, a6 += v6, a7 += v7, a8 += v8;
  }
  out[0] += a0, out[1] += a1, out[2] += a2, out[3] += a3, out[4] += a4, out[5] += a5, out[6] += a6, out[7] += a7, out[8] += a8;
}

} // namespace detail

using detail::add_forces_at;

InteriorEvaluator::Impl::Impl(const SomiglianaSources &s, const InteriorEvaluationOptions &o)
  : src(s), opt(o), up(s.constants(), o.equivalent_points, check_points(o), o.equivalent_ratio, o.check_ratio),
    down(s.constants(), o.equivalent_points, check_points(o), o.check_ratio, o.equivalent_ratio),
    tree(triangle_centroids(s), leaves_of(o.source_leaf))
{
}

void InteriorEvaluator::Impl::order_particles()
{
  const Particles &P = src.particles();
  const std::size_t n = P.size();
  detail::OrderedParticles &o = particles;
  for (int a = 0; a < 3; ++a)
    for (auto *v : {&o.y[a], &o.f[a], &o.m[a], &o.n[a], &o.c[a]}) v->resize(n);
  o.r2.resize(n);
  std::size_t at = 0;
  for (int e : tree.perm())
    for (std::size_t i = Particles::per_triangle * static_cast<std::size_t>(e), end = i + Particles::per_triangle; i < end; ++i, ++at) {
      for (int a = 0; a < 3; ++a) {
        o.y[a][at] = P.y[a][i], o.f[a][at] = P.f[a][i], o.m[a][at] = P.m[a][i], o.n[a][at] = P.n[a][i];
        o.c[a][at] = src.centroid(e)[a];
      }
      o.r2[at] = src.near_radius(e) * src.near_radius(e);
    }
}

void InteriorEvaluator::Impl::add_equivalent(const Vec3 &x, int b, double *out) const
{
  const std::vector<double> &f = q[b];
  const detail::SpherePoints &s = up.equiv;
  const int n = s.size();
  const Vec3 &c = tree.cluster(b).centre;
  const double r = R[b] * up.r_equiv, ox = c[0] - x[0], oy = c[1] - x[1], oz = c[2] - x[2];
  const SomiglianaConstants &k = src.constants();
  const double *SX = s.x.data(), *SY = s.y.data(), *SZ = s.z.data(), *Q0 = f.data(), *Q1 = f.data() + n, *Q2 = f.data() + 2 * n;
  double a0 = 0, a1 = 0, a2 = 0, a3 = 0, a4 = 0, a5 = 0, a6 = 0, a7 = 0, a8 = 0;
#pragma omp simd reduction(+ : a0, a1, a2, a3, a4, a5, a6, a7, a8)
  for (int j = 0; j < n; ++j) {
    double w0, w1, w2, w3, w4, w5, w6, w7, w8;
    kelvin_force_point(k, ox + r * SX[j], oy + r * SY[j], oz + r * SZ[j], Q0[j], Q1[j], Q2[j], w0, w1, w2, w3, w4, w5, w6, w7, w8);
    a0 += w0, a1 += w1, a2 += w2, a3 += w3, a4 += w4, a5 += w5, a6 += w6, a7 += w7, a8 += w8;
  }
  out[0] += a0, out[1] += a1, out[2] += a2, out[3] += a3, out[4] += a4, out[5] += a5, out[6] += a6, out[7] += a7, out[8] += a8;
}

void InteriorEvaluator::Impl::add_leaf(const Vec3 &x, int b, double *out, InteriorEvaluationStats &s) const
{
  const Cluster &cl = tree.cluster(b);
  const double D = norm(x - cl.centre);
  if (D >= opt.check_ratio * R[b] && D >= reach[b] && cl.size() * Particles::per_triangle > up.pe()) {
    s.kernel_far += up.pe();
    return add_equivalent(x, b, out);
  }
  particles.add_regular(src.constants(), x, Particles::per_triangle * static_cast<std::size_t>(cl.begin), Particles::per_triangle * static_cast<std::size_t>(cl.end), out);
  s.kernel_near += Particles::per_triangle * cl.size();
  for (int p = cl.begin; p < cl.end; ++p) {
    const int e = tree.perm()[p];
    if (!src.is_regular(x, e)) src.add_triangle(x, e, out), ++s.adaptive_triangles;
  }
}

void InteriorEvaluator::Impl::source_radii()
{
  R.assign(tree.num_clusters(), 0.0);
  reach.assign(tree.num_clusters(), 0.0);
  for (int c = 0; c < tree.num_clusters(); ++c) {
    const Cluster &cl = tree.cluster(c);
    for (int p = cl.begin; p < cl.end; ++p) {
      const int e = tree.perm()[p];
      const double d = norm(src.centroid(e) - cl.centre);
      R[c] = std::max(R[c], d + src.radius(e));
      reach[c] = std::max(reach[c], d + src.near_radius(e));
    }
  }
  nest_radii(tree, R);
}

void InteriorEvaluator::Impl::upward_leaf(int c)
{
  const Cluster &cl = tree.cluster(c);
  const detail::OrderedParticles &o = particles;
  const SomiglianaConstants &k = src.constants();
  const std::size_t begin = Particles::per_triangle * static_cast<std::size_t>(cl.begin), end = Particles::per_triangle * static_cast<std::size_t>(cl.end);
  const int pc = up.pc();
  std::vector<double> field(3 * pc, 0.0);
  const double *Y0 = o.y[0].data(), *Y1 = o.y[1].data(), *Y2 = o.y[2].data(), *F0 = o.f[0].data(), *F1 = o.f[1].data(), *F2 = o.f[2].data();
  const double *M0 = o.m[0].data(), *M1 = o.m[1].data(), *M2 = o.m[2].data(), *N0 = o.n[0].data(), *N1 = o.n[1].data(), *N2 = o.n[2].data();
  for (int i = 0; i < pc; ++i) {
    const Vec3 x = up.check_point(cl.centre, R[c], i);
    const double x0 = x[0], x1 = x[1], x2 = x[2];
    double u0 = 0, u1 = 0, u2 = 0;
#pragma omp simd reduction(+ : u0, u1, u2)
    for (std::size_t j = begin; j < end; ++j) {
      double v0, v1, v2;
      somigliana_displacement_point(k, Y0[j] - x0, Y1[j] - x1, Y2[j] - x2, F0[j], F1[j], F2[j], M0[j], M1[j], M2[j], N0[j], N1[j], N2[j], v0, v1, v2);
      u0 += v0, u1 += v1, u2 += v2;
    }
    field[i] = u0, field[pc + i] = u1, field[2 * pc + i] = u2;
  }
  up.solve(R[c], field, q[c]);
}

void InteriorEvaluator::Impl::upward_inner(int c)
{
  const Cluster &cl = tree.cluster(c);
  const int pc = up.pc();
  std::vector<double> field(3 * pc, 0.0);
  for (int child : {cl.left, cl.right})
    for (int i = 0; i < pc; ++i) {
      double u[3] = {0, 0, 0};
      add_forces_at(src.constants(), up.check_point(cl.centre, R[c], i), tree.cluster(child).centre, R[child] * up.r_equiv, up.equiv, q[child].data(), u);
      field[i] += u[0], field[pc + i] += u[1], field[2 * pc + i] += u[2];
    }
  up.solve(R[c], field, q[c]);
}

void InteriorEvaluator::Impl::upward()
{
  const SerialBlas serial; // the fits' products run inside the loops over clusters
  source_radii();
  q.assign(tree.num_clusters(), {});
  for (int l = tree.levels() - 1; l >= 0; --l) {
    const std::vector<int> &level = tree.clusters_at_level(l);
#pragma omp parallel for schedule(dynamic)
    for (std::size_t i = 0; i < level.size(); ++i) {
      const int c = level[i];
      if (tree.is_leaf(c)) upward_leaf(c);
      else upward_inner(c);
    }
  }
}

bool InteriorEvaluator::Impl::far(const Vec3 &ca, double Ra, int b) const
{
  const double D = norm(ca - tree.cluster(b).centre), ri = opt.equivalent_ratio, ro = opt.check_ratio;
  return D >= ro * R[b] + ri * Ra && D >= ro * Ra + ri * R[b] && D >= reach[b] + ri * Ra;
}

InteriorEvaluator::InteriorEvaluator(const SomiglianaSources &src, const InteriorEvaluationOptions &options) : m_impl(std::make_unique<Impl>(src, options))
{
  if (options.equivalent_points < 4 || !(options.equivalent_ratio >= 1) || !(options.check_ratio > options.equivalent_ratio) || options.source_leaf < 1 ||
      options.target_leaf < 1)
    throw std::invalid_argument("interior evaluation: need at least 4 equivalent points, 1 <= equivalent ratio < check ratio and leaves of at least one");
  const Timer timer;
  if (!options.direct) {
    m_impl->order_particles();
    m_impl->upward();
  }
  m_upward_seconds = timer.seconds();
}

InteriorEvaluator::~InteriorEvaluator() = default;

} // namespace hssbem
