// The H² factorization's solve, for one right-hand side or a block of them (the steps replayed:
// elimination_step.cpp), and its error estimate (see h2_factorization.hpp).
#include "factors.hpp"

#include "hssbem/core/phase.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace hssbem {

void H2Factorization::solve(const double *b, double *x) const
{
  const std::size_t n = 3 * static_cast<std::size_t>(m_count);
  if (x != b) std::copy(b, b + n, x);
  solve_block(x, 1, static_cast<int>(n));
}

void H2Factorization::solve_block(double *X, int nrhs, int ld) const
{
  PhaseScope phase(Phase::H2Solve);
  const RankComm &comm = *m_comm;
  const Factors &f = *m_f;
  const std::size_t n = 3 * static_cast<std::size_t>(m_count), first = 3 * static_cast<std::size_t>(m_first), nt = static_cast<std::size_t>(f.top_n), stride = static_cast<std::size_t>(ld);
  h2f::Step::Work w;
  std::vector<double> t; // the top's right-hand sides, whole on every rank
  collectively(comm, [&] {
    if (nrhs < 0 || ld < 0 || stride < n) throw std::invalid_argument("H2 factorization: a block solve needs nrhs >= 0 and ld >= the rows");
    for (const h2f::Step &s : f.steps) s.forward(X, stride, nrhs, w);
    t.assign(nt * nrhs, 0.0);
    for (int c = 0; c < nrhs; ++c)
      for (std::size_t i = 0; i < f.top_own.size(); ++i) t[c * nt + f.top_pos[i]] = X[c * stride + f.top_own[i]];
  });
  comm.sum(t.data(), static_cast<int>(t.size()));
  if (f.spread)
    for (int c = 0; c < nrhs; ++c) f.top->solve(t.data() + c * nt); // collective
  else {
    collectively(comm, [&] {
      for (int c = 0; c < nrhs; ++c) // rank 0; refined in double when mixed
        if (f.top) f.top->solve(t.data() + c * nt);
      if (!f.top) std::fill(t.begin(), t.end(), 0.0);
    });
    comm.sum(t.data(), static_cast<int>(t.size())); // and its unknowns to every rank
  }
  collectively(comm, [&] {
    for (int c = 0; c < nrhs; ++c)
      for (std::size_t i = 0; i < f.top_own.size(); ++i) X[c * stride + f.top_own[i]] = t[c * nt + f.top_pos[i]];
    for (auto it = f.steps.rbegin(); it != f.steps.rend(); ++it) it->backward(X, stride, nrhs, w);
    for (int c = 0; c < nrhs; ++c) // A-hat = A D: x = D y
      for (std::size_t i = 0; i < n; ++i) X[i + c * stride] *= m_K.col_scale(f.pattern.slot[first + i]);
  });
}

void solve_mesh_order(const H2Factorization &F, const double *b, double *x)
{
  const ClusterTree &tree = F.matrix().tree();
  if (F.num_points() != tree.num_points()) throw std::logic_error("H2 factorization: a solve in mesh order needs every point on this rank");
  std::vector<double> y(3 * static_cast<std::size_t>(tree.num_points()));
  tree.to_cluster_order(b, y.data(), 3);
  F.solve(y.data(), y.data());
  tree.to_mesh_order(y.data(), x, 3);
}

double estimate_inverse_error(const H2Factorization &F, const std::function<void(const double *, double *)> &apply_a, int iterations, unsigned seed)
{
  const RankComm &comm = F.comm();
  const std::size_t n = 3 * static_cast<std::size_t>(F.num_points());
  std::mt19937_64 gen(seed + static_cast<unsigned>(comm.rank()));
  std::normal_distribution<double> normal;
  std::vector<double> v, z, w;
  collectively(comm, [&] {
    for (auto *a : {&v, &z, &w}) a->resize(n);
    for (double &e : v) e = normal(gen);
  });
  const auto norm = [&](const std::vector<double> &a) {
    double s = 0;
    for (double e : a) s += e * e;
    comm.sum(&s, 1);
    return std::sqrt(s);
  };
  double worst = 0;
  for (int it = 0; it < iterations; ++it) {
    const double nv = norm(v);
    if (!(nv > 0)) break; // zero (or NaN) on every rank alike
    F.solve(v.data(), z.data());
    apply_a(z.data(), w.data());
    for (std::size_t i = 0; i < n; ++i) w[i] = v[i] - w[i];
    const double nw = norm(w);
    worst = std::max(worst, nw / nv);
    for (std::size_t i = 0; i < n; ++i) v[i] = w[i] / nw;
  }
  return worst;
}

} // namespace hssbem
