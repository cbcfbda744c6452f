// Entries-free truncation of an HSS matrix to a looser tolerance (see truncate.hpp).
//
// Notation, for a cluster τ other than the root, with parent p and sibling s: K_hss is the matrix
// K represents, "outside τ" the columns outside τ's range, S_τ the old row skeleton (k_τ rows),
// Cand_τ the old candidate rows, U_τ the old transfer (|Cand_τ| × k_τ); primes mark the result.
// Rows only; columns are the same with V, the column skeletons and transposed couplings.
//
// 1. Represented block rows. Ufull_τ = U_τ (leaf) or blockdiag(Ufull_a, Ufull_b)·U_τ is the
//    identity on the rows of S_τ, so
//        K_hss(rows of τ, outside τ) = Ufull_τ M_τ,   K_hss(Cand_τ, outside τ) = U_τ M_τ,
//    with M_τ = K_hss(S_τ, outside τ). Outside τ is s plus outside p, and the rows S_τ of
//    Ufull_p are T_τ, the rows of U_p that belong to S_τ (its top k_a rows for the left child):
//        M_τ = [ B_τs Vfull_sᵀ ,  T_τ M_p ].
// 2. Compact factors. Vfull_s = Q_s Rv_s with orthonormal Q_s: bottom-up, Rv_s is the R of
//    [Rv_a V_s(top rows); Rv_b V_s(bottom rows)] (a leaf: of V_s). If M_p = F_p Q_pᵀ, then
//        M_τ = F_τ blockdiag(Q_s, Q_p)ᵀ,   F_τ = [ B_τs Rv_sᵀ ,  T_τ F_p ]
//    top-down (no second block under the root). blockdiag(Q_s, Q_p) has orthonormal columns
//    (disjoint column ranges), so a row ID of M_τ is one of F_τ. F_τ is replaced by the L of its
//    LQ factorization, so it never has more than k_τ columns.
// 3. Truncation, bottom-up. Cand'_τ: the new candidates (a leaf's rows, or S'_a then S'_b).
//    Suppose each child c has a k'_c × k_c matrix E_c with, exactly,
//        K_hss(S'_c, outside c) = E_c M_c.                                         (*)
//    Then K_hss(Cand'_τ, outside τ) = Ũ_τ M_τ with Ũ_τ = U_τ for a leaf and
//        Ũ_τ = [ E_a U_τ(top k_a rows) ; E_b U_τ(bottom k_b rows) ]
//    (the columns outside τ of (*) for a are E_a T_a M_τ). A row ID of X_τ = Ũ_τ F_τ picks rows
//    J of Cand'_τ and W with X_τ ≈ W X_τ(J, :); then S'_τ = Cand'_τ(J), U'_τ = W and (*) holds
//    for τ with E_τ = Ũ_τ(J, :). Only the IDs approximate; errors add up over the levels, as in
//    the compressor.
//    S'_τ need not lie in S_τ: a child may drop a row of S_τ and keep one that the parent then
//    needs instead. Where S'_τ ⊂ S_τ, E_τ is a selection of identity rows.
// 4. Couplings. B'_ab = K_hss(S'_a, C'_b) = E_a B_ab E^colᵀ_b: K's own entries where both new
//    skeletons are subsets of the old ones, and represented entries elsewhere.
//
// Forced entries (rigid-body terms) are kept, first, and, as in the skeletonizer's
// select_skeleton, interpolate nothing: the ID runs over the free candidates only. Nothing is
// lost by that, since K's U_τ never interpolates a free row from a forced one. A row forced in p
// (its rigid-body term reaches outside p) is forced in the child that holds it as well (it
// reaches outside the child too: Skeletonizer::row_forced), so it is among the new candidates;
// this is checked. Its rows of Ũ and E are unit rows, so its coupling entries stay exact.
#include "hssbem/hss/truncate.hpp"

#include "hssbem/compress/share_skeletons.hpp"
#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/cluster_exchange.hpp"
#include "hssbem/core/dense_ops.hpp"
#include "hssbem/core/interpolative.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/core/fault.hpp"
#include "hssbem/core/phase.hpp"
#include "hssbem/hss/hss_distributed.hpp"

#include <algorithm>
#include <cstddef>
#include <functional>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace hssbem {

namespace {

using Size = std::size_t;
using namespace dense; // row_block, rows_at, hcat, vcat, product

/// R with A = Q R, Q with orthonormal columns; A itself when it has no more rows than columns.
DenseMatrix r_factor(DenseMatrix A)
{
  if (A.m <= A.n) return A;
  std::vector<double> tau(static_cast<Size>(A.n));
  if (A.n > 0 && lapack::geqrf(A.m, A.n, A.data(), A.ld(), tau.data()) != 0) throw std::runtime_error("HSS truncation: dgeqrf failed");
  DenseMatrix R(A.n, A.n);
  for (int j = 0; j < A.n; ++j)
    for (int i = 0; i <= j; ++i) R(i, j) = A(i, j);
  return R;
}

/// L with A = L Qᵀ, Q with orthonormal columns; A itself when it has no more columns than rows.
DenseMatrix l_factor(DenseMatrix A)
{
  if (A.n <= A.m) return A;
  std::vector<double> tau(static_cast<Size>(A.m));
  if (A.m > 0 && lapack::gelqf(A.m, A.n, A.data(), A.ld(), tau.data()) != 0) throw std::runtime_error("HSS truncation: dgelqf failed");
  DenseMatrix L(A.m, A.m);
  for (int j = 0; j < A.m; ++j)
    for (int i = j; i < A.m; ++i) L(i, j) = A(i, j);
  return L;
}

/// A new skeleton: positions among the candidates (forced first) and the interpolation matrix.
struct Selection {
  std::vector<int> local;
  DenseMatrix W; ///< candidates × skeleton, the identity on the skeleton rows
};

/// Row ID of X (candidates × features) over its free rows; the forced rows (positions, in
/// order) are kept first and interpolate nothing, as in the skeletonizer's select_skeleton.
/// The rank cap counts the forced rows.
Selection select_rows(const DenseMatrix &X, const std::vector<int> &forced, IdOptions id)
{
  std::vector<char> is_forced(static_cast<Size>(X.m), 0);
  for (int q : forced) is_forced[q] = 1;
  std::vector<int> free_idx;
  for (int q = 0; q < X.m; ++q)
    if (!is_forced[q]) free_idx.push_back(q);
  const int nf = static_cast<int>(forced.size());
  if (id.max_rank >= 0) id.max_rank = std::max(0, id.max_rank - nf);
  const DenseMatrix Xf = l_factor(rows_at(X, free_idx)); // same row relations, at most as many columns as rows
  const ColumnId cid = row_id(Xf.data(), Xf.m, Xf.n, Xf.ld(), id);
  const int k = cid.rank();
  Selection s{forced, DenseMatrix(X.m, nf + k)};
  for (int t = 0; t < nf; ++t) s.W(forced[t], t) = 1.0;
  for (int t = 0; t < k; ++t) {
    s.local.push_back(free_idx[cid.skeleton[t]]);
    s.W(free_idx[cid.skeleton[t]], nf + t) = 1.0;
  }
  for (Size j = 0; j < cid.redundant.size(); ++j)
    for (int t = 0; t < k; ++t) s.W(free_idx[cid.redundant[j]], nf + t) = cid.T[t + j * static_cast<Size>(k)];
  return s;
}

/// Positions in cand of the first `nforced` entries of skel.
std::vector<int> forced_positions(const std::vector<int> &skel, int nforced, const std::vector<int> &cand)
{
  std::vector<int> pos;
  for (int t = 0; t < nforced; ++t) {
    const auto it = std::find(cand.begin(), cand.end(), skel[t]);
    if (it == cand.end()) throw std::logic_error("HSS truncation: a forced skeleton entry is missing from the new candidates");
    pos.push_back(static_cast<int>(it - cand.begin()));
  }
  return pos;
}

/// One side of the generators: rows (U) or columns (V).
struct SideRef {
  std::vector<int> HssCluster::*skel;
  DenseMatrix HssCluster::*basis;
  int HssCluster::*forced;
};
const SideRef k_sides[2] = {{&HssCluster::row_skel, &HssCluster::U, &HssCluster::row_forced},
                            {&HssCluster::col_skel, &HssCluster::V, &HssCluster::col_forced}};

/// Per cluster and side: the formulas' R (Ru or Rv), F (F or G) and E.
struct SideWork {
  DenseMatrix R, F, E;
};

/// Every forced entry of an inner cluster is a forced entry of one of its children (the
/// compressor forces by "the rigid-body term reaches outside", which is inherited downwards).
void check_forced_nested(const HssMatrix &K)
{
  const ClusterTree &tree = K.tree();
  for (int c = 1; c < tree.num_clusters(); ++c) {
    const Cluster &cl = tree.cluster(c);
    if (cl.left < 0) continue;
    for (const SideRef &side : k_sides) {
      const HssCluster &h = K.cluster(c), &a = K.cluster(cl.left), &b = K.cluster(cl.right);
      const auto forced_in = [&side](const HssCluster &child, int v) {
        const auto &s = child.*side.skel;
        return std::find(s.begin(), s.begin() + child.*side.forced, v) != s.begin() + child.*side.forced;
      };
      for (int t = 0; t < h.*side.forced; ++t)
        if (!forced_in(a, (h.*side.skel)[t]) && !forced_in(b, (h.*side.skel)[t]))
          throw std::logic_error("HSS truncation: cluster " + std::to_string(c) + " has a forced skeleton entry its children do not force");
    }
  }
}

class Truncator {
public:
  Truncator(const HssMatrix &K, HssMatrix &out, const IdOptions &id, const RankComm &comm)
    : m_K(K), m_out(out), m_tree(K.tree()), m_id(id), m_comm(comm), m_passes(K, comm)
  {
    for (auto &w : m_work) w.resize(static_cast<Size>(m_tree.num_clusters()));
  }

  /// The four steps, each within the parts first and then above them (rank 0), the parts' roots'
  /// factors crossing between (collective).
  void run()
  {
    // Step 2, bottom-up: R factors (not the root's).
    collectively(m_comm, [&] { on_levels(m_passes.up, &Truncator::basis_factor); });
    to_parents([this](int c, std::vector<double> &r) { append_matrix(r, work(0, c).R), append_matrix(r, work(1, c).R); },
               [this](int c, const std::vector<double> &r, std::size_t &at) { work(0, c).R = read_matrix(r, at), work(1, c).R = read_matrix(r, at); });
    collectively(m_comm, [&] { on_levels(m_passes.top_up, &Truncator::basis_factor); });
    // Step 2, top-down: each parent makes its children's F.
    collectively(m_comm, [&] { children_of(m_passes.top_down, &Truncator::compact_factor); });
    to_children([this](int c, std::vector<double> &r) { append_matrix(r, work(0, c).F), append_matrix(r, work(1, c).F); },
                [this](int c, const std::vector<double> &r, std::size_t &at) { work(0, c).F = read_matrix(r, at), work(1, c).F = read_matrix(r, at); });
    collectively(m_comm, [&] { children_of(m_passes.down, &Truncator::compact_factor); });
    // Step 3, bottom-up: new skeletons, transfers and E.
    collectively(m_comm, [&] {
      fault_point("HssTruncate");
      on_levels(m_passes.up, &Truncator::truncate);
    });
    to_parents([this](int c, std::vector<double> &r) { pack_truncated(c, r); }, [this](int c, const std::vector<double> &r, std::size_t &at) { unpack_truncated(c, r, at); });
    collectively(m_comm, [&] { on_levels(m_passes.top_up, &Truncator::truncate); });
    // Step 4: couplings and leaf blocks of the clusters held here; every skeleton to every rank.
    collectively(m_comm, [&] {
      for (int c = 0; c < m_tree.num_clusters(); ++c)
        if (m_K.holds(c)) m_held.push_back(c);
      for_each_cluster(m_held, [this](int c) { couple_or_copy(c); });
    });
    if (m_comm.size() > 1) {
      std::vector<int> all;
      std::vector<NestedBasis *> bases;
      collectively(m_comm, [&] {
        all.resize(static_cast<Size>(m_tree.num_clusters()));
        std::iota(all.begin(), all.end(), 0);
        bases.resize(all.size());
        for (int c : all) bases[static_cast<Size>(c)] = &m_out.cluster(c);
      });
      for (bool columns : {false, true}) share_skeletons(all, bases, [this](int c) { return m_K.holds(c); }, m_comm, columns);
    }
  }

private:
  SideWork &work(int side, int c) { return m_work[side][static_cast<Size>(c)]; }
  int old_rank(int side, int c) const { return static_cast<int>((m_K.cluster(c).*k_sides[side].skel).size()); }

  /// step(c, rows) then step(c, columns) for the clusters of each level (not the root), on
  /// parallel threads when there are enough of them.
  void on_levels(const std::vector<std::vector<int>> &levels, void (Truncator::*step)(int c, int side))
  {
    for (const std::vector<int> &level : levels)
      for_each_cluster(level, [this, step](int c) {
        if (c == 0) return;
        (this->*step)(c, 0);
        (this->*step)(c, 1);
      });
  }

  /// The same for the children of the inner clusters of each level.
  void children_of(const std::vector<std::vector<int>> &levels, void (Truncator::*step)(int c, int side))
  {
    for (const std::vector<int> &level : levels)
      for_each_cluster(level, [this, step](int p) {
        const Cluster &pc = m_tree.cluster(p);
        if (pc.left < 0) return;
        for (int c : {pc.left, pc.right}) {
          (this->*step)(c, 0);
          (this->*step)(c, 1);
        }
      });
  }

  using Pack = std::function<void(int c, std::vector<double> &record)>;
  using Unpack = std::function<void(int c, const std::vector<double> &record, std::size_t &at)>;

  /// Records of the clusters held here whose parents another rank holds, to that rank (collective).
  void to_parents(const Pack &pack, const Unpack &unpack) { move_records(false, pack, unpack); }

  /// Records of the children that another rank holds of the clusters held here, to that rank
  /// (collective).
  void to_children(const Pack &pack, const Unpack &unpack) { move_records(true, pack, unpack); }

  /// For each pair (parent held here, child held elsewhere) with down, or (child held here,
  /// parent held elsewhere) without, pack(child) goes to the other rank, which unpacks it.
  void move_records(bool down, const Pack &pack, const Unpack &unpack)
  {
    exchange_records(
      m_comm, "the HSS truncation's records",
      [&](std::vector<std::vector<double>> &send) {
      for (int c = 1; c < m_tree.num_clusters(); ++c) {
        const int parent = m_tree.cluster(c).parent;
        const int here = down ? parent : c, there = down ? c : parent;
        if (!m_K.holds(here) || m_K.holds(there)) continue;
        std::vector<double> &r = send[m_K.owner(there)];
        r.push_back(c);
        pack(c, r);
      }
      },
      [&](const std::vector<std::vector<double>> &recv) {
      for (const std::vector<double> &r : recv)
        for (std::size_t at = 0; at < r.size();) {
          const int c = static_cast<int>(r[at++]);
          if (c < 1 || c >= m_tree.num_clusters()) throw std::logic_error("HSS truncation: a corrupt record from another rank");
          unpack(c, r, at);
        }
      });
  }

  /// What the parent of a part's root needs of it after step 3: E and the new skeletons.
  void pack_truncated(int c, std::vector<double> &r)
  {
    for (int side = 0; side < 2; ++side) {
      append_matrix(r, work(side, c).E);
      const std::vector<int> &skel = m_out.cluster(c).*k_sides[side].skel;
      r.push_back(static_cast<double>(skel.size()));
      r.insert(r.end(), skel.begin(), skel.end());
    }
  }

  void unpack_truncated(int c, const std::vector<double> &r, std::size_t &at)
  {
    for (int side = 0; side < 2; ++side) {
      work(side, c).E = read_matrix(r, at);
      if (at >= r.size()) throw std::logic_error("HSS truncation: a truncated record from another rank");
      const auto k = static_cast<Size>(r[at++]);
      if (at + k > r.size()) throw std::logic_error("HSS truncation: a truncated record from another rank");
      std::vector<int> &skel = m_out.cluster(c).*k_sides[side].skel;
      skel.assign(r.begin() + static_cast<long>(at), r.begin() + static_cast<long>(at + k));
      m_out.cluster(c).*k_sides[side].forced = m_K.cluster(c).*k_sides[side].forced;
      at += k;
    }
  }

  /// Step 2: the R factor of c's full basis (bottom-up).
  void basis_factor(int c, int side)
  {
    const Cluster &cl = m_tree.cluster(c);
    const DenseMatrix &W = m_K.cluster(c).*k_sides[side].basis;
    if (cl.left < 0) {
      work(side, c).R = r_factor(W);
      return;
    }
    const int ka = old_rank(side, cl.left);
    const DenseMatrix top = product(work(side, cl.left).R, 'N', row_block(W, 0, ka), 'N');
    const DenseMatrix bottom = product(work(side, cl.right).R, 'N', row_block(W, ka, W.m - ka), 'N');
    work(side, c).R = r_factor(vcat(top, bottom));
  }

  /// Step 2: F_c = [B_cs R_sᵀ, T_c F_p] (rows; columns with B_scᵀ and the sibling's row R), top-down.
  void compact_factor(int c, int side)
  {
    const int p = m_tree.cluster(c).parent;
    const Cluster &pc = m_tree.cluster(p);
    const bool left = pc.left == c;
    const HssCluster &hp = m_K.cluster(p);
    const DenseMatrix &B = left == (side == 0) ? hp.B12 : hp.B21;
    DenseMatrix F = product(B, side == 0 ? 'N' : 'T', work(1 - side, left ? pc.right : pc.left).R, 'T');
    if (p != 0) {
      const DenseMatrix T = row_block(hp.*k_sides[side].basis, left ? 0 : old_rank(side, pc.left), old_rank(side, c));
      F = hcat(F, product(T, 'N', work(side, p).F, 'N'));
    }
    work(side, c).F = l_factor(std::move(F));
  }

  /// Step 3: c's new skeleton, transfer matrix and E (bottom-up).
  void truncate(int c, int side)
  {
    const SideRef &ref = k_sides[side];
    const Cluster &cl = m_tree.cluster(c);
    const HssCluster &old = m_K.cluster(c);
    const DenseMatrix &W = old.*ref.basis;
    DenseMatrix Ut = W;
    if (cl.left >= 0) {
      const int ka = old_rank(side, cl.left);
      Ut = vcat(product(work(side, cl.left).E, 'N', row_block(W, 0, ka), 'N'),
                product(work(side, cl.right).E, 'N', row_block(W, ka, W.m - ka), 'N'));
    }
    const std::vector<int> cand = side == 0 ? m_out.candidate_rows(c) : m_out.candidate_cols(c);
    const std::vector<int> forced = forced_positions(old.*ref.skel, old.*ref.forced, cand);
    Selection sel = select_rows(product(Ut, 'N', work(side, c).F, 'N'), forced, m_id);
    HssCluster &h = m_out.cluster(c);
    (h.*ref.skel).clear();
    for (int q : sel.local) (h.*ref.skel).push_back(cand[q]);
    h.*ref.basis = std::move(sel.W);
    h.*ref.forced = old.*ref.forced;
    work(side, c).E = rows_at(Ut, sel.local);
    work(side, c).F = DenseMatrix();
    work(side, c).R = DenseMatrix();
  }

  /// Step 4: couplings E_a B_ab E^colᵀ_b of an inner cluster; a leaf's D is copied.
  void couple_or_copy(int c)
  {
    const Cluster &cl = m_tree.cluster(c);
    const HssCluster &old = m_K.cluster(c);
    HssCluster &h = m_out.cluster(c);
    if (cl.left < 0) {
      h.D = old.D;
      return;
    }
    h.B12 = product(product(work(0, cl.left).E, 'N', old.B12, 'N'), 'N', work(1, cl.right).E, 'T');
    h.B21 = product(product(work(0, cl.right).E, 'N', old.B21, 'N'), 'N', work(1, cl.left).E, 'T');
  }

  const HssMatrix &m_K;
  HssMatrix &m_out;
  const ClusterTree &m_tree;
  IdOptions m_id;
  const RankComm &m_comm;
  HssPasses m_passes;
  std::vector<SideWork> m_work[2];
  std::vector<int> m_held;
};

} // namespace

HssMatrix truncate_hss(const HssMatrix &K, double rel_tol, int max_rank) { return truncate_hss(K, rel_tol, max_rank, SerialComm()); }

HssMatrix truncate_hss(const HssMatrix &K, double rel_tol, int max_rank, const RankComm &comm)
{
  if (!(rel_tol > 0 && rel_tol < 1)) throw std::invalid_argument("HSS truncation: the relative tolerance must lie in (0, 1)");
  if (max_rank == 0) throw std::invalid_argument("HSS truncation: the rank cap must be positive (or negative for none)");
  PhaseScope scope(Phase::Truncation);
  check_forced_nested(K);
  HssMatrix out(K.tree(), K.row_block(), K.col_block()); // copies the tree only
  out.set_owners(K.owners());
  std::vector<double> scales(static_cast<Size>(K.col_block()));
  for (int q = 0; q < K.col_block(); ++q) scales[static_cast<Size>(q)] = K.col_scale(q);
  out.set_col_scales(std::move(scales));
  Truncator(K, out, IdOptions{rel_tol, max_rank < 0 ? -1 : max_rank}, comm).run();
  out.stats() = K.stats();
  out.update_stats();
  return out;
}

} // namespace hssbem
