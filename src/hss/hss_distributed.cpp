// The HSS matrix distributed over ranks: this rank's passes and the product (see hss_distributed.hpp).
#include "hssbem/hss/hss_distributed.hpp"

#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/phase.hpp"
#include "hssbem/core/tree_ownership.hpp"
#include "hss_product_steps.hpp"

#include <stdexcept>
#include <string>

namespace hssbem {

HssPasses::HssPasses(const HssMatrix &K, const RankComm &comm)
{
  const ClusterTree &tree = K.tree();
  const int nc = tree.num_clusters(), me = comm.rank();
  collectively(comm, [&] { // local work, but a member that the collective constructors build first
  if (K.rank() != me) throw std::logic_error("HSS: the matrix belongs to rank " + std::to_string(K.rank()));
  above.assign(nc, 0);
  if (tree.num_parts() > 1) {
    const std::vector<int> part = cluster_parts(tree);
    for (int c = 0; c < nc; ++c) above[c] = part[c] < 0;
  }
  if (comm.size() > 1) {
    first = tree.cluster(tree.part_cluster(me)).begin;
    count = tree.cluster(tree.part_cluster(me)).size();
  } else {
    first = 0;
    count = tree.num_points();
  }
  std::vector<int> below, top;
  for (int c = 0; c < nc; ++c)
    if (K.holds(c)) (above[c] ? top : below).push_back(c);
  up = clusters_by_level(tree, below, true);
  top_up = clusters_by_level(tree, top, true);
  top_down = clusters_by_level(tree, top, false);
  down = clusters_by_level(tree, below, false);
  });
}

HssDistributedProduct::HssDistributedProduct(const HssMatrix &K, const RankComm &comm) : m_K(K), m_comm(comm), m_passes(K, comm)
{
  const ClusterTree &tree = K.tree();
  const int P = comm.size();
  std::vector<std::vector<int>> need_moments, need_potentials;
  collectively(comm, [&] {
    need_moments.resize(P);
    need_potentials.resize(P);
    for (int c = 0; c < tree.num_clusters(); ++c) {
      if (!K.holds(c)) continue;
      const Cluster &cl = tree.cluster(c);
      if (cl.left >= 0)
        for (int ch : {cl.left, cl.right}) // the sibling couplings read the children's moments
          if (!K.holds(ch)) need_moments[K.owner(ch)].push_back(ch);
      if (cl.parent >= 0 && !K.holds(cl.parent)) need_potentials[K.owner(cl.parent)].push_back(c);
    }
  });
  m_moments = ClusterExchange(comm, std::move(need_moments));
  m_potentials = ClusterExchange(comm, std::move(need_potentials));
  for (int q = 0; q < P; ++q) {
    for (int c : m_moments.sends()[q]) m_values_sent += static_cast<long long>(K.cluster(c).col_skel.size());
    for (int c : m_potentials.sends()[q]) m_values_sent += static_cast<long long>(K.cluster(c).row_skel.size());
    m_messages_sent += !m_moments.sends()[q].empty() + !m_potentials.sends()[q].empty();
  }
}

void HssDistributedProduct::apply(const double *X, int ldx, double *Y, int ldy, int nrhs) const
{
  PhaseScope phase(Phase::Matvec);
  const HssMatrix &K = m_K;
  const ClusterTree &tree = K.tree();
  const int nc = tree.num_clusters(), first = m_passes.first;
  std::vector<DenseMatrix> xh(nc), yh(nc);
  const auto moments = [&](int c) { return static_cast<int>(K.cluster(c).col_skel.size()); };
  const auto potentials = [&](int c) { return static_cast<int>(K.cluster(c).row_skel.size()); };
  const auto upward = [&](const std::vector<std::vector<int>> &levels) {
    for (const std::vector<int> &level : levels)
      for_each_cluster(level, [&](int c) {
        if (c != 0) hss_steps::upward(K, c, X, ldx, first, nrhs, xh);
      });
  };
  const auto downward = [&](const std::vector<std::vector<int>> &levels) {
    for (const std::vector<int> &level : levels)
      for_each_cluster(level, [&](int c) {
        if (tree.is_leaf(c)) hss_steps::leaf(K, c, X, ldx, Y, ldy, first, nrhs, yh);
        else hss_steps::downward_inner(K, c, nrhs, xh, yh);
      });
  };
  // 1–2. Moments up to the parts' roots, which go to rank 0.
  collectively(m_comm, [&] { upward(m_passes.up); });
  m_moments.run(xh, nrhs, false, moments);
  // 3. Rank 0: the top, and each part root's potentials back to its rank.
  collectively(m_comm, [&] {
    upward(m_passes.top_up);
    downward(m_passes.top_down);
  });
  m_potentials.run(yh, nrhs, false, potentials);
  // 4. Down through the parts, and the leaves.
  collectively(m_comm, [&] { downward(m_passes.down); });
}

} // namespace hssbem
