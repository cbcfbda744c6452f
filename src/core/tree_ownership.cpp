// Owners of a partitioned cluster tree's clusters (see tree_ownership.hpp).
#include "hssbem/core/tree_ownership.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace hssbem {

std::vector<int> cluster_parts(const ClusterTree &tree)
{
  std::vector<int> part(tree.num_clusters(), -1);
  std::vector<int> root_of(tree.num_clusters(), -1);
  for (int p = 0; p < tree.num_parts(); ++p) root_of[tree.part_cluster(p)] = p;
  for (int c = 0; c < tree.num_clusters(); ++c) { // breadth first: a parent before its children
    const int parent = tree.cluster(c).parent;
    part[c] = root_of[c] >= 0 ? root_of[c] : parent >= 0 ? part[parent] : -1;
  }
  return part;
}

std::vector<int> cluster_owners(const ClusterTree &tree, int ranks)
{
  std::vector<int> owner(tree.num_clusters(), 0);
  if (ranks == 1) return owner;
  if (tree.num_parts() != ranks)
    throw std::invalid_argument("the cluster tree has " + std::to_string(tree.num_parts()) + " parts for " + std::to_string(ranks) + " ranks");
  owner = cluster_parts(tree);
  for (int &o : owner) o = std::max(o, 0);
  return owner;
}

std::vector<std::vector<int>> clusters_by_level(const ClusterTree &tree, const std::vector<int> &clusters, bool up)
{
  std::vector<std::vector<int>> out(tree.levels());
  for (int c : clusters) out[tree.cluster(c).level].push_back(c);
  if (up) std::reverse(out.begin(), out.end());
  out.erase(std::remove_if(out.begin(), out.end(), [](const std::vector<int> &v) { return v.empty(); }), out.end());
  return out;
}

void ClusterOwners::set(std::vector<int> owner, int rank, int clusters)
{
  if (!owner.empty() && static_cast<int>(owner.size()) != clusters) throw std::invalid_argument("one owner per cluster expected");
  m_owner = std::move(owner);
  m_rank = rank;
}

bool ClusterOwners::holds_all() const
{
  return std::all_of(m_owner.begin(), m_owner.end(), [this](int o) { return o == m_rank; });
}

} // namespace hssbem
