// The frontier of the H² factorization on several ranks: what its cross blocks, merges and top
// exchange between the ranks (see frontier.hpp). Each rank holds its part's boxes; a cross block
// lives in two copies (the rows' rank, the columns' rank), and what one side's steps do to it
// reaches the other copy as that side's CrossSide at the level's end.
#include "frontier.hpp"

#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/cluster_exchange.hpp"

#include <initializer_list>
#include <set>
#include <stdexcept>
#include <tuple>

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

/// What a record of the exchanges of the leaves' copies, the merges and the top carries
/// (Frontier::read_records).
enum Record { BoxData = 0, ColumnBasis = 1, FarPart = 2, Unknowns = 3, LeafCopy = 4 };

/// A record of `kind` about clusters `ids`, then a matrix.
void append_record(std::vector<double> &r, Record kind, std::initializer_list<int> ids, const DenseMatrix &M)
{
  r.push_back(kind);
  r.insert(r.end(), ids.begin(), ids.end());
  append_matrix(r, M);
}

/// Box c's unknowns D, and with Psi its Ψ (BoxData; else Unknowns).
void append_box(std::vector<double> &r, int c, const std::vector<int> &D, const DenseMatrix *Psi)
{
  r.push_back(Psi ? BoxData : Unknowns);
  r.push_back(c);
  append_ints(r, D);
  if (Psi) append_matrix(r, *Psi);
}

} // namespace

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
        for (int b : m_cross[a])
          if (!mine(b)) append_record(send[m_owner[b]], LeafCopy, {a, b}, m_X[a].at(b).value());
      }
    },
    [&](const std::vector<std::vector<double>> &recv) { read_records(recv); });
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
          CrossSide &side = m_side[read_int(r, at)];
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
        if (boxes.insert({q, c}).second) append_box(r, c, m_D[c], &m_Psi[c]);
        if (cross_close(b, c)) continue; // the cross block holds the pair's value
        const int bb = far_pair(b, c).second;
        if (bases.insert({q, c, bb}).second) append_record(r, ColumnBasis, {c, bb}, col_basis_to(c, bb));
      }
    },
    [&](const std::vector<std::vector<double>> &recv) { read_records(recv); });
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
        if (boxes.insert({q, b}).second) append_box(r, b, m_D[b], nullptr); // no Ψ: the rows' rank adds the regularisation
        if (cross_close(b, c)) continue;
        append_record(r, FarPart, {b, c}, far[i]);
        m_pair_far[{b, c}] = std::move(far[i]); // this rank's copy (the rows) uses it too
      }
    },
    [&](const std::vector<std::vector<double>> &recv) { read_records(recv); });
}

void Frontier::read_records(const std::vector<std::vector<double>> &recv)
{
  for (const std::vector<double> &r : recv)
    for (std::size_t at = 0; at < r.size();) {
      const int kind = read_int(r, at), c = read_int(r, at);
      if (kind == BoxData || kind == Unknowns) m_D[c] = read_ints(r, at);
      if (kind == BoxData) m_Psi[c] = read_matrix(r, at);
      else if (kind == ColumnBasis || kind == FarPart) {
        const int d = read_int(r, at); // the cluster c's basis is carried to, or the far part's column box
        (kind == ColumnBasis ? m_remote_w : m_pair_far)[{c, d}] = read_matrix(r, at);
      } else if (kind == LeafCopy) {
        const int d = read_int(r, at); // the copy of the cross block (c, d) in d's columns
        settle(m_G[c].emplace(d, StoredBlock(read_matrix(r, at))).first->second);
      } else if (kind != Unknowns)
        throw std::logic_error("H2 factorization: an unknown record from another rank");
    }
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

} // namespace hssbem::h2f
