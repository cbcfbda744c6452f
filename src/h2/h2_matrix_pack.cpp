// An H² matrix's stored form and back (see H2Matrix::pack and H2Matrix::unpack): every number as
// the compression left it, so the products after a load are those before, bit for bit.
#include "hssbem/h2/h2_matrix.hpp"

#include <stdexcept>
#include <string>

namespace hssbem {

namespace {

[[noreturn]] void damaged(const std::string &what) { throw std::invalid_argument("damaged: " + what); }

void pack_lists(PackWriter &w, const std::vector<std::vector<int>> &lists)
{
  w.put(static_cast<int>(lists.size()));
  for (const std::vector<int> &l : lists) w.put(l);
}

/// Lists of cluster indices (or of positions below `bound`), one per cluster.
std::vector<std::vector<int>> unpack_lists(PackReader &r, int count, int bound, const char *what)
{
  if (r.get_int() != count) damaged(std::string(what) + ": not one list per cluster");
  std::vector<std::vector<int>> out(count);
  for (std::vector<int> &l : out) {
    r.get(l);
    for (int v : l)
      if (v < 0 || v >= bound) damaged(std::string(what) + ": an index out of range");
  }
  return out;
}

void pack_interpolation(PackWriter &w, const StoredInterpolation &s)
{
  w.put(s.candidates);
  w.put(s.skel_pos), w.put(s.red_pos), w.put(s.Tf), w.put(s.Td);
}

StoredInterpolation unpack_interpolation(PackReader &r, int rank)
{
  StoredInterpolation s;
  s.candidates = r.get_int(0, INT32_MAX, "basis candidates");
  r.get(s.skel_pos), r.get(s.red_pos), r.get(s.Tf), r.get(s.Td);
  const std::size_t weights = s.skel_pos.size() * s.red_pos.size();
  if (s.rank() != rank || (s.Tf.size() != weights && s.Td.size() != weights) || (rank > 0 && s.skel_pos.size() + s.red_pos.size() != static_cast<std::size_t>(s.candidates)) || (rank == 0 && !s.red_pos.empty()))
    damaged("a basis does not fit its skeleton");
  for (const std::vector<int> *pos : {&s.skel_pos, &s.red_pos})
    for (int p : *pos)
      if (p < 0 || p >= s.candidates) damaged("a basis position out of range");
  return s;
}

void pack_block(PackWriter &w, const H2Block &B)
{
  w.put(B.col_cluster), w.put(B.rank), w.put(B.lr_rows ? 1 : 0);
  w.put(B.M), w.put(B.single), w.put(B.lr_s), w.put(B.lr_t);
  w.put(std::vector<int>(B.lr_slot.begin(), B.lr_slot.end()));
}

/// A block of `rows` × `cols` in column cluster `col`.
H2Block unpack_block(PackReader &r, int col, int rows, int cols)
{
  H2Block B;
  B.col_cluster = r.get_int();
  B.rank = r.get_int(-1, INT32_MAX, "block rank");
  B.lr_rows = r.get_int(0, 1, "block side") == 1;
  r.get(B.M), r.get(B.single), r.get(B.lr_s), r.get(B.lr_t);
  std::vector<int> slots;
  r.get(slots);
  if (B.col_cluster != col || B.M.m != rows || B.M.n != cols) damaged("a block does not fit the partition");
  const std::size_t entries = static_cast<std::size_t>(rows) * cols;
  if (!B.single.empty() && B.single.size() != entries) damaged("a single-precision block does not fit its sizes");
  if (B.is_low_rank()) {
    const std::size_t len = B.lr_rows ? cols : rows, other = B.lr_rows ? rows : cols;
    if (B.rank > static_cast<int>(std::min(len, other)) || B.lr_s.size() != len * B.rank || slots.size() != other || B.lr_t.size() != (other - B.rank) * B.rank)
      damaged("a low-rank block does not fit its sizes");
    for (int s : slots)
      if (s < -static_cast<int>(other - B.rank) || s >= B.rank) damaged("a low-rank block's slot out of range");
  }
  B.lr_slot.assign(slots.begin(), slots.end());
  if (B.M.a.empty() && B.single.empty() && !B.is_low_rank() && entries > 0) damaged("a block without entries");
  return B;
}

} // namespace

void H2Matrix::pack(PackWriter &w) const
{
  if (!m_bases.empty()) throw std::logic_error("H2Matrix: the bases are not stored yet (store_bases)");
  w.put(m_tree.num_clusters()), w.put(m_tree.num_points()), w.put(m_row_block), w.put(m_col_block);
  w.put(m_tree.perm());
  w.put(m_col_scale);
  pack_lists(w, m_partition.far), pack_lists(w, m_partition.near), pack_lists(w, m_partition.close);
  w.put(std::vector<int>(m_partition.has_far.begin(), m_partition.has_far.end()));
  pack_lists(w, m_row_skel), pack_lists(w, m_col_skel);
  w.put(m_row_forced), w.put(m_col_forced);
  for (int c = 0; c < m_tree.num_clusters(); ++c) {
    if (!holds(c)) continue;
    pack_interpolation(w, m_U[c]), pack_interpolation(w, m_V[c]);
    for (const auto *blocks : {&m_far[c], &m_near[c]}) {
      w.put(static_cast<int>(blocks->size()));
      for (const H2Block &B : *blocks) pack_block(w, B);
    }
  }
  w.put(m_stats.proxy_points), w.put(m_stats.eta), w.put(static_cast<double>(m_stats.entries_evaluated));
}

H2Matrix H2Matrix::unpack(ClusterTree tree, std::vector<int> owner, int rank, PackReader &r)
{
  const int nc = r.get_int(), np = r.get_int();
  if (nc != tree.num_clusters() || np != tree.num_points()) damaged("the matrix's tree is not the problem's");
  const int rb = r.get_int(1, 8, "row block"), cb = r.get_int(1, 8, "column block");
  std::vector<int> perm;
  r.get(perm);
  if (perm != tree.perm()) damaged("the matrix's tree orders the points otherwise");
  H2Matrix K(std::move(tree), rb, cb);
  K.set_owners(std::move(owner), rank);
  r.get(K.m_col_scale);
  if (static_cast<int>(K.m_col_scale.size()) != cb) damaged("the column scales");
  K.m_partition.far = unpack_lists(r, nc, nc, "far blocks");
  K.m_partition.near = unpack_lists(r, nc, nc, "near blocks");
  K.m_partition.close = unpack_lists(r, nc, nc, "close pairs");
  std::vector<int> has_far;
  r.get(has_far);
  if (static_cast<int>(has_far.size()) != nc) damaged("has_far");
  K.m_partition.has_far.assign(has_far.begin(), has_far.end());
  K.m_row_skel = unpack_lists(r, nc, rb * np, "row skeletons");
  K.m_col_skel = unpack_lists(r, nc, cb * np, "column skeletons");
  K.m_bases.clear();
  K.prepare_stored_bases();
  r.get(K.m_row_forced), r.get(K.m_col_forced);
  if (static_cast<int>(K.m_row_forced.size()) != nc || static_cast<int>(K.m_col_forced.size()) != nc) damaged("the forced skeletons");
  for (int c = 0; c < nc; ++c) {
    K.m_basis_stored[c] = 1;
    if (!K.holds(c)) continue;
    K.m_U[c] = unpack_interpolation(r, static_cast<int>(K.m_row_skel[c].size()));
    K.m_V[c] = unpack_interpolation(r, static_cast<int>(K.m_col_skel[c].size()));
    if (r.get_int() != static_cast<int>(K.m_partition.far[c].size())) damaged("the far blocks do not fit the partition");
    for (int b : K.m_partition.far[c]) K.m_far[c].push_back(unpack_block(r, b, static_cast<int>(K.m_row_skel[c].size()), static_cast<int>(K.m_col_skel[b].size())));
    if (r.get_int() != static_cast<int>(K.m_partition.near[c].size())) damaged("the near blocks do not fit the partition");
    const int rows = rb * K.m_tree.cluster(c).size();
    for (int b : K.m_partition.near[c]) K.m_near[c].push_back(unpack_block(r, b, rows, cb * K.m_tree.cluster(b).size()));
  }
  K.m_stats.proxy_points = r.get_int();
  K.m_stats.eta = r.get_double();
  K.m_stats.entries_evaluated = static_cast<long long>(r.get_double());
  K.update_stats();
  return K;
}

} // namespace hssbem
