// The H² factorization's dense top: which kind, taken from the frontier into its sinks, factored
// (see h2_factorization.hpp and top_assembly.hpp).
#include "factors.hpp"
#include "frontier.hpp"
#include "top_assembly.hpp"

#include "hssbem/core/allocator.hpp"
#include "hssbem/core/fault.hpp"
#include "hssbem/core/phase.hpp"
#include "hssbem/core/size_limits.hpp"
#include "hssbem/core/timer.hpp"

#include <algorithm>
#include <optional>
#include <stdexcept>
#include <string>

namespace hssbem {

namespace {

/// The trial solve's bound for a single-precision top: the factorization's own tolerance (at
/// most 1e-3, so that the top never adds more than the steps).
double single_trial_tol(const H2FactorOptions &o) { return std::min(o.rel_tol, 1e-3); }

/// Each step's and the top's unknowns on this rank's own rows (the steps touch no other rank's).
void to_own_rows(std::vector<h2f::Step> &steps, std::vector<int> &top_own, int first, int count)
{
  const int offset = 3 * first, n = 3 * count;
  const auto shift = [&](std::vector<int> &v) {
    for (int &g : v) {
      g -= offset;
      if (g < 0 || g >= n) throw std::logic_error("H2 factorization: a step reaches another rank's unknowns");
    }
  };
  for (h2f::Step &st : steps)
    for (std::vector<int> *v : {&st.box, &st.S, &st.R, &st.I}) shift(*v);
  shift(top_own);
}

} // namespace

void H2Factorization::factor_top(std::optional<h2f::Frontier> &front, bool single_store)
{
  PhaseScope phase(Phase::H2Top);
  const RankComm &comm = *m_comm;
  const int P = comm.size(), me = comm.rank();
  Factors &f = *m_f;
  Timer timer;
  m_stats.top_boxes = static_cast<int>(front->boxes().size());
  double n = static_cast<double>(front->active_total());
  comm.sum(&n, 1);
  // Single precision (single panels and a large top): SpreadTop, over every rank (spread) or on
  // rank 0 alone; else TopBlock on rank 0 (its LU mixed from single_top_from on). The other
  // ranks' rows go where the top is. The size model counts by the same rule (h2_top_kind).
  const H2TopKind kind = h2_top_kind(static_cast<long long>(n), single_store, m_options.single_top_from, m_options.spread_top, P);
  const bool single = kind == H2TopKind::Single || kind == H2TopKind::Spread;
  f.spread = kind == H2TopKind::Spread;
  return_free_memory(); // what the levels freed, before the top is allocated
  std::vector<float> local;
  DenseMatrix block; // the double top: all its columns on rank 0
  std::vector<double> row_sums;
  std::unique_ptr<h2f::TopSink> sink;
  collectively(comm, [&] {
    if (single) sink = std::make_unique<h2f::ColumnSink<float>>(h2f::SpreadTop::kBlock, me, f.spread ? P : 1, &local, &row_sums);
    else sink = std::make_unique<h2f::ColumnSink<double>>(h2f::SpreadTop::kBlock, me, 1, &block.a, &row_sums);
  });
  f.top_n = front->take_top(*sink, &f.top_own, &f.top_pos);
  if (single && !f.spread) comm.sum(row_sums.data(), f.top_n); // A·1 on every rank's rows, for rank 0's top
  const std::size_t front_peak = front->peak_bytes(), front_left = front->store_bytes();
  front.reset(); // spent: its memory goes before the top's LU
  sink.reset();
  return_free_memory();
  if (f.spread) {
    auto top = make_unique_collectively<h2f::SpreadTop>(comm);
    top->factor(comm, f.top_n, std::move(local), std::move(row_sums), single_trial_tol(m_options)); // collective; H2Breakdown on every rank
    f.top = std::move(top);
  }
  collectively<H2Breakdown>(comm, [&] {
    fault_point("H2FTop");
    if (!f.spread && me == 0 && single) {
      auto top = std::make_unique<h2f::SpreadTop>();
      top->factor(f.one, f.top_n, std::move(local), std::move(row_sums), single_trial_tol(m_options));
      f.top = std::move(top);
    } else if (!f.spread && me == 0) {
      auto top = std::make_unique<h2f::TopBlock>();
      block.m = block.n = f.top_n;
      if (!top->factor(std::move(block), m_options.single_top_from))
        throw H2Breakdown("H2 factorization broke down: the top block (" + std::to_string(f.top_n) + " unknowns) is singular to working precision");
      m_stats.top_mixed = top->mixed();
      f.top = std::move(top);
    }
    to_own_rows(f.steps, f.top_own, m_first, m_count);
  });
  m_stats.time_top = timer.seconds();
  m_stats.top_size = f.top_n;
  m_stats.top_single = single;
  m_stats.top_spread = f.spread ? P : 0;
  m_stats.top_bytes = f.top ? f.top->bytes() : 0;
  m_stats.workspace_bytes = std::max(front_peak, front_left + m_stats.top_bytes);
}

} // namespace hssbem
