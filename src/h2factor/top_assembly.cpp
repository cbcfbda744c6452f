// The dense top taken from the frontier into its sinks (see top_assembly.hpp).
#include "top_assembly.hpp"

#include "frontier.hpp"

#include "hssbem/core/allocator.hpp"
#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/cluster_exchange.hpp"

#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace hssbem::h2f {

namespace {

/// Message words (doubles) that carry `count` values of type T.
template <class T>
std::size_t words(std::size_t count)
{
  return (count * sizeof(T) + sizeof(double) - 1) / sizeof(double);
}

} // namespace

template <class T>
void ColumnSink<T>::begin(const std::vector<int> &off, const std::vector<int> &mine)
{
  m_off = off;
  const int n = off.back();
  m_cols.resize(m_ranks);
  for (int r = 0; r < m_ranks; ++r) m_cols[r] = spread_columns(n, m_nb, r, m_ranks);
  m_base.assign(m_ranks, std::vector<std::size_t>(off.size() - 1, 0));
  m_out.assign(m_ranks, {});
  for (int r = 0; r < m_ranks; ++r) {
    std::size_t at = 0;
    for (int s : mine) m_base[r][s] = at, at += static_cast<std::size_t>(off[s + 1] - off[s]) * m_cols[r];
    if (r == m_rank) continue;
    message_count(words<T>(at), m_ranks == 1 ? "these rows of the dense top (to rank 0; a smaller top, -pc_h2_top_size, or one spread over the ranks fits)" : "the spread top's columns for rank " + std::to_string(r));
    m_out[r].assign(words<T>(at) * sizeof(double) / sizeof(T), T(0)); // whole message words
  }
  m_local->assign(static_cast<std::size_t>(n) * my_columns(), T(0));
  m_sums->assign(n, 0.0);
}

template <class T>
void ColumnSink<T>::put(int s, int t, DenseMatrix B)
{
  const int n = m_off.back(), m = m_off[s + 1] - m_off[s];
  if (B.m != m || B.n != m_off[t + 1] - m_off[t]) throw std::logic_error("H2 factorization: a top block of unexpected size");
  for (int j = 0; j < B.n; ++j) {
    const int c = m_off[t] + j, r = (c / m_nb) % m_ranks, place = (c / m_nb / m_ranks) * m_nb + c % m_nb;
    const double *src = B.data() + static_cast<std::size_t>(j) * B.ld();
    T *dst = r == m_rank ? m_local->data() + static_cast<std::size_t>(place) * n + m_off[s] : m_out[r].data() + m_base[r][s] + static_cast<std::size_t>(place) * m;
    double *sums = m_sums->data() + m_off[s];
    for (int i = 0; i < m; ++i) {
      dst[i] = static_cast<T>(src[i]);
      sums[i] += src[i];
    }
  }
}

template <class T>
double *ColumnSink<T>::place(int s, int t, int *ld)
{
  if constexpr (std::is_same_v<T, double>) // the double top's columns, all on rank 0 (A·1 is not needed)
    if (m_ranks == 1 && m_rank == 0) {
      *ld = m_off.back();
      return m_local->data() + static_cast<std::size_t>(m_off[t]) * m_off.back() + m_off[s];
    }
  return nullptr;
}

template <class T>
std::vector<std::vector<double>> ColumnSink<T>::messages(int ranks)
{
  std::vector<std::vector<double>> send(ranks);
  for (int r = 0; r < m_ranks; ++r) {
    send[r].resize(words<T>(m_out[r].size()));
    if (!m_out[r].empty()) std::memcpy(send[r].data(), m_out[r].data(), m_out[r].size() * sizeof(T));
    std::vector<T>().swap(m_out[r]);
  }
  return send;
}

template <class T>
void ColumnSink<T>::receive(int, const std::vector<int> &from, const std::vector<double> &message)
{
  // Another rank's rows of this rank's columns: for each of its boxes, column by column.
  const int n = m_off.back(), mine_cols = my_columns();
  std::size_t need = 0, at = 0;
  for (int s : from) need += static_cast<std::size_t>(m_off[s + 1] - m_off[s]) * mine_cols;
  if (words<T>(need) != message.size()) throw std::logic_error("H2 factorization: a message of the top's columns of unexpected length");
  const char *in = reinterpret_cast<const char *>(message.data()); // the values' bytes (copied, never read as T in place)
  for (int s : from) {
    const int m = m_off[s + 1] - m_off[s];
    for (int lc = 0; lc < mine_cols; ++lc, at += m) std::memcpy(m_local->data() + static_cast<std::size_t>(lc) * n + m_off[s], in + at * sizeof(T), m * sizeof(T));
  }
}

template class ColumnSink<float>;
template class ColumnSink<double>;

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
    int ld = 0;
    double *out = it == m_M[P].end() ? sink.place(s, t, &ld) : nullptr;
    if (out) add_far_part(P, Q, out, ld);
    else sink.put(s, t, it != m_M[P].end() ? it->second.take() : far_part(P, Q));
  }
  m_M[P].clear();
}

int Frontier::take_top(TopSink &sink, std::vector<int> *own, std::vector<int> *pos)
{
  share_top_columns();
  std::vector<int> off;
  exchange_records(
    *m_comm, "the dense top's rows",
    [&](std::vector<std::vector<double>> &send) {
      off = top_offsets();
      const std::vector<int> here = my_positions();
      own->clear();
      pos->clear();
      for (int s : here) {
        own->insert(own->end(), m_D[m_front[s]].begin(), m_D[m_front[s]].end());
        for (int i = off[s]; i < off[s + 1]; ++i) pos->push_back(i);
      }
      sink.begin(off, here);
      for_each_cluster(here, [&](int s) { take_row(s, sink); });
      release_stores();
      return_free_memory();
      send = sink.messages(m_comm->size());
    },
    [&](std::vector<std::vector<double>> &recv) {
      for (int q = 0; q < m_comm->size(); ++q) {
        if (q == m_rank) continue;
        std::vector<int> from; // rank q's boxes
        for (int s = 0; s + 1 < static_cast<int>(off.size()); ++s)
          if (m_owner[m_front[s]] == q) from.push_back(s);
        sink.receive(q, from, recv[q]);
        std::vector<double>().swap(recv[q]);
      }
    });
  return off.back();
}

} // namespace hssbem::h2f
