// The frontier of the H² factorization on several ranks: what its cross blocks, merges and top
// exchange between the ranks (see frontier.hpp). Each rank holds its part's boxes; a cross block
// lives in two copies (the rows' rank, the columns' rank), and what one side's steps do to it
// reaches the other copy as that side's CrossSide at the level's end.
#include "frontier.hpp"

#include "hssbem/core/allocator.hpp"
#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/cluster_exchange.hpp"
#include "hssbem/core/dense_ops.hpp"

#include "top_block.hpp"

#include <algorithm>
#include <cstring>
#include <numeric>
#include <optional>
#include <string>
#include <set>
#include <tuple>
#include <stdexcept>

namespace hssbem::h2f {

namespace {

void append_ints(std::vector<double> &r, const std::vector<int> &v)
{
  r.push_back(static_cast<double>(v.size()));
  r.insert(r.end(), v.begin(), v.end());
}

int read_int(const std::vector<double> &r, std::size_t &at)
{
  if (at >= r.size()) throw std::logic_error("H2 factorization: a truncated record from another rank");
  return static_cast<int>(r[at++]);
}

std::vector<int> read_ints(const std::vector<double> &r, std::size_t &at)
{
  const int n = read_int(r, at);
  if (n < 0 || at + static_cast<std::size_t>(n) > r.size()) throw std::logic_error("H2 factorization: a corrupt record from another rank");
  std::vector<int> v(r.begin() + static_cast<long>(at), r.begin() + static_cast<long>(at) + n);
  at += static_cast<std::size_t>(n);
  return v;
}

/// The top's rows of this rank into the column blocks of a spread LU (SpreadTop): its own
/// columns into `local` (n × its count), the others' into one message per rank, rounded to
/// single precision (two floats to a value), box row by box row: for each of this rank's boxes
/// s in frontier order, for each of the destination's columns in order, box s's rows.
class SpreadSink : public TopSink {
public:
  SpreadSink(int nb, int rank, int ranks, const std::vector<int> &mine, std::vector<float> *local, std::vector<double> *row_sums)
    : m_nb(nb), m_rank(rank), m_ranks(ranks), m_mine(mine), m_local(local), m_sums(row_sums)
  {
  }
  void begin(const std::vector<int> &off) override
  {
    m_off = off;
    const int n = off.back();
    m_cols.resize(m_ranks);
    for (int r = 0; r < m_ranks; ++r) m_cols[r] = spread_columns(n, m_nb, r, m_ranks);
    m_base.assign(m_ranks, std::vector<std::size_t>(off.size() - 1, 0));
    m_out.assign(m_ranks, {});
    for (int r = 0; r < m_ranks; ++r) {
      std::size_t at = 0;
      for (int s : m_mine) m_base[r][s] = at, at += static_cast<std::size_t>(off[s + 1] - off[s]) * m_cols[r];
      if (r == m_rank) continue;
      message_count((at + at % 2) / 2, "the spread top's columns for rank " + std::to_string(r));
      m_out[r].assign(at + at % 2, 0.0f); // an even count: two floats to a value
    }
    m_local->assign(static_cast<std::size_t>(n) * m_cols[m_rank], 0.0f);
    m_sums->assign(n, 0.0);
  }
  void put(int s, int t, DenseMatrix B) override
  {
    const int n = m_off.back(), m = m_off[s + 1] - m_off[s];
    if (B.m != m || B.n != m_off[t + 1] - m_off[t]) throw std::logic_error("H2 factorization: a top block of unexpected size");
    for (int j = 0; j < B.n; ++j) {
      const int c = m_off[t] + j, r = (c / m_nb) % m_ranks, place = (c / m_nb / m_ranks) * m_nb + c % m_nb;
      const double *src = B.data() + static_cast<std::size_t>(j) * B.ld();
      float *dst = r == m_rank ? m_local->data() + static_cast<std::size_t>(place) * n + m_off[s] : m_out[r].data() + m_base[r][s] + static_cast<std::size_t>(place) * m;
      double *sums = m_sums->data() + m_off[s];
      for (int i = 0; i < m; ++i) {
        dst[i] = static_cast<float>(src[i]);
        sums[i] += src[i];
      }
    }
  }
  bool single() const override { return true; }
  /// The messages to the other ranks (this sink's buffers go).
  std::vector<std::vector<double>> messages()
  {
    std::vector<std::vector<double>> send(m_ranks);
    for (int r = 0; r < m_ranks; ++r) {
      send[r].resize(m_out[r].size() / 2);
      if (!m_out[r].empty()) std::memcpy(send[r].data(), m_out[r].data(), m_out[r].size() * sizeof(float));
      std::vector<float>().swap(m_out[r]);
    }
    return send;
  }
  /// Another rank's message: the rows of its boxes `from` (positions, in frontier order).
  void receive(const std::vector<int> &from, const std::vector<double> &message)
  {
    const int n = m_off.back(), mine_cols = m_cols[m_rank];
    std::size_t need = 0, at = 0;
    for (int s : from) need += static_cast<std::size_t>(m_off[s + 1] - m_off[s]) * mine_cols;
    if ((need + need % 2) / 2 != message.size()) throw std::logic_error("H2 factorization: a spread top message of unexpected length");
    const char *in = reinterpret_cast<const char *>(message.data()); // the floats' bytes (copied, never read as floats in place)
    for (int s : from) {
      const int m = m_off[s + 1] - m_off[s];
      for (int lc = 0; lc < mine_cols; ++lc, at += m) std::memcpy(m_local->data() + static_cast<std::size_t>(lc) * n + m_off[s], in + at * sizeof(float), m * sizeof(float));
    }
  }

private:
  int m_nb, m_rank, m_ranks;
  std::vector<int> m_mine;
  std::vector<float> *m_local;
  std::vector<double> *m_sums;
  std::vector<int> m_off, m_cols;
  std::vector<std::vector<std::size_t>> m_base; ///< per destination rank, per box of this rank: floats before its rows
  std::vector<std::vector<float>> m_out;
};

/// What a record of the merges' and the top's exchanges carries.
enum Record { BoxData = 0, ColumnBasis = 1, FarPart = 2 };

} // namespace

std::pair<int, int> Frontier::far_pair(int P, int Q) const
{
  for (int a = P; a >= 0; a = m_tree.cluster(a).parent)
    for (int b = Q; b >= 0; b = m_tree.cluster(b).parent)
      if (m_part.is_far(a, b)) return {a, b};
  throw std::logic_error("H2 factorization: no far block above a pair that is not close");
}

DenseMatrix Frontier::col_basis_to(int Q, int b) const
{
  if (mine(Q)) return restricted_basis(Q, b, false);
  const auto it = m_remote_w.find({Q, b});
  if (it == m_remote_w.end()) throw std::logic_error("H2 factorization: another rank's column basis is missing");
  return it->second;
}

void Frontier::exchange_leaf_copies()
{
  exchange_records(
    *m_comm, "the leaves' cross blocks",
    [&](std::vector<std::vector<double>> &send) {
      for (int a : m_front) {
        if (!mine(a)) continue;
        for (int b : m_cross[a]) {
          if (mine(b)) continue;
          std::vector<double> &r = send[m_owner[b]];
          r.push_back(a);
          r.push_back(b);
          append_matrix(r, m_X[a].at(b).value());
        }
      }
    },
    [&](const std::vector<std::vector<double>> &recv) {
      for (const std::vector<double> &r : recv)
        for (std::size_t at = 0; at < r.size();) {
          const int a = read_int(r, at), b = read_int(r, at);
          settle(m_G[a].emplace(b, StoredBlock(read_matrix(r, at))).first->second);
        }
    });
}

void Frontier::exchange_sides()
{
  const int P = m_comm->size();
  exchange_records(
    *m_comm, "the sides of the cross blocks",
    [&](std::vector<std::vector<double>> &send) {
      for (int X : m_front) {
        if (!mine(X) || !m_side[X].recorded) continue;
        std::vector<char> to(P, 0);
        for (int Y : m_cross[X])
          if (!mine(Y)) to[m_owner[Y]] = 1;
        for (int q = 0; q < P; ++q) {
          if (!to[q]) continue;
          send[q].push_back(X);
          append_ints(send[q], m_side[X].kept);
          append_matrix(send[q], m_side[X].C);
        }
      }
    },
    [&](const std::vector<std::vector<double>> &recv) {
      for (const std::vector<double> &r : recv)
        for (std::size_t at = 0; at < r.size();) {
          const int X = read_int(r, at);
          CrossSide &side = m_side[X];
          side.recorded = true;
          side.kept = read_ints(r, at);
          side.C = read_matrix(r, at);
        }
    });
}

void Frontier::send_column_data(const std::vector<std::pair<int, int>> &pairs)
{
  exchange_records(
    *m_comm, "the column data of cross pairs",
    [&](std::vector<std::vector<double>> &send) {
      std::set<std::pair<int, int>> boxes;       // (rank, c) sent
      std::set<std::tuple<int, int, int>> bases; // (rank, c, the cluster its basis is carried to) sent
      for (const auto &[b, c] : pairs) {
        const int q = m_owner[b];
        std::vector<double> &r = send[q];
        if (boxes.insert({q, c}).second) {
          r.push_back(BoxData);
          r.push_back(c);
          append_ints(r, m_D[c]);
          append_matrix(r, m_Psi[c]);
        }
        if (cross_close(b, c)) continue; // the cross block holds the pair's value
        const int bb = far_pair(b, c).second;
        if (!bases.insert({q, c, bb}).second) continue;
        r.push_back(ColumnBasis);
        r.push_back(c);
        r.push_back(bb);
        append_matrix(r, col_basis_to(c, bb));
      }
    },
    [&](const std::vector<std::vector<double>> &recv) {
      for (const std::vector<double> &r : recv)
        for (std::size_t at = 0; at < r.size();) {
          const int kind = read_int(r, at), c = read_int(r, at);
          if (kind == BoxData) {
            m_D[c] = read_ints(r, at);
            m_Psi[c] = read_matrix(r, at);
          } else if (kind == ColumnBasis) {
            const int bb = read_int(r, at);
            m_remote_w[{c, bb}] = read_matrix(r, at);
          } else
            throw std::logic_error("H2 factorization: an unknown record from another rank");
        }
    });
}

void Frontier::send_far_parts(const std::vector<std::pair<int, int>> &pairs)
{
  exchange_records(
    *m_comm, "the far parts of cross pairs",
    [&](std::vector<std::vector<double>> &send) {
      std::vector<int> todo; // positions of the pairs that need a far part
      for (std::size_t i = 0; i < pairs.size(); ++i)
        if (!cross_close(pairs[i].first, pairs[i].second)) todo.push_back(static_cast<int>(i));
      std::vector<DenseMatrix> far(pairs.size());
      for_each_cluster(todo, [&](int i) { far[i] = far_part(pairs[i].first, pairs[i].second); });
      std::set<std::pair<int, int>> boxes;
      for (std::size_t i = 0; i < pairs.size(); ++i) {
        const auto [b, c] = pairs[i];
        const int q = m_owner[c];
        std::vector<double> &r = send[q];
        if (boxes.insert({q, b}).second) {
          r.push_back(BoxData);
          r.push_back(b);
          append_ints(r, m_D[b]);
          append_matrix(r, DenseMatrix());
        }
        if (cross_close(b, c)) continue;
        r.push_back(FarPart);
        r.push_back(b);
        r.push_back(c);
        append_matrix(r, far[i]);
        m_pair_far[{b, c}] = std::move(far[i]); // this rank's copy (the rows) uses it too
      }
    },
    [&](const std::vector<std::vector<double>> &recv) {
      for (const std::vector<double> &r : recv)
        for (std::size_t at = 0; at < r.size();) {
          const int kind = read_int(r, at), b = read_int(r, at);
          if (kind == BoxData) {
            m_D[b] = read_ints(r, at);
            read_matrix(r, at); // no Ψ: the rows' rank adds the regularisation
          } else if (kind == FarPart) {
            const int c = read_int(r, at);
            m_pair_far[{b, c}] = read_matrix(r, at);
          } else
            throw std::logic_error("H2 factorization: an unknown record from another rank");
        }
    });
}

void Frontier::prepare_cross_merge(int l, const std::vector<int> &front, const std::vector<char> &in_front)
{
  // The new level's cross pairs between this rank's boxes and another's, as the children pairs
  // they are assembled from: (b other, c mine) needs c's column data on b's rank; (b mine,
  // c other) needs the far parts computed here.
  std::vector<std::pair<int, int>> columns, rows;
  std::vector<std::pair<int, int>> whole_rows, whole_cols; // (P, Q) of the new level, P mine / Q mine
  collectively(*m_comm, [&] {
    for (int P : front)
      for (int Q : m_part.close[P]) {
        if (!in_front[Q] || same_part(P, Q) || mine(P) == mine(Q)) continue;
        for (int b : parts_of(P, l))
          for (int c : parts_of(Q, l)) (mine(P) ? rows : columns).push_back({b, c});
        (mine(P) ? whole_rows : whole_cols).push_back({P, Q});
      }
  });
  const auto concat = [&](int Q) {
    const std::vector<int> kids = parts_of(Q, l);
    if (kids.size() == 1 && kids[0] == Q) return;
    std::vector<int> D;
    for (int c : kids) D.insert(D.end(), m_D[c].begin(), m_D[c].end());
    m_D[Q] = std::move(D);
  };
  send_column_data(columns);
  collectively(*m_comm, [&] {
    for (const auto &pq : whole_rows) concat(pq.second);
  });
  send_far_parts(rows);
  collectively(*m_comm, [&] {
    for (const auto &pq : whole_cols) concat(pq.first);
  });
}

void Frontier::share_top_columns()
{
  std::vector<std::pair<int, int>> pairs; // (P other, Q mine): Q's data for P's rows
  collectively(*m_comm, [&] {
    for (int p : m_front)
      for (int q : m_front)
        if (!mine(p) && mine(q)) pairs.push_back({p, q});
  });
  send_column_data(pairs); // and every box's unknowns to every rank
}

std::vector<int> Frontier::top_offsets() const
{
  std::vector<int> off(m_front.size() + 1, 0);
  for (std::size_t s = 0; s < m_front.size(); ++s) off[s + 1] = off[s] + static_cast<int>(m_D[m_front[s]].size());
  return off;
}

/// The positions of this rank's boxes in frontier order.
std::vector<int> Frontier::my_positions() const
{
  std::vector<int> here;
  for (int s = 0; s < static_cast<int>(m_front.size()); ++s)
    if (mine(m_front[s])) here.push_back(s);
  return here;
}

void Frontier::pack_top_rows(const std::vector<int> &here, bool halves, std::vector<double> &r)
{
  const int nb = static_cast<int>(m_front.size());
  const auto values = [&](std::size_t count) { return halves ? (count + 1) / 2 : count; };
  // Box row s: its position, its unknowns (for a check), then its blocks. The rows are written
  // in place into one message sized beforehand, so that it is never copied as it grows.
  std::vector<std::size_t> start(here.size() + 1, 0);
  for (std::size_t i = 0; i < here.size(); ++i) {
    const std::size_t m = m_D[m_front[here[i]]].size();
    std::size_t size = 2 + m;
    for (int t = 0; t < nb; ++t) size += 2 + values(m * m_D[m_front[t]].size());
    start[i + 1] = start[i] + size;
  }
  message_count(start.back(), "rank " + std::to_string(m_rank) + "'s rows of the dense top (to rank 0; a smaller top, -pc_h2_top_size, or one spread over the ranks fits)");
  r.resize(start.back());
  std::vector<int> rows(here.size());
  std::iota(rows.begin(), rows.end(), 0);
  for_each_cluster(rows, [&](int i) {
    const int X = m_front[here[i]];
    double *out = r.data() + start[i];
    *out++ = here[i];
    *out++ = static_cast<double>(m_D[X].size());
    out = std::copy(m_D[X].begin(), m_D[X].end(), out);
    std::vector<float> rounded;
    for (int t = 0; t < nb; ++t) {
      const int Q = m_front[t];
      const auto it = m_M[X].find(Q);
      const DenseMatrix B = it != m_M[X].end() ? it->second.take() : far_part(X, Q);
      if (B.m != static_cast<int>(m_D[X].size()) || B.n != static_cast<int>(m_D[Q].size())) throw std::logic_error("H2 factorization: a top block of unexpected size");
      *out++ = B.m;
      *out++ = B.n;
      if (!halves) {
        out = std::copy(B.a.begin(), B.a.end(), out);
        continue;
      }
      rounded.assign(values(B.a.size()) * 2, 0.0f);
      std::copy(B.a.begin(), B.a.end(), rounded.begin());
      std::memcpy(out, rounded.data(), rounded.size() * sizeof(float));
      out += rounded.size() / 2;
    }
    m_M[X].clear();
    if (out != r.data() + start[i + 1]) throw std::logic_error("H2 factorization: a top row of unexpected length");
  });
}

void Frontier::unpack_top_rows(std::vector<std::vector<double>> &recv, const std::vector<int> &here, bool halves, TopSink &sink) const
{
  const int nb = static_cast<int>(m_front.size());
  const auto values = [&](std::size_t count) { return halves ? (count + 1) / 2 : count; };
  std::vector<char> seen(nb, 0);
  std::vector<float> rounded; // a block as it came (rounded), copied out of the message
  for (int s : here) seen[s] = 1;
  for (std::vector<double> &r : recv) {
    for (std::size_t at = 0; at < r.size();) {
      const int s = read_int(r, at);
      if (s < 0 || s >= nb || seen[s] || read_ints(r, at) != m_D[m_front[s]]) throw std::logic_error("H2 factorization: a box row of the top came twice or does not match");
      seen[s] = 1;
      for (int t = 0; t < nb; ++t) {
        if (!halves) {
          sink.put(s, t, read_matrix(r, at));
          continue;
        }
        const int m = read_int(r, at), n = read_int(r, at);
        const std::size_t count = static_cast<std::size_t>(m) * static_cast<std::size_t>(n);
        if (m != static_cast<int>(m_D[m_front[s]].size()) || n != static_cast<int>(m_D[m_front[t]].size()) || at + values(count) > r.size())
          throw std::logic_error("H2 factorization: a corrupt top block from another rank");
        rounded.resize(count);
        std::memcpy(rounded.data(), r.data() + at, count * sizeof(float));
        DenseMatrix B(m, n);
        std::copy(rounded.begin(), rounded.end(), B.a.begin());
        at += values(count);
        sink.put(s, t, std::move(B));
      }
    }
    std::vector<double>().swap(r);
  }
  if (std::find(seen.begin(), seen.end(), 0) != seen.end()) throw std::logic_error("H2 factorization: a box of the top came from no rank");
}

void Frontier::take_top_ranks(std::vector<int> *dofs, std::vector<std::vector<int>> *from, std::vector<int> *own, TopSink &sink)
{
  const int nb = static_cast<int>(m_front.size()), P = m_comm->size();
  share_top_columns();
  // Blocks travel rounded to single precision, two to a value, when the sink rounds them anyway.
  const bool halves = sink.single();
  std::vector<int> here;
  exchange_records(
    *m_comm, "the dense top's rows",
    [&](std::vector<std::vector<double>> &send) {
      dofs->clear();
      from->assign(P, {});
      own->clear();
      here = my_positions();
      for (int s : here) own->insert(own->end(), m_D[m_front[s]].begin(), m_D[m_front[s]].end());
      if (m_rank == 0) { // its own rows straight into the sink
        const std::vector<int> off = top_offsets();
        for (int s = 0; s < nb; ++s) {
          const int q = m_owner.empty() ? 0 : m_owner[m_front[s]];
          for (int i = off[s]; i < off[s + 1]; ++i) (*from)[q].push_back(i);
          dofs->insert(dofs->end(), m_D[m_front[s]].begin(), m_D[m_front[s]].end());
        }
        sink.begin(off);
        for_each_cluster(here, [&](int s) { take_row(s, sink); });
      } else
        pack_top_rows(here, halves, send[0]);
      release_stores();
      return_free_memory();
    },
    [&](std::vector<std::vector<double>> &recv) {
      if (m_rank == 0) unpack_top_rows(recv, here, halves, sink);
    });
}

int Frontier::take_top_spread(int nb, std::vector<float> *local, std::vector<double> *row_sums, std::vector<int> *own, std::vector<int> *pos)
{
  const int nb_boxes = static_cast<int>(m_front.size()), P = m_comm->size();
  share_top_columns();
  std::vector<int> off;
  std::optional<SpreadSink> sink;
  exchange_records(
    *m_comm, "the spread top's columns",
    [&](std::vector<std::vector<double>> &send) {
      off = top_offsets();
      check_spread_size(off.back(), nb, P);
      const std::vector<int> here = my_positions();
      own->clear();
      pos->clear();
      for (int s : here) {
        own->insert(own->end(), m_D[m_front[s]].begin(), m_D[m_front[s]].end());
        for (int i = off[s]; i < off[s + 1]; ++i) pos->push_back(i);
      }
      sink.emplace(nb, m_rank, P, here, local, row_sums);
      sink->begin(off);
      for_each_cluster(here, [&](int s) { take_row(s, *sink); });
      release_stores();
      return_free_memory();
      send = sink->messages();
    },
    [&](std::vector<std::vector<double>> &recv) {
      for (int q = 0; q < P; ++q) {
        if (q == m_rank) continue;
        std::vector<int> from; // rank q's boxes
        for (int s = 0; s < nb_boxes; ++s)
          if (m_owner[m_front[s]] == q) from.push_back(s);
        sink->receive(from, recv[q]);
        std::vector<double>().swap(recv[q]);
      }
    });
  return off.back();
}

} // namespace hssbem::h2f
