// Fast evaluation of Somigliana's identities at many points (see interior_evaluation.hpp).
#include "interior_evaluation_impl.hpp"

#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/core/timer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <tuple>
#include <utility>

namespace hssbem {

namespace {

/// What a particle's kernel (single and double layer, somigliana_point) costs against a point
/// force's (kelvin_force_point): about twice, by the profile of the 13k sphere's 10⁶ points
/// (40 % of the time for 2 157 particles per point, 10.8 % for 1 168 forces). A leaf takes inner
/// forces when they cost less than its particles.
constexpr int particle_cost = 2;

/// Singular values below this fraction of the largest are dropped from the fits: rounding in
/// the fitted field is amplified by at most its inverse.
constexpr double pinv_tol = 1e-9;

/// Steps of the search for a source cluster's centre (source_centres): the radii stop shrinking
/// by about 48 (sphere_13k: 200 or 1000 steps change the near particles per point by 0.5 %).
constexpr int centre_steps = 48;

detail::SpherePoints sphere_points(int n)
{
  detail::SpherePoints s;
  for (const Vec3 &p : unit_sphere_points(n)) s.x.push_back(p[0]), s.y.push_back(p[1]), s.z.push_back(p[2]);
  s.fx.assign(s.x.begin(), s.x.end()), s.fy.assign(s.y.begin(), s.y.end()), s.fz.assign(s.z.begin(), s.z.end());
  return s;
}

/// Moore–Penrose pseudo-inverse (truncated SVD) of the m × n column-major matrix A: n × m.
std::vector<double> pseudo_inverse(std::vector<double> A, int m, int n)
{
  const int k = std::min(m, n);
  std::vector<double> s(k), U(static_cast<std::size_t>(m) * k), Vt(static_cast<std::size_t>(k) * n);
  if (lapack::gesdd(m, n, A.data(), m, s.data(), U.data(), m, Vt.data(), k) != 0) throw std::runtime_error("interior evaluation: SVD of a fit failed");
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

/// Check points of a fit with `equivalent` equivalent points: check_factor times as many, at least as many.
int check_points(const InteriorEvaluationOptions &o, int equivalent) { return std::max(equivalent, static_cast<int>(std::lround(o.check_factor * equivalent))); }

ClusterTreeOptions leaves_of(int n)
{
  ClusterTreeOptions o;
  o.leaf_size = std::max(1, n);
  return o;
}

/// Radii as small as the upward pass allows: a cluster's ball holds its triangles, and its check
/// sphere (check_ratio · R) lies outside its children's, where their forces are fitted:
/// R ≥ R_child + |centre − centre_child| / check_ratio.
void nest_radii(const ClusterTree &tree, const std::vector<Vec3> &C, double check_ratio, std::vector<double> &R)
{
  for (int l = tree.levels() - 1; l >= 0; --l)
    for (int c : tree.clusters_at_level(l)) {
      const Cluster &cl = tree.cluster(c);
      if (cl.left < 0) continue;
      for (int child : {cl.left, cl.right}) R[c] = std::max(R[c], norm(C[child] - C[c]) / check_ratio + R[child]);
    }
}

/// A ball (centre, radius) and its far side's distance from some point.
struct FarBall {
  Vec3 c{};
  double r = 0, distance = -1;
};

/// The centre and radius of a small ball around a set of balls, given farthest(x) (the ball whose
/// far side is farthest from x): Bădoiu–Clarkson steps from `start` towards that far side, the
/// smallest ball met kept.
template <class Farthest>
std::pair<Vec3, double> small_ball(const Vec3 &start, const Farthest &farthest)
{
  Vec3 x = start, best = x;
  double best_r = std::numeric_limits<double>::max();
  for (int it = 1; it <= centre_steps; ++it) {
    const FarBall f = farthest(x);
    if (f.distance < best_r) best_r = f.distance, best = x;
    const Vec3 to = f.c - x;
    const double d = norm(to);
    if (d == 0) break;
    x = x + ((d + f.r) / (d * (it + 1))) * to;
  }
  return {best, best_r};
}

/// The ball of a triangle of [begin, end) (tree order) whose far side is farthest from x, if farther than f.
void farthest_triangle(const SomiglianaSources &src, const ClusterTree &tree, int begin, int end, const Vec3 &x, FarBall &f)
{
  for (int p = begin; p < end; ++p) {
    const int e = tree.perm()[p];
    const double d = norm(src.centroid(e) - x) + src.radius(e);
    if (d > f.distance) f = {src.centroid(e), src.radius(e), d};
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
        kelvin_displacement_point<double>(k, d0, d1, d2, b == 0, b == 1, b == 2, col[i], col[pc + i], col[2 * pc + i]);
      }
    }
  pinv = pseudo_inverse(std::move(A), m, n);
}

void Fit::solve(double R, const std::vector<double> &field, std::vector<double> &forces) const
{
  forces.assign(3 * pe(), 0.0);
  lapack::gemv('N', 3 * pe(), 3 * pc(), R, pinv.data(), 3 * pe(), field.data(), 0.0, forces.data());
}

} // namespace detail

using detail::add_forces_at;

InteriorEvaluator::Impl::Impl(const SomiglianaSources &s, const InteriorEvaluationOptions &o)
  : src(s), opt(o), up(s.constants(), o.equivalent_points, check_points(o, o.equivalent_points), o.equivalent_ratio, o.check_ratio),
    down(s.constants(), o.equivalent_points, check_points(o, o.equivalent_points), o.check_ratio, o.equivalent_ratio),
    tree(triangle_centroids(s), leaves_of(o.source_leaf))
{
  if (o.inner_points > 0 && !o.direct) inner = std::make_unique<detail::Fit>(s.constants(), o.inner_points, check_points(o, o.inner_points), o.equivalent_ratio, o.inner_ratio);
}

void InteriorEvaluator::Impl::order_particles()
{
  const Particles &P = src.particles();
  const std::size_t n = P.size();
  detail::OrderedParticles &o = particles;
  for (int a = 0; a < 3; ++a) {
    for (auto *v : {&o.y[a], &o.f[a], &o.m[a], &o.n[a]}) v->resize(n);
    for (auto *v : {&o.ys[a], &o.fs[a], &o.ms[a], &o.ns[a]}) v->resize(n);
  }
  for (int c = 0; c < tree.num_clusters(); ++c) {
    const Cluster &cl = tree.cluster(c);
    if (!tree.is_leaf(c)) continue;
    for (int p = cl.begin; p < cl.end; ++p) {
      const int e = tree.perm()[p];
      for (std::size_t k = 0; k < Particles::per_triangle; ++k) {
        const std::size_t i = Particles::per_triangle * static_cast<std::size_t>(e) + k, at = Particles::per_triangle * static_cast<std::size_t>(p) + k;
        for (int a = 0; a < 3; ++a) {
          o.y[a][at] = P.y[a][i], o.f[a][at] = P.f[a][i], o.m[a][at] = P.m[a][i], o.n[a][at] = P.n[a][i];
          o.ys[a][at] = static_cast<float>(P.y[a][i] - C[c][a]), o.fs[a][at] = static_cast<float>(P.f[a][i]);
          o.ms[a][at] = static_cast<float>(P.m[a][i]), o.ns[a][at] = static_cast<float>(P.n[a][i]);
        }
      }
    }
  }
}

void InteriorEvaluator::Impl::add_equivalent(const Vec3 &x, int b, double *out) const
{
  detail::add_forces_field(src.constants(), x, C[b], R[b] * up.r_equiv, up.equiv, qf[b].data(), out);
}

void InteriorEvaluator::Impl::add_leaf(const Vec3 &x, int b, double *out, InteriorEvaluationStats &s) const
{
  const Cluster &cl = tree.cluster(b);
  const double D = norm(x - C[b]);
  if (D >= opt.check_ratio * R[b] && D >= reach[b] && cl.size() * Particles::per_triangle > up.pe()) {
    s.kernel_far += up.pe();
    return add_equivalent(x, b, out);
  }
  const std::size_t begin = Particles::per_triangle * static_cast<std::size_t>(cl.begin), end = Particles::per_triangle * static_cast<std::size_t>(cl.end);
  if (D >= reach[b] && !qi[b].empty() && D >= inner->r_check * R[b]) {
    s.kernel_inner += inner->pe();
    return detail::add_forces_field(src.constants(), x, C[b], R[b] * inner->r_equiv, inner->equiv, qi[b].data(), out);
  }
  s.kernel_near += Particles::per_triangle * cl.size();
  if (D >= reach[b]) return particles.add_regular(src.constants(), x, C[b], begin, end, nullptr, out); // every triangle regular at x
  // The triangles near x (decided in doubles, as SomiglianaSources does) are split instead.
  thread_local std::vector<float> weight; // add_leaf runs on the evaluation's threads
  weight.resize(end - begin);
  for (int p = cl.begin; p < cl.end; ++p) {
    const int e = tree.perm()[p];
    const bool regular = src.is_regular(x, e);
    std::fill_n(&weight[Particles::per_triangle * static_cast<std::size_t>(p - cl.begin)], Particles::per_triangle, regular ? 1.0f : 0.0f);
    if (!regular) src.add_triangle(x, e, out), ++s.adaptive_triangles;
  }
  particles.add_regular(src.constants(), x, C[b], begin, end, weight.data(), out);
}

void InteriorEvaluator::Impl::source_centres()
{
  const int nc = tree.num_clusters();
  C.resize(nc);
  std::vector<double> r(nc);
  std::vector<int> leaves; // in the order of their triangles
  for (int c = 0; c < nc; ++c)
    if (tree.is_leaf(c)) leaves.push_back(c);
  std::sort(leaves.begin(), leaves.end(), [&](int a, int b) { return tree.cluster(a).begin < tree.cluster(b).begin; });
#pragma omp parallel for schedule(dynamic)
  for (std::size_t i = 0; i < leaves.size(); ++i) { // over the triangles
    const Cluster &cl = tree.cluster(leaves[i]);
    std::tie(C[leaves[i]], r[leaves[i]]) = small_ball(cl.centre, [&](const Vec3 &x) {
      FarBall f;
      farthest_triangle(src, tree, cl.begin, cl.end, x, f);
      return f;
    });
  }
#pragma omp parallel for schedule(dynamic)
  for (int c = 0; c < nc; ++c) { // over the triangles too, skipping the leaves whose balls lie closer than the farthest so far
    const Cluster &cl = tree.cluster(c);
    if (tree.is_leaf(c)) continue;
    const auto first = std::lower_bound(leaves.begin(), leaves.end(), cl.begin, [&](int l, int at) { return tree.cluster(l).begin < at; });
    const auto last = std::lower_bound(first, leaves.end(), cl.end, [&](int l, int at) { return tree.cluster(l).begin < at; });
    C[c] = small_ball(cl.centre, [&](const Vec3 &x) {
             FarBall f;
             for (auto l = first; l != last; ++l)
               if (norm(C[*l] - x) + r[*l] > f.distance) farthest_triangle(src, tree, tree.cluster(*l).begin, tree.cluster(*l).end, x, f);
             return f;
           }).first;
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
      const double d = norm(src.centroid(e) - C[c]);
      R[c] = std::max(R[c], d + src.radius(e));
      reach[c] = std::max(reach[c], d + src.near_radius(e));
    }
  }
  nest_radii(tree, C, opt.check_ratio, R);
}

void InteriorEvaluator::Impl::leaf_field(int c, const detail::Fit &fit, std::vector<double> &field) const
{
  const Cluster &cl = tree.cluster(c);
  const detail::OrderedParticles &o = particles;
  const SomiglianaConstants &k = src.constants();
  const std::size_t begin = Particles::per_triangle * static_cast<std::size_t>(cl.begin), end = Particles::per_triangle * static_cast<std::size_t>(cl.end);
  const int pc = fit.pc();
  field.assign(3 * pc, 0.0);
  const double *Y0 = o.y[0].data(), *Y1 = o.y[1].data(), *Y2 = o.y[2].data(), *F0 = o.f[0].data(), *F1 = o.f[1].data(), *F2 = o.f[2].data();
  const double *M0 = o.m[0].data(), *M1 = o.m[1].data(), *M2 = o.m[2].data(), *N0 = o.n[0].data(), *N1 = o.n[1].data(), *N2 = o.n[2].data();
  for (int i = 0; i < pc; ++i) {
    const Vec3 x = fit.check_point(C[c], R[c], i);
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
}

void InteriorEvaluator::Impl::upward_leaf(int c)
{
  std::vector<double> field;
  leaf_field(c, up, field);
  up.solve(R[c], field, q[c]);
  // Inner forces where they cost less than the particles, and where their check sphere clears
  // the triangles' near zones (the particles' field there is the 7-point rule's, smooth enough to fit).
  if (inner && particle_cost * Particles::per_triangle * tree.cluster(c).size() > inner->pe() && inner->r_check * R[c] >= reach[c]) {
    std::vector<double> forces;
    leaf_field(c, *inner, field);
    inner->solve(R[c], field, forces);
    qi[c] = detail::to_float(forces);
  }
}

void InteriorEvaluator::Impl::upward_inner(int c)
{
  const Cluster &cl = tree.cluster(c);
  const int pc = up.pc();
  std::vector<double> field(3 * pc, 0.0);
  for (int child : {cl.left, cl.right})
    for (int i = 0; i < pc; ++i) {
      double u[3] = {0, 0, 0};
      add_forces_at(src.constants(), up.check_point(C[c], R[c], i), C[child], R[child] * up.r_equiv, up.equiv, q[child].data(), u);
      field[i] += u[0], field[pc + i] += u[1], field[2 * pc + i] += u[2];
    }
  up.solve(R[c], field, q[c]);
}

void InteriorEvaluator::Impl::upward()
{
  const SerialBlas serial; // the fits' products run inside the loops over clusters
  source_radii();
  q.assign(tree.num_clusters(), {});
  qi.assign(tree.num_clusters(), {});
  for (int l = tree.levels() - 1; l >= 0; --l) {
    const std::vector<int> &level = tree.clusters_at_level(l);
#pragma omp parallel for schedule(dynamic)
    for (std::size_t i = 0; i < level.size(); ++i) {
      const int c = level[i];
      if (tree.is_leaf(c)) upward_leaf(c);
      else upward_inner(c);
    }
  }
  qf.resize(q.size());
  for (std::size_t c = 0; c < q.size(); ++c) qf[c] = detail::to_float(q[c]);
}

bool InteriorEvaluator::Impl::far(const Vec3 &ca, double Ra, int b) const
{
  const double D = norm(ca - C[b]), ri = opt.equivalent_ratio, ro = opt.check_ratio;
  return D >= ro * R[b] + ri * Ra && D >= ro * Ra + ri * R[b] && D >= reach[b] + ri * Ra;
}

InteriorEvaluator::InteriorEvaluator(const SomiglianaSources &src, const InteriorEvaluationOptions &options) : m_impl(std::make_unique<Impl>(src, options))
{
  if (options.equivalent_points < 4 || !(options.equivalent_ratio >= 1) || !(options.check_ratio > options.equivalent_ratio) || options.source_leaf < 1 ||
      options.target_leaf < 1)
    throw std::invalid_argument("interior evaluation: need at least 4 equivalent points, 1 <= equivalent ratio < check ratio and leaves of at least one");
  if (options.inner_points < 0 || (options.inner_points > 0 && (options.inner_points < 4 || !(options.inner_ratio > options.equivalent_ratio))))
    throw std::invalid_argument("interior evaluation: inner points must be 0 or at least 4, with an inner ratio above the equivalent ratio");
  const Timer timer;
  if (!options.direct) {
    m_impl->source_centres();
    m_impl->order_particles();
    m_impl->upward();
  }
  m_upward_seconds = timer.seconds();
}

InteriorEvaluator::~InteriorEvaluator() = default;

} // namespace hssbem
