// The frontier of the H² factorization: active boxes, their bases and explicit blocks, the far
// parts between them (see frontier.hpp).
#include "frontier.hpp"

#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/dense_ops.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/core/tree_ownership.hpp"

#include <algorithm>
#include <numeric>
#include <stdexcept>

namespace hssbem::h2f {

namespace {

const H2Block &find_far_block(const H2Matrix &K, int a, int b)
{
  for (const H2Block &B : K.far_blocks(a))
    if (B.col_cluster == b) return B;
  throw std::logic_error("H2 factorization: a far pair without its far block");
}

/// The rank of one side of cluster c's nested basis (rows: U, else V).
int basis_rank(const H2Matrix &K, int c, bool rows) { return rows ? K.row_interpolation(c).rank() : K.col_interpolation(c).rank(); }

} // namespace

Frontier::Frontier(const H2Matrix &K, const FarFieldSketch &sketch, const Pattern &pattern, bool single, std::vector<int> part, const RankComm &comm)
  : m_K(K), m_tree(K.tree()), m_part(K.partition()), m_sketch(sketch), m_pat(pattern), m_w(K.col_block()), m_single(single), m_box_part(std::move(part)), m_comm(&comm)
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
      add_regularisation(B.m, B.n, B.data(), B.ld(), a, b);
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
    E = dense::product(E, 'N', dense::sub(B, x == left ? 0 : kl, kx, 0, B.n), 'N');
    x = par;
  }
  return E;
}

std::pair<int, int> Frontier::far_pair(int P, int Q) const
{
  for (int a = P; a >= 0; a = m_tree.cluster(a).parent)
    for (int b = Q; b >= 0; b = m_tree.cluster(b).parent)
      if (m_part.is_far(a, b)) return {a, b};
  throw std::logic_error("H2 factorization: no far block above a pair that is not close");
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
  const auto [a, b] = far_pair(P, Q);
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
  if (it == m_F[P].end()) return;
  DenseMatrix fc;
  const DenseMatrix *fill = it->second.peek();
  add(fill ? *fill : (fc = it->second.value()));
}

DenseMatrix Frontier::far_part(int P, int Q) const
{
  DenseMatrix out(static_cast<int>(m_D[P].size()), static_cast<int>(m_D[Q].size()));
  add_far_part(P, Q, out.data(), out.ld());
  return out;
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

} // namespace hssbem::h2f
