// The dense top taken from the frontier into its sinks (see top_assembly.hpp).
#include "top_assembly.hpp"

#include "frontier.hpp"

#include "hssbem/core/allocator.hpp"
#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/cluster_exchange.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

namespace hssbem::h2f {

namespace {

/// The rows of boxes `from` out of a RowSink's message, into sink.put(): box row by box row,
/// each row's blocks in order.
void read_rows(TopSink &sink, const std::vector<int> &off, const std::vector<int> &from, const std::vector<double> &message)
{
  const std::size_t n = static_cast<std::size_t>(off.back());
  std::size_t count = 0, at = 0;
  for (int s : from) count += static_cast<std::size_t>(off[s + 1] - off[s]) * n;
  if (count != message.size()) throw std::logic_error("H2 factorization: a message of the top's rows of unexpected length");
  for (int s : from)
    for (int t = 0; t + 1 < static_cast<int>(off.size()); ++t) {
      DenseMatrix B(off[s + 1] - off[s], off[t + 1] - off[t]);
      std::copy_n(message.begin() + static_cast<long>(at), B.a.size(), B.a.begin());
      at += B.a.size();
      sink.put(s, t, std::move(B));
    }
}

} // namespace

void GridSink::begin(const std::vector<int> &off, const std::vector<int> &)
{
  m_G.off = off;
  const std::size_t nb = off.size() - 1;
  m_G.blocks.assign(nb * nb, DenseMatrix());
}

void GridSink::put(int s, int t, DenseMatrix B) { m_G.blocks[static_cast<std::size_t>(s) * m_G.boxes() + t] = std::move(B); }

void GridSink::receive(int, const std::vector<int> &from, const std::vector<double> &message) { read_rows(*this, m_G.off, from, message); }

void SpreadSink::begin(const std::vector<int> &off, const std::vector<int> &mine)
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
    message_count((at + at % 2) / 2, m_ranks == 1 ? "these rows of the dense top (to rank 0; a smaller top, -pc_h2_top_size, or one spread over the ranks fits)" : "the spread top's columns for rank " + std::to_string(r));
    m_out[r].assign(at + at % 2, 0.0f); // an even count: two floats to a value
  }
  m_local->assign(static_cast<std::size_t>(n) * my_columns(), 0.0f);
  m_sums->assign(n, 0.0);
}

void SpreadSink::put(int s, int t, DenseMatrix B)
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

std::vector<std::vector<double>> SpreadSink::messages(int ranks)
{
  std::vector<std::vector<double>> send(ranks);
  for (int r = 0; r < m_ranks; ++r) {
    send[r].resize(m_out[r].size() / 2);
    if (!m_out[r].empty()) std::memcpy(send[r].data(), m_out[r].data(), m_out[r].size() * sizeof(float));
    std::vector<float>().swap(m_out[r]);
  }
  return send;
}

void SpreadSink::receive(int, const std::vector<int> &from, const std::vector<double> &message)
{
  // Another rank's rows of this rank's columns: for each of its boxes, column by column.
  const int n = m_off.back(), mine_cols = my_columns();
  std::size_t need = 0, at = 0;
  for (int s : from) need += static_cast<std::size_t>(m_off[s + 1] - m_off[s]) * mine_cols;
  if ((need + need % 2) / 2 != message.size()) throw std::logic_error("H2 factorization: a spread top message of unexpected length");
  const char *in = reinterpret_cast<const char *>(message.data()); // the floats' bytes (copied, never read as floats in place)
  for (int s : from) {
    const int m = m_off[s + 1] - m_off[s];
    for (int lc = 0; lc < mine_cols; ++lc, at += m) std::memcpy(m_local->data() + static_cast<std::size_t>(lc) * n + m_off[s], in + at * sizeof(float), m * sizeof(float));
  }
}

void RowSink::begin(const std::vector<int> &off, const std::vector<int> &mine)
{
  m_off = off;
  m_start.assign(off.size() - 1, 0);
  std::size_t at = 0;
  for (int s : mine) m_start[s] = at, at += static_cast<std::size_t>(off[s + 1] - off[s]) * off.back();
  message_count(at, "these rows of the dense top (to rank 0; a smaller top, -pc_h2_top_size, or one spread over the ranks fits)");
  m_out.assign(at, 0.0);
}

void RowSink::put(int s, int t, DenseMatrix B)
{
  const int m = m_off[s + 1] - m_off[s];
  if (B.m != m || B.n != m_off[t + 1] - m_off[t]) throw std::logic_error("H2 factorization: a top block of unexpected size");
  std::copy(B.a.begin(), B.a.end(), m_out.begin() + static_cast<long>(m_start[s] + static_cast<std::size_t>(m) * m_off[t]));
}

std::vector<std::vector<double>> RowSink::messages(int ranks)
{
  std::vector<std::vector<double>> send(ranks);
  send[0] = std::move(m_out);
  return send;
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
