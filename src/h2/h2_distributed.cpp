// The H² matrix distributed over ranks: cluster owners and the product (see h2_distributed.hpp).
#include "hssbem/h2/h2_distributed.hpp"

#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/phase.hpp"
#include "hssbem/core/tree_ownership.hpp"
#include "h2_transfer.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
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
  std::vector<std::vector<int>> need_low(P), need_vals(P), need_top(P), need_pot(P);
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
    }
  });
  m_low = ClusterExchange(comm, std::move(need_low));
  m_vals = ClusterExchange(comm, std::move(need_vals));
  m_top = ClusterExchange(comm, std::move(need_top));
  m_pot = ClusterExchange(comm, std::move(need_pot));
  for (const auto &list : m_vals.sends()) m_boundary.insert(m_boundary.end(), list.begin(), list.end());
  std::sort(m_boundary.begin(), m_boundary.end());
  m_boundary.erase(std::unique(m_boundary.begin(), m_boundary.end()), m_boundary.end());
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

void H2DistributedProduct::apply(const double *X, int ldx, double *Y, int ldy, int nrhs) const
{
  PhaseScope phase(Phase::Matvec);
  const H2Matrix &K = m_K;
  const ClusterTree &tree = K.tree();
  const int nc = tree.num_clusters(), w = K.col_block(), rb = K.row_block();
  std::vector<DenseMatrix> xh(nc), yh(nc), xv(nc);
  const auto moments = [&](int c) { return static_cast<int>(K.col_skeleton(c).size()); };
  const auto potentials = [&](int c) { return static_cast<int>(K.row_skeleton(c).size()); };
  const auto values = [&](int c) { return w * tree.cluster(c).size(); };
  const auto upward = [&](const std::vector<std::vector<int>> &levels) {
    for (const std::vector<int> &level : levels)
      for_each_cluster(level, [&](int c) {
        const Cluster &cl = tree.cluster(c);
        const StoredInterpolation &V = K.col_interpolation(c);
        xh[c] = DenseMatrix(V.rank(), nrhs);
        if (V.rank() == 0) return;
        CandidateRows<const double> x;
        if (cl.left < 0) x.base = X + static_cast<long>(w) * (cl.begin - m_first), x.ld = ldx;
        else x.a = &xh[cl.left], x.b = &xh[cl.right];
        std::vector<double> buf;
        interp_t(V, x, nrhs, xh[c].data(), xh[c].ld(), buf);
      });
  };
  const auto downward = [&](const std::vector<std::vector<int>> &levels) {
    for (const std::vector<int> &level : levels)
      for_each_cluster(level, [&](int c) {
        const Cluster &cl = tree.cluster(c);
        for (int ch : {cl.left, cl.right})
          if (yh[ch].m != potentials(ch) || yh[ch].n != nrhs) yh[ch] = DenseMatrix(potentials(ch), nrhs); // another rank's child
        CandidateRows<double> y;
        y.a = &yh[cl.left], y.b = &yh[cl.right];
        std::vector<double> buf;
        interp_n(K.row_interpolation(c), yh[c].data(), yh[c].ld(), nrhs, y, buf);
      });
  };

  // 1–2. Moments below the parts; moments and boundary values to the ranks that read them.
  collectively(m_comm, [&] {
    upward(m_up);
    for (int c : m_boundary) {
      const Cluster &cl = tree.cluster(c);
      xv[c] = DenseMatrix(values(c), nrhs);
      for (int k = 0; k < nrhs; ++k)
        std::copy_n(X + static_cast<long>(w) * (cl.begin - m_first) + static_cast<long>(k) * ldx, values(c), xv[c].data() + static_cast<long>(k) * values(c));
    }
  });
  m_low.run(xh, nrhs, false, moments);
  m_vals.run(xv, nrhs, false, values);
  // 3. Above the parts (rank 0), and the top moments other ranks' far blocks read.
  collectively(m_comm, [&] { upward(m_top_up); });
  m_top.run(xh, nrhs, false, moments);
  // 4–5. Far blocks; downward through the top, the parts' shares to their ranks.
  collectively(m_comm, [&] {
    for (int a : m_held) yh[a] = DenseMatrix(potentials(a), nrhs);
    for_each_cluster(m_held, [&](int a) {
      std::vector<double> buf;
      for (const H2Block &B : K.far_blocks(a)) B.multiply_add(xh[B.col_cluster].data(), xh[B.col_cluster].ld(), yh[a].data(), yh[a].ld(), nrhs, buf);
    });
    downward(m_top_down);
  });
  m_pot.run(yh, nrhs, true, potentials);
  // 5. Downward through the parts, then the leaves.
  collectively(m_comm, [&] {
    downward(m_down);
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
  std::vector<std::vector<double>> send(P), recv(P); // bytes, in doubles' storage (one allocation)
  std::vector<std::vector<int>> sizes(P);
  collectively(comm, [&] {
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
  for (int q = 0; q < P; ++q)
    if (!from[q].empty()) recv[q].resize(static_cast<std::size_t>(from[q][0]));
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
