// ULV-type factorization and solve of A = K E_S in HSS form (see ulv.hpp).
#include "hssbem/hss/ulv.hpp"

#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/dense_ops.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/core/fault.hpp"
#include "hssbem/core/phase.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

namespace hssbem {

using namespace dense; // sub, put, product, max_abs

namespace {

const SerialComm k_one_rank;

} // namespace

UlvFactorization::UlvFactorization(const HssMatrix &K, const std::vector<std::array<bool, 3>> &displacement_known, const LowRankTerm *extra)
  : UlvFactorization(K, k_one_rank, displacement_known, extra)
{
}

UlvFactorization::UlvFactorization(const HssMatrix &K, const RankComm &comm, const std::vector<std::array<bool, 3>> &displacement_known, const LowRankTerm *extra)
  : m_K(K), m_comm(comm), m_passes(K, comm)
{
  PhaseScope phase(Phase::Factorization);
  const ClusterTree &tree = K.tree();
  const int P = comm.size();
  std::vector<std::vector<int>> need_up, need_down;
  // A breakdown on any rank is agreed on: every rank throws it (the lowest such rank's message).
  collectively<HssBreakdown>(comm, [&] {
    if (fault_armed("Breakdown")) throw HssBreakdown("HSS factorization broke down (injected fault at Breakdown)");
    m_nodes.resize(tree.num_clusters());
    need_up.resize(P);
    need_down.resize(P);
    if (static_cast<int>(displacement_known.size()) != tree.num_points())
      throw std::invalid_argument("ULV: the boundary-condition pattern has " + std::to_string(displacement_known.size()) + " nodes, the matrix " +
                                  std::to_string(tree.num_points()));
    for (int c = 0; c < tree.num_clusters(); ++c) {
      if (!K.holds(c)) continue;
      const Cluster &cl = tree.cluster(c);
      if (cl.left >= 0)
        for (int ch : {cl.left, cl.right})
          if (!K.holds(ch)) need_up[K.owner(ch)].push_back(ch);
      if (cl.parent >= 0 && !K.holds(cl.parent)) need_down[K.owner(cl.parent)].push_back(c);
    }
    if (extra && extra->p > 0) widen_generators(*extra);
    // Each rank's part, up to its root: no communication.
    fault_point("UlvSubtree");
    factor_levels(m_passes.up, displacement_known);
  });
  m_up = ClusterExchange(comm, std::move(need_up));
  m_down = ClusterExchange(comm, std::move(need_down));
  // The top, from the parts' roots' reduced blocks (rank 0).
  std::optional<PhaseScope> top;
  if (tree.num_parts() > 1) top.emplace(Phase::FactorizationTop);
  send_part_roots();
  collectively<HssBreakdown>(comm, [&] {
    if (!m_passes.top_up.empty()) fault_point("UlvTop");
    factor_levels(m_passes.top_up, displacement_known);
  });
  m_max_front = m_root_lu.m;
  for (const Node &n : m_nodes) m_max_front = std::max(m_max_front, n.m);
}

void UlvFactorization::factor_levels(const std::vector<std::vector<int>> &levels, const std::vector<std::array<bool, 3>> &displacement_known)
{
  for (const std::vector<int> &level : levels) // an HssBreakdown is rethrown after the level
    for_each_cluster(level, [&](int c) { factor_one(c, displacement_known); });
}

void UlvFactorization::factor_one(int c, const std::vector<std::array<bool, 3>> &displacement_known)
{
  DenseMatrix D, U, V;
  if (m_K.tree().is_leaf(c)) leaf_generators(c, displacement_known, D, U, V);
  else merge_children(c, D, U, V);
  if (c != 0) factor_cluster(c, std::move(D), std::move(U), std::move(V));
  else factor_root(std::move(D));
}

/// A leaf's pattern columns: H where u is unknown, −G where t is unknown (D and V), and its row basis.
void UlvFactorization::leaf_generators(int c, const std::vector<std::array<bool, 3>> &displacement_known, DenseMatrix &D, DenseMatrix &U, DenseMatrix &V) const
{
  const ClusterTree &tree = m_K.tree();
  const Cluster &cl = tree.cluster(c);
  const HssCluster &h = m_K.cluster(c);
  const int w = m_K.col_block(), n = cl.size();
  D = DenseMatrix(3 * n, 3 * n);
  V = DenseMatrix(3 * n, h.V.n);
  for (int k = 0; k < n; ++k) {
    const auto &known = displacement_known[tree.perm()[cl.begin + k]];
    for (int a = 0; a < 3; ++a) {
      const int src = w * k + (known[a] ? 3 + a : a);
      const double s = known[a] ? -1.0 / m_K.col_scale(3 + a) : 1.0;
      for (int i = 0; i < 3 * n; ++i) D(i, 3 * k + a) = s * h.D(i, src);
      for (int j = 0; j < h.V.n; ++j) V(3 * k + a, j) = s * h.V(src, j);
    }
  }
  U = h.U;
  if (m_p == 0) return;
  // Y Zᵀ: D += Y_τ Z_τᵀ, and the bases gain Y_τ and Z_τ
  const HssCluster &wd = m_wide[c];
  lapack::gemm('N', 'T', D.m, D.n, m_p, 1.0, wd.U.data() + static_cast<std::size_t>(h.U.n) * wd.U.m, wd.U.ld(), wd.V.data() + static_cast<std::size_t>(h.V.n) * wd.V.m,
               wd.V.ld(), 1.0, D.data(), D.ld());
  U = wd.U;
  DenseMatrix Vw(V.m, V.n + m_p);
  put(Vw, 0, 0, V);
  put(Vw, 0, V.n, sub(wd.V, 0, V.m, h.V.n, m_p));
  V = std::move(Vw);
}

void UlvFactorization::factor_root(DenseMatrix D)
{
  m_root_lu = std::move(D);
  m_root_piv.assign(m_root_lu.m, 0);
  const double amax = max_abs(m_root_lu);
  const int info = lapack::getrf(m_root_lu.m, m_root_lu.data(), m_root_lu.ld(), m_root_piv.data());
  double umin = HUGE_VAL;
  for (int i = 0; i < m_root_lu.m; ++i) umin = std::min(umin, std::abs(m_root_lu(i, i)));
  // The same test as for the pivot blocks below: singular to working precision.
  if (info > 0 || (m_root_lu.m > 0 && !(umin > 1e-14 * amax)))
    throw HssBreakdown("HSS factorization broke down: the root block (" + std::to_string(m_root_lu.m) + " unknowns) is singular to working precision");
}

void UlvFactorization::send_part_roots()
{
  const ClusterTree &tree = m_K.tree();
  exchange_records(
    m_comm, "the ULV's parts' roots",
    [&](std::vector<std::vector<double>> &send) {
    for (int c = 0; c < tree.num_clusters(); ++c) {
      const int parent = tree.cluster(c).parent;
      if (!m_K.holds(c) || parent < 0 || m_K.holds(parent)) continue;
      const Node &nd = m_nodes[c];
      std::vector<double> &r = send[m_K.owner(parent)];
      r.insert(r.end(), {static_cast<double>(c), static_cast<double>(nd.m), static_cast<double>(nd.kr), nd.eliminated ? 1.0 : 0.0});
      append_matrix(r, nd.Ut);
      append_matrix(r, nd.Vt);
      append_matrix(r, nd.Dt);
    }
    },
    [&](const std::vector<std::vector<double>> &recv) {
    for (int c = 0; c < tree.num_clusters(); ++c) // the senders need only Ut (kept for nothing: their parents are elsewhere)
      if (m_K.holds(c) && tree.cluster(c).parent >= 0 && !m_K.holds(tree.cluster(c).parent)) m_nodes[c].Dt = m_nodes[c].Vt = DenseMatrix();
    for (const std::vector<double> &r : recv)
      for (std::size_t at = 0; at < r.size();) {
        if (at + 4 > r.size()) throw std::logic_error("ULV: a truncated record from another rank");
        Node &nd = m_nodes[static_cast<int>(r[at])];
        nd.m = static_cast<int>(r[at + 1]);
        nd.kr = static_cast<int>(r[at + 2]);
        nd.eliminated = r[at + 3] != 0;
        at += 4;
        nd.Ut = read_matrix(r, at);
        nd.Vt = read_matrix(r, at);
        nd.Dt = read_matrix(r, at);
      }
    });
}

void UlvFactorization::widen_generators(const LowRankTerm &extra)
{
  const ClusterTree &tree = m_K.tree();
  const int p = extra.p, n = tree.num_points();
  if (extra.Y.size() != 3ull * n * p || extra.Z.size() != 3ull * n * p) throw std::invalid_argument("ULV: the low-rank term has the wrong size");
  m_p = p;
  m_wide.assign(tree.num_clusters(), HssCluster{});
  auto identity_block = [p](DenseMatrix &M, int r0, int c0) {
    for (int i = 0; i < p; ++i) M(r0 + i, c0 + i) = 1.0;
  };
  for (int c = 0; c < tree.num_clusters(); ++c) {
    if (!m_K.holds(c)) continue;
    const Cluster &cl = tree.cluster(c);
    const HssCluster &h = m_K.cluster(c);
    HssCluster &wd = m_wide[c];
    if (cl.left < 0) {
      // Leaf: U gains Y's rows, V gains Z's rows (V's row layout is the pattern's: 3 per node).
      // A leaf that is the root has no bases (h.U is empty) but still carries Y and Z.
      wd.U = DenseMatrix(3 * cl.size(), h.U.n + p);
      wd.V = DenseMatrix(3 * cl.size(), h.V.n + p);
      put(wd.U, 0, 0, h.U);
      for (int k = 0; k < cl.size(); ++k) {
        const int node = tree.perm()[cl.begin + k];
        for (int a = 0; a < 3; ++a)
          for (int j = 0; j < p; ++j) {
            wd.U(3 * k + a, h.U.n + j) = extra.Y[(3 * static_cast<std::size_t>(node) + a) * p + j];
            wd.V(3 * k + a, h.V.n + j) = extra.Z[(3 * static_cast<std::size_t>(node) + a) * p + j];
          }
      }
      continue;
    }
    // the children's ranks from their skeletons (a child may be another rank's)
    const int kra = static_cast<int>(m_K.cluster(cl.left).row_skel.size()), krb = static_cast<int>(m_K.cluster(cl.right).row_skel.size());
    const int kca = static_cast<int>(m_K.cluster(cl.left).col_skel.size()), kcb = static_cast<int>(m_K.cluster(cl.right).col_skel.size());
    wd.B12 = DenseMatrix(kra + p, kcb + p);
    put(wd.B12, 0, 0, h.B12);
    identity_block(wd.B12, kra, kcb);
    wd.B21 = DenseMatrix(krb + p, kca + p);
    put(wd.B21, 0, 0, h.B21);
    identity_block(wd.B21, krb, kca);
    if (c == 0) continue;
    // Transfers: [U_a-part 0; 0 I; U_b-part 0; 0 I], so the parent's extra basis is Y on both halves.
    wd.U = DenseMatrix(kra + krb + 2 * p, h.U.n + p);
    put(wd.U, 0, 0, sub(h.U, 0, kra, 0, h.U.n));
    identity_block(wd.U, kra, h.U.n);
    put(wd.U, kra + p, 0, sub(h.U, kra, krb, 0, h.U.n));
    identity_block(wd.U, kra + p + krb, h.U.n);
    wd.V = DenseMatrix(kca + kcb + 2 * p, h.V.n + p);
    put(wd.V, 0, 0, sub(h.V, 0, kca, 0, h.V.n));
    identity_block(wd.V, kca, h.V.n);
    put(wd.V, kca + p, 0, sub(h.V, kca, kcb, 0, h.V.n));
    identity_block(wd.V, kca + p + kcb, h.V.n);
  }
}

void UlvFactorization::merge_children(int c, DenseMatrix &D, DenseMatrix &U, DenseMatrix &V)
{
  const Cluster &cl = m_K.tree().cluster(c);
  HssCluster h;
  h.U = U_of(c);
  h.V = V_of(c);
  const DenseMatrix &B12 = B12_of(c), &B21 = B21_of(c);
  Node &a = m_nodes[cl.left], &b = m_nodes[cl.right];
  const int ra = reduced_size(cl.left), rb = reduced_size(cl.right);
  const int kra = a.Ut.n, kca = a.Vt.n;
  D = DenseMatrix(ra + rb, ra + rb);
  put(D, 0, 0, a.Dt);
  put(D, ra, ra, b.Dt);
  put(D, 0, ra, product(product(a.Ut, 'N', B12, 'N'), 'N', b.Vt, 'T'));
  put(D, ra, 0, product(product(b.Ut, 'N', B21, 'N'), 'N', a.Vt, 'T'));
  U = DenseMatrix(ra + rb, h.U.n);
  V = DenseMatrix(ra + rb, h.V.n);
  if (c != 0) {
    put(U, 0, 0, product(a.Ut, 'N', sub(h.U, 0, kra, 0, h.U.n), 'N'));
    put(U, ra, 0, product(b.Ut, 'N', sub(h.U, kra, h.U.m - kra, 0, h.U.n), 'N'));
    put(V, 0, 0, product(a.Vt, 'N', sub(h.V, 0, kca, 0, h.V.n), 'N'));
    put(V, ra, 0, product(b.Vt, 'N', sub(h.V, kca, h.V.m - kca, 0, h.V.n), 'N'));
  }
  a.Dt = DenseMatrix();
  b.Dt = DenseMatrix();
  a.Vt = DenseMatrix();
  b.Vt = DenseMatrix();
}

void UlvFactorization::factor_cluster(int c, DenseMatrix D, DenseMatrix U, DenseMatrix V)
{
  Node &nd = m_nodes[c];
  const int m = D.m, kr = U.n, kc = V.n;
  nd.m = m;
  nd.kr = kr;
  if (m <= kr) { // nothing decouples: hand everything up
    nd.Dt = std::move(D);
    nd.Ut = std::move(U);
    nd.Vt = std::move(V);
    return;
  }
  nd.eliminated = true;
  const int ne = m - kr;
  // Û = Q [R; 0]: the last m − kr rows of Qᵀ A no longer see the rest of the matrix.
  nd.qr = std::move(U);
  nd.tau_q.assign(std::max(1, kr), 0.0);
  if (lapack::geqrf(m, kr, nd.qr.data(), nd.qr.ld(), nd.tau_q.data()) != 0) throw HssBreakdown("HSS factorization: dgeqrf failed");
  nd.Ut = DenseMatrix(kr, kr);
  for (int j = 0; j < kr; ++j)
    for (int i = 0; i <= j; ++i) nd.Ut(i, j) = nd.qr(i, j);
  lapack::ormqr('L', 'T', m, m, kr, nd.qr.data(), nd.qr.ld(), nd.tau_q.data(), D.data(), D.ld());
  // Decoupled rows E = [L 0] P (LQ); y = P x, and the first m − kr entries of y are eliminated.
  nd.lq = sub(D, kr, ne, 0, m);
  nd.tau_p.assign(ne, 0.0);
  if (lapack::gelqf(ne, m, nd.lq.data(), nd.lq.ld(), nd.tau_p.data()) != 0) throw HssBreakdown("HSS factorization: dgelqf failed");
  double lmax = 0, lmin = HUGE_VAL;
  for (int i = 0; i < ne; ++i) {
    lmax = std::max(lmax, std::abs(nd.lq(i, i)));
    lmin = std::min(lmin, std::abs(nd.lq(i, i)));
  }
  if (!(lmin > 1e-14 * std::max(lmax, max_abs(D))))
    throw HssBreakdown("HSS factorization broke down: a pivot block of cluster " + std::to_string(c) + " is singular to working precision");
  DenseMatrix top = sub(D, 0, kr, 0, m);
  lapack::ormlq('R', 'T', kr, m, ne, nd.lq.data(), nd.lq.ld(), nd.tau_p.data(), top.data(), top.ld());
  nd.Xce = sub(top, 0, kr, 0, ne);
  nd.Dt = sub(top, 0, kr, ne, kr);
  lapack::ormlq('L', 'N', m, kc, ne, nd.lq.data(), nd.lq.ld(), nd.tau_p.data(), V.data(), V.ld());
  nd.Ve = sub(V, 0, ne, 0, kc);
  nd.Vt = sub(V, ne, kr, 0, kc);
}

/// Per cluster, during a solve: reduced right-hand sides bt, the known parts z = V_τᵀ x_τ, the
/// eliminated unknowns ye, and the kept unknowns xk handed down.
struct UlvFactorization::SolveWork {
  std::vector<std::vector<double>> bt, z, ye, xk;
  explicit SolveWork(int nc) : bt(nc), z(nc), ye(nc), xk(nc) {}
};

void UlvFactorization::solve(double *b) const
{
  PhaseScope phase(Phase::Solve);
  const ClusterTree &tree = m_K.tree();
  const int nc = tree.num_clusters();
  SolveWork w(0);
  const auto up = [&](const std::vector<std::vector<int>> &levels) {
    for (const std::vector<int> &level : levels) for_each_cluster(level, [&](int c) { solve_up(c, b, w); });
  };
  const auto down = [&](const std::vector<std::vector<int>> &levels) {
    for (const std::vector<int> &level : levels) for_each_cluster(level, [&](int c) { solve_down(c, b, w); });
  };
  // Forward within the parts; their roots' reduced right-hand sides and known parts to rank 0.
  std::vector<DenseMatrix> msg;
  collectively(m_comm, [&] {
    w = SolveWork(nc);
    msg.resize(nc);
    up(m_passes.up);
    for (const std::vector<int> &to : m_up.sends())
      for (int c : to) {
        msg[c] = DenseMatrix(static_cast<int>(w.bt[c].size() + w.z[c].size()), 1);
        std::copy(w.bt[c].begin(), w.bt[c].end(), msg[c].a.begin());
        std::copy(w.z[c].begin(), w.z[c].end(), msg[c].a.begin() + static_cast<long>(w.bt[c].size()));
      }
  });
  std::optional<PhaseScope> top;
  if (tree.num_parts() > 1) top.emplace(Phase::SolveTop);
  m_up.run(msg, 1, false, [this](int c) { return reduced_size(c) + col_rank(c); });
  // The top (rank 0), down to the parts' roots, whose unknowns go back.
  collectively(m_comm, [&] {
    for (const std::vector<int> &from : m_up.receives())
      for (int c : from) {
        const int r = reduced_size(c);
        w.bt[c].assign(msg[c].a.begin(), msg[c].a.begin() + r);
        w.z[c].assign(msg[c].a.begin() + r, msg[c].a.end());
      }
    up(m_passes.top_up);
    down(m_passes.top_down);
    for (const std::vector<int> &to : m_down.sends())
      for (int c : to) {
        msg[c] = DenseMatrix(static_cast<int>(w.xk[c].size()), 1);
        std::copy(w.xk[c].begin(), w.xk[c].end(), msg[c].a.begin());
      }
  });
  m_down.run(msg, 1, false, [this](int c) { return reduced_size(c); });
  top.reset();
  // Backward within the parts.
  collectively(m_comm, [&] {
    for (const std::vector<int> &from : m_down.receives())
      for (int c : from) w.xk[c] = msg[c].a;
    down(m_passes.down);
  });
}

/// Upward: eliminate, carrying the reduced right-hand sides and the known part V_τᵀ x_τ.
void UlvFactorization::solve_up(int c, const double *b, SolveWork &w) const
{
  const Cluster &cl = m_K.tree().cluster(c);
  const Node &nd = m_nodes[c];
  std::vector<double> bh, zin(c != 0 ? col_rank(c) : 0, 0.0);
  if (cl.left < 0) {
    bh.assign(b + 3L * (cl.begin - m_passes.first), b + 3L * (cl.end - m_passes.first));
  } else {
    const DenseMatrix &hV = V_of(c), &B12 = B12_of(c), &B21 = B21_of(c);
    const Node &a = m_nodes[cl.left], &bb = m_nodes[cl.right];
    const int ra = reduced_size(cl.left), rb = reduced_size(cl.right);
    bh.resize(ra + rb);
    std::copy(w.bt[cl.left].begin(), w.bt[cl.left].end(), bh.begin());
    std::copy(w.bt[cl.right].begin(), w.bt[cl.right].end(), bh.begin() + ra);
    std::vector<double> tmp(std::max(B12.m, B21.m));
    lapack::gemv('N', B12.m, B12.n, 1.0, B12.data(), B12.ld(), w.z[cl.right].data(), 0.0, tmp.data());
    lapack::gemv('N', a.Ut.m, a.Ut.n, -1.0, a.Ut.data(), a.Ut.ld(), tmp.data(), 1.0, bh.data());
    lapack::gemv('N', B21.m, B21.n, 1.0, B21.data(), B21.ld(), w.z[cl.left].data(), 0.0, tmp.data());
    lapack::gemv('N', bb.Ut.m, bb.Ut.n, -1.0, bb.Ut.data(), bb.Ut.ld(), tmp.data(), 1.0, bh.data() + ra);
    if (c != 0) { // what the children already know of V_τᵀ x_τ: V_τᵀ [z_a; z_b], by row blocks
      const int ka = static_cast<int>(w.z[cl.left].size()), kb = static_cast<int>(w.z[cl.right].size());
      lapack::gemv('T', ka, hV.n, 1.0, hV.data(), hV.ld(), w.z[cl.left].data(), 0.0, zin.data());
      lapack::gemv('T', kb, hV.n, 1.0, hV.data() + ka, hV.ld(), w.z[cl.right].data(), 1.0, zin.data());
    }
  }
  if (c == 0) {
    if (m_root_lu.m > 0) lapack::getrs('N', m_root_lu.m, 1, m_root_lu.data(), m_root_lu.ld(), m_root_piv.data(), bh.data(), m_root_lu.m);
    w.xk[0] = std::move(bh);
    return;
  }
  if (!nd.eliminated) {
    w.bt[c] = std::move(bh);
    w.z[c] = std::move(zin);
    return;
  }
  const int m = nd.m, kr = nd.kr, ne = m - kr;
  lapack::ormqr('L', 'T', m, 1, kr, nd.qr.data(), nd.qr.ld(), nd.tau_q.data(), bh.data(), m);
  std::vector<double> y(bh.begin() + kr, bh.end());
  lapack::trsm('L', 'L', 'N', 'N', ne, 1, 1.0, nd.lq.data(), nd.lq.ld(), y.data(), ne);
  bh.resize(kr);
  lapack::gemv('N', kr, ne, -1.0, nd.Xce.data(), nd.Xce.ld(), y.data(), 1.0, bh.data());
  lapack::gemv('T', ne, nd.Ve.n, 1.0, nd.Ve.data(), nd.Ve.ld(), y.data(), 1.0, zin.data());
  w.bt[c] = std::move(bh);
  w.z[c] = std::move(zin);
  w.ye[c] = std::move(y);
}

/// Downward: undo the transforms and hand the kept unknowns to the children.
void UlvFactorization::solve_down(int c, double *b, SolveWork &w) const
{
  const Cluster &cl = m_K.tree().cluster(c);
  const Node &nd = m_nodes[c];
  std::vector<double> x;
  if (c != 0 && nd.eliminated) {
    x = w.ye[c];
    x.insert(x.end(), w.xk[c].begin(), w.xk[c].end());
    lapack::ormlq('L', 'T', nd.m, 1, nd.m - nd.kr, nd.lq.data(), nd.lq.ld(), nd.tau_p.data(), x.data(), nd.m);
  } else {
    x = std::move(w.xk[c]);
  }
  if (cl.left < 0) {
    std::copy(x.begin(), x.end(), b + 3L * (cl.begin - m_passes.first));
  } else {
    const int ra = reduced_size(cl.left);
    w.xk[cl.left].assign(x.begin(), x.begin() + ra);
    w.xk[cl.right].assign(x.begin() + ra, x.end());
  }
}

namespace {

template <class Node>
std::size_t node_bytes(const Node &n)
{
  return n.qr.bytes() + n.lq.bytes() + n.Xce.bytes() + n.Ve.bytes() + n.Ut.bytes() + n.Vt.bytes() + n.Dt.bytes() + (n.tau_q.size() + n.tau_p.size()) * sizeof(double);
}

} // namespace

std::size_t UlvFactorization::memory_bytes() const
{
  std::size_t s = m_root_lu.bytes() + m_root_piv.size() * sizeof(int);
  for (const Node &n : m_nodes) s += node_bytes(n);
  for (const HssCluster &h : m_wide) s += h.U.bytes() + h.V.bytes() + h.B12.bytes() + h.B21.bytes();
  return s;
}

std::size_t UlvFactorization::top_bytes() const
{
  std::size_t s = m_root_lu.bytes() + m_root_piv.size() * sizeof(int);
  for (const std::vector<int> &level : m_passes.top_up)
    for (int c : level) s += node_bytes(m_nodes[c]);
  return s;
}

} // namespace hssbem
