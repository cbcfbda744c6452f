// Strong-admissibility block partition by dual tree traversal (see block_partition.hpp).
#include "hssbem/h2/block_partition.hpp"

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace hssbem {

static bool contains(const std::vector<int> &sorted, int v) { return std::binary_search(sorted.begin(), sorted.end(), v); }

bool BlockPartition::is_far(int a, int b) const { return contains(far[a], b); }

bool BlockPartition::is_close(int a, int b) const { return contains(close[a], b); }

BlockPartition strong_block_partition(const ClusterTree &tree, const std::vector<double> &radius, double eta)
{
  if (!(eta >= 0)) throw std::invalid_argument("H2: the admissibility parameter eta must be >= 0");
  const int nc = tree.num_clusters();
  if (static_cast<int>(radius.size()) != nc) throw std::invalid_argument("H2: one radius per cluster expected");
  BlockPartition p;
  p.far.resize(nc);
  p.near.resize(nc);
  p.close.resize(nc);
  std::vector<std::pair<int, int>> stack{{0, 0}};
  while (!stack.empty()) {
    const auto [a, b] = stack.back();
    stack.pop_back();
    const Cluster &ca = tree.cluster(a), &cb = tree.cluster(b);
    if (norm(ca.centre - cb.centre) > (1 + eta) * (radius[a] + radius[b])) {
      p.far[a].push_back(b);
      continue;
    }
    p.close[a].push_back(b);
    const bool la = ca.left < 0, lb = cb.left < 0;
    if (la && lb) {
      p.near[a].push_back(b);
    } else if (la) {
      stack.push_back({a, cb.left});
      stack.push_back({a, cb.right});
    } else if (lb) {
      stack.push_back({ca.left, b});
      stack.push_back({ca.right, b});
    } else {
      for (int x : {ca.left, ca.right})
        for (int y : {cb.left, cb.right}) stack.push_back({x, y});
    }
  }
  for (int c = 0; c < nc; ++c) {
    std::sort(p.far[c].begin(), p.far[c].end());
    std::sort(p.near[c].begin(), p.near[c].end());
    std::sort(p.close[c].begin(), p.close[c].end());
  }
  p.has_far.assign(nc, 0);
  for (int c = 0; c < nc; ++c) { // breadth-first numbering: a parent comes before its children
    const int parent = tree.cluster(c).parent;
    p.has_far[c] = !p.far[c].empty() || (parent >= 0 && p.has_far[parent]);
  }
  return p;
}

} // namespace hssbem
