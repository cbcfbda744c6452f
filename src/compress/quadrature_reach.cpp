// How far the quadrature reaches from each node and cluster (see quadrature_reach.hpp).
#include "hssbem/compress/quadrature_reach.hpp"

#include <algorithm>

namespace hssbem {

QuadratureReach quadrature_reach(const BemOperator &op, const ClusterTree &tree)
{
  const Discretization &disc = op.discretization();
  const double ratio = op.quadrature_options().near_ratio * (1.0 + 1e-9) + 1e-12;
  const int nn = disc.num_nodes();
  QuadratureReach r;
  r.sigma.assign(nn, 0.0);
  r.h.assign(nn, 0.0);
  for (int j = 0; j < nn; ++j) {
    const Vec3 &s = disc.node_position(j);
    for (const int *t = disc.support_begin(j); t != disc.support_end(j); ++t) {
      const Triangle &tri = op.triangle(*t);
      const Vec3 c = (1.0 / 3) * (tri.p[0] + tri.p[1] + tri.p[2]);
      const double d = std::max({norm(tri.p[1] - tri.p[0]), norm(tri.p[2] - tri.p[1]), norm(tri.p[0] - tri.p[2])});
      r.h[j] = std::max(r.h[j], d);
      r.sigma[j] = std::max(r.sigma[j], norm(c - s) + ratio * d);
    }
  }
  const int nc = tree.num_clusters();
  r.row_r.assign(nc, 0.0);
  r.src_r.assign(nc, 0.0);
  r.reach_r.assign(nc, 0.0);
  for (int c = 0; c < nc; ++c) {
    const Cluster &cl = tree.cluster(c);
    for (int k = cl.begin; k < cl.end; ++k) {
      const int j = tree.perm()[k];
      const double d = norm(disc.node_position(j) - cl.centre);
      r.row_r[c] = std::max(r.row_r[c], norm(disc.node(j).point - cl.centre));
      r.src_r[c] = std::max(r.src_r[c], d + r.h[j]);
      r.reach_r[c] = std::max(r.reach_r[c], d + r.sigma[j]);
    }
  }
  return r;
}

} // namespace hssbem
