// The H² matrix distributed over ranks: cluster owners and the product (see h2_distributed.hpp).
#include "hssbem/h2/h2_distributed.hpp"

#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/phase.hpp"
#include "hssbem/core/tree_ownership.hpp"
#include "h2_transfer.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>

namespace hssbem {

using transfer::CandidateRows;
using transfer::interp_n;
using transfer::interp_t;

H2DistributedProduct::H2DistributedProduct(const H2Matrix &K, const RankComm &comm) : m_K(K), m_comm(comm)
{
  const ClusterTree &tree = K.tree();
  const int nc = tree.num_clusters(), me = comm.rank(), P = comm.size();
  const BlockPartition &bp = K.partition();
  std::vector<std::vector<int>> need_low(P), need_vals(P), need_top(P), need_pot(P), need_row_up(P), need_far_t(P);
  collectively(comm, [&] {
    if (K.rank() != me) throw std::logic_error("H2: the matrix belongs to rank " + std::to_string(K.rank()));
    m_above.assign(nc, 0);
    if (P > 1) {
      const std::vector<int> part = cluster_parts(tree);
      for (int c = 0; c < nc; ++c) m_above[c] = part[c] < 0;
      m_first = tree.cluster(tree.part_cluster(me)).begin;
      m_count = tree.cluster(tree.part_cluster(me)).size();
    } else {
      m_first = 0;
      m_count = tree.num_points();
    }
    std::vector<int> up, top_up, top_down, down;
    for (int c = 0; c < nc; ++c) {
      if (!K.holds(c)) continue;
      m_held.push_back(c);
      const bool leaf = tree.is_leaf(c);
      if (leaf) m_leaves.push_back(c);
      (m_above[c] ? top_up : up).push_back(c);
      if (!leaf) (m_above[c] ? top_down : down).push_back(c);
    }
    m_up = clusters_by_level(tree, up, true);
    m_top_up = clusters_by_level(tree, top_up, true);
    m_top_down = clusters_by_level(tree, top_down, false);
    m_down = clusters_by_level(tree, down, false);
    // What this rank needs from the others.
    for (int a : m_held) {
      for (int b : bp.far[a])
        if (!K.holds(b)) (m_above[b] ? need_top : need_low)[K.owner(b)].push_back(b);
      const Cluster &ca = tree.cluster(a);
      if (m_above[a] && ca.left >= 0 && K.col_interpolation(a).rank() > 0) // its moments need its children's
        for (int ch : {ca.left, ca.right})
          if (!K.holds(ch)) need_low[K.owner(ch)].push_back(ch);
      if (ca.left < 0)
        for (int b : bp.near[a])
          if (!K.holds(b)) need_vals[K.owner(b)].push_back(b);
      const int parent = ca.parent;
      if (parent >= 0 && !K.holds(parent)) need_pot[K.owner(parent)].push_back(a);
      if (m_above[a] && ca.left >= 0 && K.row_interpolation(a).rank() > 0) // the transposed pass's row moments
        for (int ch : {ca.left, ca.right})
          if (!K.holds(ch)) need_row_up[K.owner(ch)].push_back(ch);
    }
    // The transposed far blocks of other ranks' clusters whose column clusters this rank holds.
    for (int a = 0; a < nc; ++a) {
      if (K.holds(a)) continue;
      for (int b : bp.far[a])
        if (K.holds(b)) need_far_t[K.owner(a)].push_back(b);
    }
    for (std::vector<int> &list : need_far_t) {
      std::sort(list.begin(), list.end());
      list.erase(std::unique(list.begin(), list.end()), list.end());
    }
  });
  m_low = ClusterExchange(comm, std::move(need_low));
  m_vals = ClusterExchange(comm, std::move(need_vals));
  m_top = ClusterExchange(comm, std::move(need_top));
  m_pot = ClusterExchange(comm, std::move(need_pot));
  m_row_up = ClusterExchange(comm, std::move(need_row_up));
  m_far_t = ClusterExchange(comm, std::move(need_far_t));
  collectively(comm, [&] {
    for (const auto &list : m_vals.sends()) m_boundary.insert(m_boundary.end(), list.begin(), list.end());
    std::sort(m_boundary.begin(), m_boundary.end());
    m_boundary.erase(std::unique(m_boundary.begin(), m_boundary.end()), m_boundary.end());
  });
  // Traffic of one product with one column.
  for (int q = 0; q < P; ++q) {
    long long values = 0;
    for (int c : m_low.sends()[q]) values += static_cast<long long>(K.col_skeleton(c).size());
    for (int c : m_top.sends()[q]) values += static_cast<long long>(K.col_skeleton(c).size());
    for (int c : m_vals.sends()[q]) values += static_cast<long long>(K.col_block()) * tree.cluster(c).size();
    for (int c : m_pot.sends()[q]) values += static_cast<long long>(K.row_skeleton(c).size());
    m_values_sent += values;
    m_messages_sent += !m_low.sends()[q].empty() + !m_top.sends()[q].empty() + !m_vals.sends()[q].empty() + !m_pot.sends()[q].empty();
  }
}

namespace {

/// The passes over a distributed matrix's clusters that the product and the far-field passes
/// share: upward (moments through one side's bases) and downward (potentials through them).
struct Passes {
  const H2Matrix &K;
  int first, nrhs;
  bool rows; ///< the row bases (U) and row_block(), else the column bases (V) and col_block()
  const StoredInterpolation &basis(int c) const { return rows ? K.row_interpolation(c) : K.col_interpolation(c); }
  int block() const { return rows ? K.row_block() : K.col_block(); }
  /// Moments m[c] = Bᵀ x over the clusters of `levels` (deepest first), x this rank's points.
  void upward(const std::vector<std::vector<int>> &levels, const double *X, int ldx, std::vector<DenseMatrix> &m) const
  {
    const ClusterTree &tree = K.tree();
    for (const std::vector<int> &level : levels)
      for_each_cluster(level, [&](int c) {
        const Cluster &cl = tree.cluster(c);
        const StoredInterpolation &B = basis(c);
        m[c] = DenseMatrix(B.rank(), nrhs);
        if (B.rank() == 0) return;
        CandidateRows<const double> x;
        if (cl.left < 0) x.base = X + static_cast<long>(block()) * (cl.begin - first), x.ld = ldx;
        else x.a = &m[cl.left], x.b = &m[cl.right];
        std::vector<double> buf;
        interp_t(B, x, nrhs, m[c].data(), m[c].ld(), buf);
      });
  }
  /// Potentials carried from each cluster of `levels` (top first) to its children; a child held
  /// by another rank gets a block of its own to send there.
  void downward(const std::vector<std::vector<int>> &levels, std::vector<DenseMatrix> &pot, const std::function<int(int)> &size) const
  {
    const ClusterTree &tree = K.tree();
    for (const std::vector<int> &level : levels)
      for_each_cluster(level, [&](int c) {
        const Cluster &cl = tree.cluster(c);
        for (int ch : {cl.left, cl.right})
          if (pot[ch].m != size(ch) || pot[ch].n != nrhs) pot[ch] = DenseMatrix(size(ch), nrhs); // another rank's child
        CandidateRows<double> y;
        y.a = &pot[cl.left], y.b = &pot[cl.right];
        std::vector<double> buf;
        interp_n(basis(c), pot[c].data(), pot[c].ld(), nrhs, y, buf);
      });
  }
};

} // namespace

void H2DistributedProduct::far_potentials(const double *X, int ldx, int nrhs, std::vector<DenseMatrix> &yh, std::vector<DenseMatrix> *xv) const
{
  const H2Matrix &K = m_K;
  const ClusterTree &tree = K.tree();
  const int nc = tree.num_clusters(), w = K.col_block();
  std::vector<DenseMatrix> xh;
  const auto moments = [&](int c) { return static_cast<int>(K.col_skeleton(c).size()); };
  const auto potentials = [&](int c) { return static_cast<int>(K.row_skeleton(c).size()); };
  const auto values = [&](int c) { return w * tree.cluster(c).size(); };
  const Passes up{K, m_first, nrhs, false}, down{K, m_first, nrhs, true};

  // 1–2. Moments below the parts; moments and boundary values to the ranks that read them.
  collectively(m_comm, [&] {
    xh.resize(nc);
    yh.assign(nc, DenseMatrix());
    if (xv) xv->resize(nc);
    up.upward(m_up, X, ldx, xh);
    if (!xv) return;
    for (int c : m_boundary) {
      const Cluster &cl = tree.cluster(c);
      (*xv)[c] = DenseMatrix(values(c), nrhs);
      for (int k = 0; k < nrhs; ++k)
        std::copy_n(X + static_cast<long>(w) * (cl.begin - m_first) + static_cast<long>(k) * ldx, values(c), (*xv)[c].data() + static_cast<long>(k) * values(c));
    }
  });
  m_low.run(xh, nrhs, false, moments);
  if (xv) m_vals.run(*xv, nrhs, false, values);
  // 3. Above the parts (rank 0), and the top moments other ranks' far blocks read.
  collectively(m_comm, [&] { up.upward(m_top_up, X, ldx, xh); });
  m_top.run(xh, nrhs, false, moments);
  // 4–5. Far blocks; downward through the top, the parts' shares to their ranks.
  collectively(m_comm, [&] {
    for (int a : m_held) yh[a] = DenseMatrix(potentials(a), nrhs);
    for_each_cluster(m_held, [&](int a) {
      std::vector<double> buf;
      for (const H2Block &B : K.far_blocks(a)) B.multiply_add(xh[B.col_cluster].data(), xh[B.col_cluster].ld(), yh[a].data(), yh[a].ld(), nrhs, buf);
    });
    down.downward(m_top_down, yh, potentials);
  });
  m_pot.run(yh, nrhs, true, potentials);
}

void H2DistributedProduct::apply(const double *X, int ldx, double *Y, int ldy, int nrhs) const
{
  PhaseScope phase(Phase::H2Matvec);
  const H2Matrix &K = m_K;
  const ClusterTree &tree = K.tree();
  const int w = K.col_block(), rb = K.row_block();
  std::vector<DenseMatrix> yh, xv;
  far_potentials(X, ldx, nrhs, yh, &xv);
  // 5. Downward through the parts, then the leaves.
  collectively(m_comm, [&] {
    const Passes down{K, m_first, nrhs, true};
    down.downward(m_down, yh, [&](int c) { return static_cast<int>(K.row_skeleton(c).size()); });
    for_each_cluster(m_leaves, [&](int c) {
      const Cluster &cl = tree.cluster(c);
      double *y = Y + static_cast<long>(rb) * (cl.begin - m_first);
      const int m = rb * cl.size();
      for (int k = 0; k < nrhs; ++k) std::fill(y + static_cast<long>(k) * ldy, y + static_cast<long>(k) * ldy + m, 0.0);
      std::vector<double> buf;
      for (const H2Block &B : K.near_blocks(c)) {
        const int b = B.col_cluster;
        if (K.holds(b)) B.multiply_add(X + static_cast<long>(w) * (tree.cluster(b).begin - m_first), ldx, y, ldy, nrhs, buf);
        else B.multiply_add(xv[b].data(), xv[b].ld(), y, ldy, nrhs, buf);
      }
      CandidateRows<double> rows;
      rows.base = y, rows.ld = ldy;
      interp_n(K.row_interpolation(c), yh[c].data(), yh[c].ld(), nrhs, rows, buf);
    });
  });
}

std::vector<DenseMatrix> H2DistributedProduct::skeleton_far_field(const double *X, int ldx, int nrhs) const
{
  std::vector<DenseMatrix> yh;
  far_potentials(X, ldx, nrhs, yh, nullptr);
  collectively(m_comm, [&] {
    const Passes down{m_K, m_first, nrhs, true};
    down.downward(m_down, yh, [&](int c) { return static_cast<int>(m_K.row_skeleton(c).size()); });
  });
  for (int c = 0; c < m_K.tree().num_clusters(); ++c) // frees only: nothing to fail
    if (!m_K.holds(c)) yh[c] = DenseMatrix();
  return yh;
}

std::vector<DenseMatrix> H2DistributedProduct::skeleton_far_field_transposed(const double *Y, int ldy, int nrhs) const
{
  const H2Matrix &K = m_K;
  const int nc = K.tree().num_clusters();
  const auto row_moments = [&](int c) { return static_cast<int>(K.row_skeleton(c).size()); };
  const auto col_potentials = [&](int c) { return static_cast<int>(K.col_skeleton(c).size()); };
  const Passes up{K, m_first, nrhs, true}, down{K, m_first, nrhs, false};
  std::vector<DenseMatrix> yh, xh;
  // Row moments up through the parts, the parts' roots' to rank 0, up through the top.
  collectively(m_comm, [&] {
    yh.resize(nc);
    xh.resize(nc);
    up.upward(m_up, Y, ldy, yh);
  });
  m_row_up.run(yh, nrhs, false, row_moments);
  // Far blocks transposed, summed per column cluster: this rank's own, and its shares of the
  // other ranks' column clusters (sent to their owners, which add them up).
  std::vector<int> targets;
  collectively(m_comm, [&] {
    up.upward(m_top_up, Y, ldy, yh);
    std::vector<std::vector<std::pair<int, int>>> by_col(nc);
    for (int a : m_held)
      for (std::size_t i = 0; i < K.far_blocks(a).size(); ++i) by_col[K.far_blocks(a)[i].col_cluster].push_back({a, static_cast<int>(i)});
    for (int b = 0; b < nc; ++b)
      if (K.holds(b) || !by_col[b].empty()) {
        targets.push_back(b);
        xh[b] = DenseMatrix(col_potentials(b), nrhs);
      }
    for_each_cluster(targets, [&](int b) {
      std::vector<double> buf;
      for (const auto &[a, i] : by_col[b]) K.far_blocks(a)[i].multiply_add_transposed(yh[a].data(), yh[a].ld(), xh[b].data(), xh[b].ld(), nrhs, buf);
    });
  });
  m_far_t.run(xh, nrhs, true, col_potentials);
  // Down through the top (rank 0), the parts' shares to their ranks, down through the parts.
  collectively(m_comm, [&] { down.downward(m_top_down, xh, col_potentials); });
  m_pot.run(xh, nrhs, true, col_potentials);
  collectively(m_comm, [&] { down.downward(m_down, xh, col_potentials); });
  for (int c = 0; c < nc; ++c) // frees only: nothing to fail
    if (!K.holds(c)) xh[c] = DenseMatrix();
  return xh;
}

} // namespace hssbem

namespace hssbem {

namespace {

/// Bytes of a cluster's bases and blocks: counted first (out null), then written into a buffer of
/// that size; arrays go as their size and raw contents (floats stay 4 bytes).
struct Packer {
  char *out = nullptr;
  std::size_t n = 0;
  void raw(const void *p, std::size_t bytes)
  {
    if (out && bytes) std::memcpy(out + n, p, bytes);
    n += bytes;
  }
  template <class T>
  void put(T v)
  {
    raw(&v, sizeof v);
  }
  template <class T>
  void put_all(const std::vector<T> &a)
  {
    put<std::int64_t>(static_cast<std::int64_t>(a.size()));
    raw(a.data(), a.size() * sizeof(T));
  }
  void put_interpolation(const StoredInterpolation &s)
  {
    put<int>(s.candidates);
    put_all(s.skel_pos);
    put_all(s.red_pos);
    put_all(s.Tf);
    put_all(s.Td);
  }
  void put_block(const H2Block &B)
  {
    put<int>(B.col_cluster);
    put<int>(B.M.m);
    put<int>(B.M.n);
    put_all(B.M.a);
    put_all(B.single);
    put<int>(B.rank);
    put<int>(B.lr_rows ? 1 : 0);
    put_all(B.lr_s);
    put_all(B.lr_slot);
    put_all(B.lr_t);
  }
};

struct Reader {
  const char *in;
  std::size_t size, at = 0;
  void raw(void *p, std::size_t bytes)
  {
    if (at + bytes > size) throw std::logic_error("H2 gather: a truncated record");
    if (bytes) std::memcpy(p, in + at, bytes);
    at += bytes;
  }
  template <class T>
  T get()
  {
    T v;
    raw(&v, sizeof v);
    return v;
  }
  template <class T>
  std::vector<T> get_all()
  {
    const auto n = static_cast<std::size_t>(get<std::int64_t>());
    if (n > size) throw std::logic_error("H2 gather: a corrupt record");
    std::vector<T> a(n);
    raw(a.data(), n * sizeof(T));
    return a;
  }
  StoredInterpolation get_interpolation()
  {
    StoredInterpolation s;
    s.candidates = get<int>();
    s.skel_pos = get_all<int>();
    s.red_pos = get_all<int>();
    s.Tf = get_all<float>();
    s.Td = get_all<double>();
    return s;
  }
  H2Block get_block()
  {
    H2Block B;
    B.col_cluster = get<int>();
    B.M.m = get<int>();
    B.M.n = get<int>();
    B.M.a = get_all<double>();
    B.single = get_all<float>();
    B.rank = get<int>();
    B.lr_rows = get<int>() != 0;
    B.lr_s = get_all<float>();
    B.lr_slot = get_all<H2Block::Slot>();
    B.lr_t = get_all<float>();
    return B;
  }
};

} // namespace

std::optional<H2Matrix> gather_h2_matrix(const H2Matrix &K, const RankComm &comm, int root)
{
  const int P = comm.size(), me = comm.rank(), nc = K.tree().num_clusters();
  const auto pack = [&](Packer &p) {
    for (int c = 0; c < nc; ++c) {
      if (!K.holds(c)) continue;
      p.put<int>(c);
      p.put_interpolation(K.row_interpolation(c));
      p.put_interpolation(K.col_interpolation(c));
      p.put<std::int64_t>(static_cast<std::int64_t>(K.far_blocks(c).size()));
      for (const H2Block &B : K.far_blocks(c)) p.put_block(B);
      p.put<std::int64_t>(static_cast<std::int64_t>(K.near_blocks(c).size()));
      for (const H2Block &B : K.near_blocks(c)) p.put_block(B);
    }
  };
  std::vector<std::vector<double>> send, recv; // bytes, in doubles' storage (one allocation)
  std::vector<std::vector<int>> sizes;
  collectively(comm, [&] {
    send.resize(P);
    recv.resize(P);
    sizes.resize(P);
    if (me == root) return;
    Packer count;
    pack(count);
    send[root].resize((count.n + sizeof(double) - 1) / sizeof(double));
    Packer write;
    write.out = reinterpret_cast<char *>(send[root].data());
    pack(write);
    if (send[root].size() > static_cast<std::size_t>(std::numeric_limits<int>::max())) throw std::length_error("H2 gather: a part too large for one message");
    sizes[root] = {static_cast<int>(send[root].size())};
  });
  const std::vector<std::vector<int>> from = comm.exchange(sizes);
  collectively(comm, [&] {
    for (int q = 0; q < P; ++q)
      if (!from[q].empty()) recv[q].resize(static_cast<std::size_t>(from[q][0]));
  });
  comm.exchange(send, recv);
  send.clear();
  std::optional<H2Matrix> whole;
  collectively(comm, [&] {
    if (me != root) return;
    whole.emplace(K);
    for (int q = 0; q < P; ++q) {
      Reader r{reinterpret_cast<const char *>(recv[q].data()), recv[q].size() * sizeof(double)};
      while (r.size - r.at >= sizeof(int) + 2 * sizeof(std::int64_t)) {
        const int c = r.get<int>();
        StoredInterpolation U = r.get_interpolation(), V = r.get_interpolation();
        std::vector<H2Block> far(static_cast<std::size_t>(r.get<std::int64_t>())), near;
        for (H2Block &B : far) B = r.get_block();
        near.resize(static_cast<std::size_t>(r.get<std::int64_t>()));
        for (H2Block &B : near) B = r.get_block();
        whole->adopt(c, std::move(U), std::move(V), std::move(far), std::move(near));
      }
      std::vector<double>().swap(recv[q]);
    }
    whole->set_owners({}, 0);
    whole->update_stats();
  });
  return whole;
}

} // namespace hssbem
