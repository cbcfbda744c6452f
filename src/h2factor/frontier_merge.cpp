// The frontier of the H² factorization: a level's boxes merged into their parents (see
// frontier.hpp).
#include "frontier.hpp"

#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/dense_ops.hpp"
#include "hssbem/core/lapack.hpp"

#include <algorithm>
#include <stdexcept>

namespace hssbem::h2f {

std::vector<int> Frontier::parts_of(int P, int l) const
{
  const Cluster &cp = m_tree.cluster(P);
  if (cp.level == l - 1 && cp.left >= 0) return {cp.left, cp.right};
  return {P};
}

DenseMatrix Frontier::assemble(int P, int Q, int l, std::vector<std::map<int, StoredBlock>> &which)
{
  DenseMatrix B(static_cast<int>(m_D[P].size()), static_cast<int>(m_D[Q].size()));
  int ro = 0;
  for (int b : parts_of(P, l)) {
    int co = 0;
    for (int c : parts_of(Q, l)) {
      const auto it = which[b].find(c);
      if (it != which[b].end()) {
        dense::put(B, ro, co, it->second.take());
        which[b].erase(it);
      } else if (B.m > 0)
        add_far_part(b, c, &B(ro, co), B.ld()); // children that are not close (or of different parts)
      co += static_cast<int>(m_D[c].size());
    }
    ro += static_cast<int>(m_D[b].size());
  }
  return B;
}

void Frontier::merge(int l)
{
  std::vector<int> front;
  std::vector<char> in_front;
  collectively(*m_comm, [&] {
    for (int c : m_tree.clusters_at_level(l - 1))
      if (m_box_part.empty() || m_box_part[c] >= 0) front.push_back(c);
    for (int c : m_tree.leaves())
      if (m_tree.cluster(c).level < l - 1) front.push_back(c);
    if (!m_box_part.empty()) // the parts' roots (and boxes under them) that stop below level l - 1
      for (int c : m_front)
        if (m_tree.cluster(c).level >= l && m_box_part[m_tree.cluster(c).parent] < 0) front.push_back(c);
    // Unknowns and restricted bases of the new boxes: children's, concatenated and transferred.
    std::vector<int> parents;
    for (int P : front)
      if (m_tree.cluster(P).level == l - 1 && m_tree.cluster(P).left >= 0 && mine(P)) parents.push_back(P);
    merge_bases(parents);
    in_front.assign(m_tree.num_clusters(), 0);
    for (int P : front) in_front[P] = 1;
  });
  if (!m_owner.empty()) prepare_cross_merge(l, front, in_front);
  collectively(*m_comm, [&] { merge_blocks(l, front, in_front); });
}

void Frontier::merge_bases(const std::vector<int> &parents)
{
  for_each_cluster(parents, [&](int P) {
    const Cluster &cp = m_tree.cluster(P);
    const int a = cp.left, b = cp.right;
    m_D[P] = m_D[a];
    m_D[P].insert(m_D[P].end(), m_D[b].begin(), m_D[b].end());
    if (m_pat.regularised()) {
      m_Phi[P] = dense::vcat(m_Phi[a], m_Phi[b]);
      m_Psi[P] = dense::vcat(m_Psi[a], m_Psi[b]);
    }
    for (int rows = 0; rows < 2; ++rows) {
      const DenseMatrix B = basis_side(m_K, P, rows);
      const DenseMatrix Ea = (rows ? m_Eu[a] : m_Ew[a]).value(), Eb = (rows ? m_Eu[b] : m_Ew[b]).value();
      StoredBlock &stored = rows ? m_Eu[P] : m_Ew[P];
      stored = StoredBlock(DenseMatrix(static_cast<int>(m_D[P].size()), B.n));
      DenseMatrix &E = stored.open();
      if (B.n == 0) continue;
      if (B.m != Ea.n + Eb.n) throw std::logic_error("H2 factorization: a basis does not match its children's");
      if (Ea.m > 0 && Ea.n > 0) lapack::gemm('N', 'N', Ea.m, B.n, Ea.n, 1.0, Ea.data(), Ea.ld(), B.data(), B.ld(), 0.0, E.data(), E.ld());
      if (Eb.m > 0 && Eb.n > 0) lapack::gemm('N', 'N', Eb.m, B.n, Eb.n, 1.0, Eb.data(), Eb.ld(), B.data() + Ea.n, B.ld(), 0.0, E.data() + Ea.m, E.ld());
      settle(stored);
    }
  });
}

void Frontier::merge_blocks(int l, std::vector<int> &front, std::vector<char> &in_front)
{
  // Blocks between close new boxes, from the children's blocks and far parts; fill-in between
  // boxes whose parents are still not close stays fill-in, on the parents.
  std::vector<std::map<int, StoredBlock>> M(m_tree.num_clusters()), X(m_tree.num_clusters()), G(m_tree.num_clusters());
  std::vector<std::vector<int>> cross(m_tree.num_clusters());
  for_each_cluster(front, [&](int P) {
    for (int Q : m_part.close[P]) {
      if (!in_front[Q]) continue;
      if (same_part(P, Q)) {
        if (mine(P)) settle(M[P].emplace(Q, StoredBlock(assemble(P, Q, l, m_M))).first->second);
        continue;
      }
      cross[P].push_back(Q);
      if (mine(Q)) settle(G[P].emplace(Q, StoredBlock(assemble(P, Q, l, m_G))).first->second);
      if (mine(P)) settle(X[P].emplace(Q, StoredBlock(assemble(P, Q, l, m_X))).first->second);
    }
  });
  m_remote_w.clear();
  m_pair_far.clear();
  std::vector<std::map<int, StoredBlock>> F = merged_fill(l);
  std::size_t added = 0;
  for (const auto *store : {&M, &F, &X, &G})
    for (const auto &row : *store)
      for (const auto &e : row) added += e.second.bytes();
  m_peak = std::max(m_peak, store_bytes() + added);
  m_M.swap(M);
  m_F.swap(F);
  m_X.swap(X);
  m_G.swap(G);
  m_cross.swap(cross);
  for (int P : m_front) // boxes now inside a parent
    if (!in_front[P]) {
      m_D[P].clear();
      m_Eu[P] = StoredBlock();
      m_Ew[P] = StoredBlock();
      m_Phi[P] = DenseMatrix();
      m_Psi[P] = DenseMatrix();
    }
  m_front.swap(front);
  m_in_front.swap(in_front);
  for (auto &v : m_fill_cols) v.clear();
  for (auto &v : m_fill_col_blocks) v.clear();
  for (int P : m_front)
    for (const auto &e : m_F[P]) m_fill_cols[e.first].push_back(P);
}

std::vector<std::map<int, StoredBlock>> Frontier::merged_fill(int l)
{
  const auto up = [&](int b) { return m_tree.cluster(b).level == l ? m_tree.cluster(b).parent : b; };
  const auto offset = [&](int P, int b) {
    int o = 0;
    for (int x : parts_of(P, l)) {
      if (x == b) break;
      o += static_cast<int>(m_D[x].size());
    }
    return o;
  };
  // Parent by parent (its row of fill comes from its own parts only), each parked when complete.
  std::vector<std::map<int, StoredBlock>> out(m_tree.num_clusters());
  std::vector<int> parents;
  for (int b : m_front) parents.push_back(up(b));
  std::sort(parents.begin(), parents.end());
  parents.erase(std::unique(parents.begin(), parents.end()), parents.end());
  for_each_cluster(parents, [&](int P) {
    std::map<int, DenseMatrix> F;
    for (int b : parts_of(P, l)) {
      if (!m_in_front[b]) continue;
      for (auto &[c, stored] : m_F[b]) {
        const int Q = up(c);
        if (m_part.is_close(P, Q)) continue; // inside the close block of P and Q (assemble)
        auto it = F.find(Q);
        if (it == F.end()) it = F.emplace(Q, DenseMatrix(static_cast<int>(m_D[P].size()), static_cast<int>(m_D[Q].size()))).first;
        const int ro = offset(P, b), co = offset(Q, c);
        const DenseMatrix B = stored.take(); // this block's only use
        for (int j = 0; j < B.n; ++j)
          for (int i = 0; i < B.m; ++i) it->second(ro + i, co + j) += B(i, j);
      }
    }
    for (auto &[Q, B] : F) settle(out[P].emplace(Q, StoredBlock(std::move(B))).first->second);
  });
  return out;
}

} // namespace hssbem::h2f
