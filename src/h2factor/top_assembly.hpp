// Private to the H² factorization: how the frontier's last boxes become the dense top on the
// ranks that factor it. Every rank takes its own boxes' rows of the top into a sink
// (Frontier::take_top, one row-taking for every kind of top); the sinks' messages carry what
// another rank holds to it.
#pragma once

#include "top_block.hpp"

#include <vector>

namespace hssbem::h2f {

/// Where this rank's rows of the top go, block by block.
class TopSink {
public:
  virtual ~TopSink() = default;
  /// Once: box s of the frontier holds the top's rows off[s] .. off[s + 1] − 1; `mine` lists
  /// this rank's boxes (positions, ascending).
  virtual void begin(const std::vector<int> &off, const std::vector<int> &mine) = 0;
  /// Block (s, t) of this rank's box row s; concurrent calls have different s.
  virtual void put(int s, int t, DenseMatrix B) = 0;
  /// Where block (s, t) lies in double in this rank's own storage (leading dimension *ld, zeros
  /// there), for a far part added in place instead of put(); null when it does not.
  virtual double *place(int, int, int *) { return nullptr; }
  /// Once the rows are in: what goes to each of `ranks` ranks (the sink's buffers go).
  virtual std::vector<std::vector<double>> messages(int ranks) { return std::vector<std::vector<double>>(ranks); }
  /// What rank q sent here, about its boxes `from` (positions, ascending).
  virtual void receive(int q, const std::vector<int> &from, const std::vector<double> &message) = 0;
};

/// The top's columns over ranks 0 .. `ranks` − 1, blocks of nb columns, block j on rank j mod
/// ranks, in values of type T: this rank's columns into `local` (n × its count, column-major) and
/// A·1 on its rows into `row_sums`; the other ranks' columns of this rank's rows into one message
/// per rank: a single-precision top (SpreadTop, T float: two values to a message word), spread,
/// or with ranks = 1 on rank 0 (every other rank sends its rows there and keeps no columns), like
/// the double top (TopBlock, T double, ranks = 1).
template <class T>
class ColumnSink : public TopSink {
public:
  ColumnSink(int nb, int rank, int ranks, std::vector<T> *local, std::vector<double> *row_sums)
    : m_nb(nb), m_rank(rank), m_ranks(ranks), m_local(local), m_sums(row_sums)
  {
  }
  void begin(const std::vector<int> &off, const std::vector<int> &mine) override;
  void put(int s, int t, DenseMatrix B) override;
  double *place(int s, int t, int *ld) override;
  std::vector<std::vector<double>> messages(int ranks) override;
  void receive(int q, const std::vector<int> &from, const std::vector<double> &message) override;

private:
  int my_columns() const { return m_rank < m_ranks ? m_cols[m_rank] : 0; }

  int m_nb, m_rank, m_ranks;
  std::vector<T> *m_local;
  std::vector<double> *m_sums;
  std::vector<int> m_off, m_cols;
  std::vector<std::vector<std::size_t>> m_base; ///< per destination rank, per box: values before its rows
  std::vector<std::vector<T>> m_out;
};

} // namespace hssbem::h2f
