// METIS partition of the dof nodes (see node_partition.hpp).
#include "hssbem/bem/node_partition.hpp"

#include <metis.h>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace hssbem {

namespace {

/// Adjacency (CSR) of the dof-node graph: nodes sharing a triangle or a mesh vertex.
void node_graph(const Discretization &disc, std::vector<idx_t> &xadj, std::vector<idx_t> &adj)
{
  const int n = disc.num_nodes();
  const SurfaceMesh &mesh = disc.mesh();
  std::vector<std::vector<int>> nb(n);
  for (int t = 0; t < mesh.num_triangles(); ++t) {
    const std::array<int, 3> &e = disc.element_nodes(t);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        if (e[a] != e[b]) nb[e[a]].push_back(e[b]);
  }
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const int first = disc.first_node(v), count = disc.node_count(v);
    for (int a = 0; a < count; ++a)
      for (int b = 0; b < count; ++b)
        if (a != b) nb[first + a].push_back(first + b);
  }
  xadj.assign(n + 1, 0);
  adj.clear();
  for (int i = 0; i < n; ++i) {
    std::sort(nb[i].begin(), nb[i].end());
    nb[i].erase(std::unique(nb[i].begin(), nb[i].end()), nb[i].end());
    adj.insert(adj.end(), nb[i].begin(), nb[i].end());
    xadj[i + 1] = static_cast<idx_t>(adj.size());
  }
}

/// Number of parts that are not one connected piece of the graph.
int disconnected_parts(const std::vector<idx_t> &xadj, const std::vector<idx_t> &adj, const std::vector<int> &part, int nparts)
{
  const int n = static_cast<int>(part.size());
  std::vector<int> pieces(nparts, 0), stack;
  std::vector<char> seen(n, 0);
  for (int s = 0; s < n; ++s) {
    if (seen[s]) continue;
    ++pieces[part[s]];
    seen[s] = 1;
    stack.assign({s});
    while (!stack.empty()) {
      const int i = stack.back();
      stack.pop_back();
      for (idx_t k = xadj[i]; k < xadj[i + 1]; ++k) {
        const int j = static_cast<int>(adj[k]);
        if (!seen[j] && part[j] == part[i]) {
          seen[j] = 1;
          stack.push_back(j);
        }
      }
    }
  }
  return static_cast<int>(std::count_if(pieces.begin(), pieces.end(), [](int p) { return p > 1; }));
}

} // namespace

std::vector<int> partition_nodes(const Discretization &disc, int nparts, NodePartitionStats *stats)
{
  const int n = disc.num_nodes();
  if (nparts < 1) throw std::invalid_argument("node partition: at least one part expected");
  if (n < k_min_nodes_per_part * nparts)
    throw std::invalid_argument("the surface has " + std::to_string(n) + " dof nodes, too few for " + std::to_string(nparts) + " MPI ranks (at least " +
                                std::to_string(k_min_nodes_per_part) + " per rank): run on at most " + std::to_string(std::max(1, n / k_min_nodes_per_part)) + " ranks");
  std::vector<idx_t> xadj, adj;
  node_graph(disc, xadj, adj);
  std::vector<int> part(n, 0);
  if (nparts > 1) {
    idx_t nv = n, ncon = 1, np = nparts, cut = 0;
    std::vector<idx_t> vwgt(n, 3), where(n, 0);
    idx_t options[METIS_NOPTIONS];
    METIS_SetDefaultOptions(options);
    options[METIS_OPTION_SEED] = 1;
    options[METIS_OPTION_NUMBERING] = 0;
    options[METIS_OPTION_CONTIG] = 1;
    int status = METIS_PartGraphKway(&nv, &ncon, xadj.data(), adj.data(), vwgt.data(), nullptr, nullptr, &np, nullptr, nullptr, options, &cut, where.data());
    const auto complete = [&] {
      std::vector<int> count(nparts, 0);
      for (idx_t w : where) ++count[w];
      return std::all_of(count.begin(), count.end(), [](int c) { return c > 0; });
    };
    if (status != METIS_OK || !complete()) { // e.g. a disconnected surface: no contiguous k-way
      METIS_SetDefaultOptions(options);
      options[METIS_OPTION_SEED] = 1;
      options[METIS_OPTION_NUMBERING] = 0;
      status = METIS_PartGraphRecursive(&nv, &ncon, xadj.data(), adj.data(), vwgt.data(), nullptr, nullptr, &np, nullptr, nullptr, options, &cut, where.data());
      if (status != METIS_OK) throw std::runtime_error("node partition: METIS failed (status " + std::to_string(status) + ")");
      if (!complete()) throw std::runtime_error("node partition: METIS left a part empty");
    }
    for (int i = 0; i < n; ++i) part[i] = static_cast<int>(where[i]);
  }
  if (stats) {
    NodePartitionStats s;
    s.parts = nparts;
    std::vector<int> count(nparts, 0);
    for (int p : part) ++count[p];
    s.min_nodes = *std::min_element(count.begin(), count.end());
    s.max_nodes = *std::max_element(count.begin(), count.end());
    s.imbalance = static_cast<double>(s.max_nodes) * nparts / n;
    for (int i = 0; i < n; ++i)
      for (idx_t k = xadj[i]; k < xadj[i + 1]; ++k) {
        if (adj[k] <= i) continue;
        ++s.edges;
        if (part[adj[k]] != part[i]) ++s.edge_cut;
      }
    s.disconnected_parts = disconnected_parts(xadj, adj, part, nparts);
    *stats = s;
  }
  return part;
}

} // namespace hssbem
