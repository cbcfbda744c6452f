// The frontier of the H² factorization: active boxes, their explicit blocks, merging a level
// into its parents, and the dense top (see frontier.hpp).
#include "frontier.hpp"

#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/dense_ops.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/core/tree_ownership.hpp"

#include "top_block.hpp"

#include <algorithm>
#include <numeric>
#include <stdexcept>

namespace hssbem::h2f {

namespace {

DenseMatrix multiply(const DenseMatrix &A, const DenseMatrix &B, char tb = 'N')
{
  const int n = tb == 'N' ? B.n : B.m;
  DenseMatrix C(A.m, n);
  if (A.m > 0 && n > 0 && A.n > 0) lapack::gemm('N', tb, A.m, n, A.n, 1.0, A.data(), A.ld(), B.data(), B.ld(), 0.0, C.data(), C.ld());
  return C;
}

const H2Block &find_far_block(const H2Matrix &K, int a, int b)
{
  for (const H2Block &B : K.far_blocks(a))
    if (B.col_cluster == b) return B;
  throw std::logic_error("H2 factorization: a far pair without its far block");
}

/// One side of cluster c's nested basis in double (rows: U, else V), candidates × rank.
DenseMatrix basis_side(const H2Matrix &K, int c, bool rows) { return rows ? K.row_interpolation(c).expand() : K.col_interpolation(c).expand(); }

int basis_rank(const H2Matrix &K, int c, bool rows) { return rows ? K.row_interpolation(c).rank() : K.col_interpolation(c).rank(); }

} // namespace

DenseMatrix &StoredBlock::open()
{
  if (m_parked) {
    m_d.a.assign(m_s.begin(), m_s.end());
    std::vector<float>().swap(m_s);
    m_parked = false;
  }
  return m_d;
}

void StoredBlock::park()
{
  if (m_parked) return;
  m_s.assign(m_d.a.begin(), m_d.a.end());
  std::vector<double>().swap(m_d.a);
  m_parked = true;
}

DenseMatrix StoredBlock::take()
{
  DenseMatrix out = m_parked ? value() : std::move(m_d);
  *this = StoredBlock();
  return out;
}

DenseMatrix StoredBlock::value() const
{
  if (!m_parked) return m_d;
  DenseMatrix out(m_d.m, m_d.n);
  std::copy(m_s.begin(), m_s.end(), out.a.begin());
  return out;
}

namespace {

const RankComm &one_rank()
{
  static const SerialComm comm;
  return comm;
}

} // namespace

Frontier::Frontier(const H2Matrix &K, const FarFieldSketch &sketch, const Pattern &pattern, bool single, std::vector<int> part, const RankComm *comm)
  : m_K(K), m_tree(K.tree()), m_part(K.partition()), m_sketch(sketch), m_pat(pattern), m_w(K.col_block()), m_single(single), m_box_part(std::move(part)),
    m_comm(comm ? comm : &one_rank())
{
  collectively(*m_comm, [&] { // this rank's leaves; every leaf's unknowns and Φ, Ψ
    if (!m_box_part.empty() && m_box_part.size() != static_cast<std::size_t>(m_tree.num_clusters())) throw std::invalid_argument("H2 factorization: a part list of the wrong length");
    if (m_comm->size() > 1) {
      if (m_box_part.empty()) throw std::invalid_argument("H2 factorization: several ranks need the tree's parts");
      m_owner = cluster_owners(m_tree, m_comm->size());
      m_rank = m_comm->rank();
    }
    const std::size_t nc = static_cast<std::size_t>(m_tree.num_clusters());
    m_in_front.assign(nc, 0);
    for (auto *v : {&m_D, &m_cross, &m_fill_cols}) v->resize(nc);
    for (auto *v : {&m_Eu, &m_Ew}) v->resize(nc);
    for (auto *v : {&m_Phi, &m_Psi}) v->resize(nc);
    for (auto *v : {&m_M, &m_F, &m_X, &m_G}) v->resize(nc);
    m_side.resize(nc);
    m_fill_col_blocks.resize(nc);
    m_opened.resize(nc);
    m_front = m_tree.leaves();
    for (int c : m_front) m_in_front[c] = 1;
    init_leaves();
  });
  if (!m_owner.empty()) exchange_leaf_copies();
  note_bytes();
}

void Frontier::init_leaves()
{
  for (int c : m_front) {
    const Cluster &cl = m_tree.cluster(c);
    for (int b : m_part.near[c])
      if (!same_part(c, b)) m_cross[c].push_back(b);
    m_D[c].resize(3 * static_cast<std::size_t>(cl.size()));
    for (int i = 0; i < 3 * cl.size(); ++i) m_D[c][i] = 3 * cl.begin + i;
    if (mine(c)) {
      m_Eu[c] = StoredBlock(basis_side(m_K, c, true));
      m_Ew[c] = StoredBlock(leaf_col_basis(c));
      settle(m_Eu[c]);
      settle(m_Ew[c]);
    }
    if (m_pat.regularised()) {
      const std::size_t N = static_cast<std::size_t>(m_pat.dofs());
      m_Phi[c] = DenseMatrix(static_cast<int>(m_D[c].size()), 6);
      m_Psi[c] = DenseMatrix(static_cast<int>(m_D[c].size()), 6);
      for (int j = 0; j < 6; ++j)
        for (std::size_t i = 0; i < m_D[c].size(); ++i) {
          m_Phi[c](static_cast<int>(i), j) = m_pat.phi[m_D[c][i] + j * N];
          m_Psi[c](static_cast<int>(i), j) = m_pat.psi[m_D[c][i] + j * N];
        }
    }
  }
  for (int a : m_front)
    for (int b : m_part.near[a]) {
      if (!mine(a)) continue;
      DenseMatrix B = leaf_near(a, b);
      add_regularisation(B, a, b);
      if (!same_part(a, b)) { // a cross block, in its two copies (the other rank's: exchange_leaf_copies)
        if (mine(b)) settle(m_G[a].emplace(b, StoredBlock(B)).first->second);
        settle(m_X[a].emplace(b, StoredBlock(std::move(B))).first->second);
      } else
        settle(m_M[a].emplace(b, StoredBlock(std::move(B))).first->second);
    }
}

DenseMatrix Frontier::leaf_col_basis(int c) const
{
  const Cluster &cl = m_tree.cluster(c);
  const DenseMatrix V = basis_side(m_K, c, false);
  DenseMatrix W(3 * cl.size(), V.n);
  for (int k = cl.begin; k < cl.end; ++k)
    for (int a = 0; a < 3; ++a) {
      const int g = 3 * k + a, row = m_w * (k - cl.begin) + m_pat.slot[g];
      for (int j = 0; j < V.n; ++j) W(3 * (k - cl.begin) + a, j) = m_pat.sign[g] * V(row, j);
    }
  return W;
}

DenseMatrix Frontier::leaf_near(int a, int b) const
{
  const H2Block *B = m_K.near_block(a, b);
  if (!B) throw std::logic_error("H2 factorization: a near pair without its near block");
  const Cluster &cb = m_tree.cluster(b);
  const int m = 3 * m_tree.cluster(a).size();
  DenseMatrix out(m, 3 * cb.size());
  std::vector<double> buf;
  const double *d = B->data(buf); // any stored form, in double
  for (int k = cb.begin; k < cb.end; ++k)
    for (int c = 0; c < 3; ++c) {
      const int g = 3 * k + c, col = m_w * (k - cb.begin) + m_pat.slot[g], j = 3 * (k - cb.begin) + c;
      const double *dc = d + static_cast<std::size_t>(col) * B->M.ld();
      for (int i = 0; i < m; ++i) out(i, j) = m_pat.sign[g] * dc[i];
    }
  return out;
}

void Frontier::add_regularisation(DenseMatrix &B, int P, int Q) const { add_regularisation(B.m, B.n, B.data(), B.ld(), P, Q); }

void Frontier::add_regularisation(int m, int n, double *out, int ld, int P, int Q) const
{
  if (!m_pat.regularised() || m == 0 || n == 0) return;
  const DenseMatrix &a = m_Phi[P], &b = m_Psi[Q];
  lapack::gemm('N', 'T', m, n, 6, m_pat.c, a.data(), a.ld(), b.data(), b.ld(), 1.0, out, ld);
}

std::size_t Frontier::active_total() const
{
  std::size_t s = 0;
  for (int X : m_front)
    if (mine(X)) s += m_D[X].size();
  return s;
}

bool Frontier::level_has_far_field(int l) const
{
  if (m_pat.regularised()) return true;
  for (int X : m_tree.clusters_at_level(l))
    if (steps_at(X) && mine(X) && (m_Eu[X].cols() > 0 || m_Ew[X].cols() > 0 || !m_F[X].empty() || !m_fill_cols[X].empty() || !m_cross[X].empty())) return true;
  return false;
}

std::vector<int> Frontier::neighbours(int X) const
{
  std::vector<int> nb;
  for (int Y : m_part.close[X])
    if (m_in_front[Y] && Y != X && same_part(X, Y)) nb.push_back(Y);
  return nb;
}

DenseMatrix Frontier::restricted_basis(int P, int a, bool rows) const
{
  DenseMatrix E = (rows ? m_Eu[P] : m_Ew[P]).value();
  for (int x = P; x != a;) {
    const int par = m_tree.cluster(x).parent, left = m_tree.cluster(par).left;
    if (!m_K.holds(par)) throw std::logic_error("H2 factorization: a far block above the parts (another rank's bases) is not supported");
    const DenseMatrix B = basis_side(m_K, par, rows);
    const int kl = basis_rank(m_K, left, rows), kx = basis_rank(m_K, x, rows);
    E = multiply(E, dense::sub(B, x == left ? 0 : kl, kx, 0, B.n));
    x = par;
  }
  return E;
}

void Frontier::add_far_part(int P, int Q, double *out, int ld) const
{
  const int m = static_cast<int>(m_D[P].size()), n = static_cast<int>(m_D[Q].size());
  const auto add = [&](const DenseMatrix &B) {
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < m; ++i) out[i + static_cast<std::size_t>(j) * ld] += B(i, j);
  };
  if (!same_part(P, Q) && m_part.is_close(P, Q)) return add(m_X[P].at(Q).value()); // a cross block holds the whole current value
  const auto done = m_pair_far.find({P, Q});
  if (done != m_pair_far.end()) return add(done->second); // computed by P's rank
  for (int a = P; a >= 0; a = m_tree.cluster(a).parent)
    for (int b = Q; b >= 0; b = m_tree.cluster(b).parent) {
      if (!m_part.is_far(a, b)) continue;
      if (m == 0 || n == 0) return;
      const H2Block &F = find_far_block(m_K, a, b);
      std::vector<double> buf;
      const double *f = F.data(buf); // any stored form, in double
      // The bases as they rest when they need no carrying up, else carried to a and b.
      DenseMatrix Uc, Wc;
      const DenseMatrix *U = a == P ? m_Eu[P].peek() : nullptr, *W = b == Q && mine(Q) ? m_Ew[Q].peek() : nullptr;
      if (!U) U = &(Uc = restricted_basis(P, a, true));
      if (!W) W = &(Wc = col_basis_to(Q, b));
      if (F.M.m > 0 && F.M.n > 0) {
        DenseMatrix UF(m, F.M.n);
        lapack::gemm('N', 'N', m, F.M.n, F.M.m, 1.0, U->data(), U->ld(), f, F.M.ld(), 0.0, UF.data(), UF.ld());
        lapack::gemm('N', 'T', m, n, F.M.n, 1.0, UF.data(), UF.ld(), W->data(), W->ld(), 1.0, out, ld);
      }
      add_regularisation(m, n, out, ld, P, Q);
      const auto it = m_F[P].find(Q);
      if (it != m_F[P].end()) {
        DenseMatrix fc;
        const DenseMatrix *fill = it->second.peek();
        if (!fill) fill = &(fc = it->second.value());
        for (int j = 0; j < n; ++j)
          for (int i = 0; i < m; ++i) out[i + static_cast<std::size_t>(j) * ld] += (*fill)(i, j);
      }
      return;
    }
  throw std::logic_error("H2 factorization: no far block above a pair that is not close");
}

DenseMatrix Frontier::far_part(int P, int Q) const
{
  DenseMatrix out(static_cast<int>(m_D[P].size()), static_cast<int>(m_D[Q].size()));
  add_far_part(P, Q, out.data(), out.ld());
  return out;
}

std::vector<int> Frontier::parts_of(int P, int l) const
{
  const Cluster &cp = m_tree.cluster(P);
  if (cp.level == l - 1 && cp.left >= 0) return {cp.left, cp.right};
  return {P};
}

DenseMatrix Frontier::assemble_cross(int P, int Q, int l, std::vector<std::map<int, StoredBlock>> &which)
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
        add_far_part(b, c, &B(ro, co), B.ld()); // children of different parts that are not close
      co += static_cast<int>(m_D[c].size());
    }
    ro += static_cast<int>(m_D[b].size());
  }
  return B;
}

long long Frontier::cross_pairs() const
{
  long long n = 0;
  for (const auto &row : m_X) n += static_cast<long long>(row.size());
  return n;
}

std::size_t Frontier::cross_bytes() const
{
  std::size_t s = 0;
  for (const auto *store : {&m_X, &m_G})
    for (const auto &row : *store)
      for (const auto &e : row) s += e.second.bytes();
  return s;
}

void Frontier::finish_level()
{
  if (!m_owner.empty()) exchange_sides();
  // The copies of one cross block go through the other side's step independently: for this
  // rank's box Y and a partner X that took a step, rows of the copy in Y's columns (m_G[X][Y])
  // are kept as X kept them, and columns of the copy in Y's rows (m_X[Y][X]) transformed as X
  // transformed its own copy's.
  collectively(*m_comm, [&] { apply_other_sides(); });
}

void Frontier::apply_other_sides()
{
  std::vector<int> here;
  for (int Y : m_front)
    if (mine(Y)) here.push_back(Y);
  for_each_cluster(here, [&](int Y) {
    for (int X : m_cross[Y]) {
      const CrossSide &side = m_side[X];
      if (!side.recorded) continue;
      StoredBlock &ghost = m_G[X].at(Y);
      DenseMatrix &g = ghost.open();
      g = dense::rows_at(g, side.kept);
      settle(ghost);
      StoredBlock &stored = m_X[Y].at(X);
      const DenseMatrix B = stored.take();
      DenseMatrix out(B.m, side.C.n);
      if (B.m > 0 && B.n > 0 && side.C.n > 0) lapack::gemm('N', 'N', B.m, side.C.n, B.n, 1.0, B.data(), B.ld(), side.C.data(), side.C.ld(), 0.0, out.data(), out.ld());
      stored = StoredBlock(std::move(out));
      settle(stored);
    }
  });
  for (CrossSide &side : m_side) side = CrossSide();
}

DenseMatrix Frontier::assemble_close(int P, int Q, int l)
{
  DenseMatrix B(static_cast<int>(m_D[P].size()), static_cast<int>(m_D[Q].size()));
  int ro = 0;
  for (int b : parts_of(P, l)) {
    int co = 0;
    for (int c : parts_of(Q, l)) {
      const auto it = m_M[b].find(c);
      if (it != m_M[b].end()) {
        dense::put(B, ro, co, it->second.take());
        m_M[b].erase(it);
      } else if (B.m > 0)
        add_far_part(b, c, &B(ro, co), B.ld());
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
        if (mine(P)) settle(M[P].emplace(Q, StoredBlock(assemble_close(P, Q, l))).first->second);
        continue;
      }
      cross[P].push_back(Q);
      if (mine(Q)) settle(G[P].emplace(Q, StoredBlock(assemble_cross(P, Q, l, m_G))).first->second);
      if (mine(P)) settle(X[P].emplace(Q, StoredBlock(assemble_cross(P, Q, l, m_X))).first->second);
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
        if (m_part.is_close(P, Q)) continue; // inside the close block of P and Q (assemble_close)
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

DenseMatrix &Frontier::open(int X, StoredBlock &b)
{
  if (m_single) m_opened[X].push_back(&b);
  return b.open();
}

void Frontier::claim(int X)
{
  std::vector<StoredBlock *> &v = m_fill_col_blocks[X];
  v.clear();
  for (int Z : m_fill_cols[X]) v.push_back(&m_F[Z].at(X));
}

void Frontier::rest(int X)
{
  for (StoredBlock *b : m_opened[X]) b->park();
  std::vector<StoredBlock *>().swap(m_opened[X]);
}

std::size_t Frontier::store_bytes() const
{
  std::size_t s = 0;
  for (const auto *store : {&m_M, &m_F, &m_X, &m_G})
    for (const auto &row : *store)
      for (const auto &e : row) s += e.second.bytes();
  for (int X : m_front) s += m_Eu[X].bytes() + m_Ew[X].bytes();
  return s;
}

void Frontier::take_top(std::vector<int> *dofs, TopSink &sink)
{
  const int nb = static_cast<int>(m_front.size());
  sink.begin(top_offsets());
  std::vector<int> block_rows(nb);
  std::iota(block_rows.begin(), block_rows.end(), 0);
  for_each_cluster(block_rows, [&](int s) { take_row(s, sink); });
  release_stores();
  dofs->clear();
  for (int P : m_front) dofs->insert(dofs->end(), m_D[P].begin(), m_D[P].end());
}

void Frontier::release_stores()
{
  for (auto *store : {&m_M, &m_F, &m_X, &m_G})
    for (auto &row : *store) std::map<int, StoredBlock>().swap(row);
  for (int X : m_front) m_Eu[X] = StoredBlock(), m_Ew[X] = StoredBlock();
  std::map<std::pair<int, int>, DenseMatrix>().swap(m_remote_w);
  std::map<std::pair<int, int>, DenseMatrix>().swap(m_pair_far);
  m_fill_col_blocks.clear();
}

void Frontier::take_row(int s, TopSink &sink)
{
  const int P = m_front[s], nb = static_cast<int>(m_front.size());
  for (int t = 0; t < nb; ++t) {
    const int Q = m_front[t];
    const auto it = m_M[P].find(Q);
    sink.put(s, t, it != m_M[P].end() ? it->second.take() : far_part(P, Q));
  }
  m_M[P].clear();
}

} // namespace hssbem::h2f
