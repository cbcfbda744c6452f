// The H² factorization's levels: each level's boxes eliminated on the threads as a dependency
// graph, the other sides of the cross blocks, the merge into the next level (see
// h2_factorization.hpp).
#include "factors.hpp"
#include "frontier.hpp"

#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/phase.hpp"
#include "hssbem/core/progress.hpp"
#include "hssbem/core/timer.hpp"

#include <algorithm>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>

namespace hssbem {

namespace {

/// Whether factoring the remaining unknowns densely now costs less than eliminating level l
/// first: the level's Schur complements at most Σ_X 2 |I_X|² |D_X| flops (I_X: X and its close
/// neighbours, every active unknown of X redundant at worst) against the dense top's (2/3) n³, in
/// single precision at twice the rate from single_top_from on (docs/h2-factorization.md).
bool dense_top_is_cheaper(const h2f::Frontier &F, const std::vector<int> &boxes, double n, const RankComm &comm, int mixed_from)
{
  double level = collectively(comm, [&] {
    double flops = 0;
    for (int X : boxes) {
      const double m = static_cast<double>(F.active(X).size());
      double around = m;
      for (int Y : F.neighbours(X)) around += static_cast<double>(F.active(Y).size());
      flops += 2 * around * around * m;
    }
    return flops;
  });
  comm.sum(&level, 1);
  const double top = 2.0 / 3.0 * n * n * n / (mixed_from > 0 && n >= mixed_from ? 2.0 : 1.0);
  return top < level;
}

/// The boxes of one level in elimination order, each with the earlier boxes whose closed
/// neighbourhoods meet its own (the steps that must come first; any other pair of steps touches
/// disjoint blocks and may run at once, in either order, with the same result).
struct LevelSchedule {
  std::vector<int> order;              ///< boxes, in the order of greedy colour classes
  std::vector<int> waits;              ///< per position: earlier boxes it must wait for
  std::vector<std::vector<int>> after; ///< per position: later positions that wait for it
  /// Per position: every other box comes before it or after it in the graph, so it always runs
  /// alone (and may use threaded BLAS: a property of the graph, so the factors do not depend on
  /// the threads' timing).
  std::vector<char> alone;
};

/// Which positions of s are ordered with respect to every other (transitive closure by bitsets).
std::vector<char> lone_positions(const LevelSchedule &s)
{
  const std::size_t n = s.order.size(), words = (n + 63) / 64;
  std::vector<std::uint64_t> anc(n * words, 0), desc(n * words, 0);
  const auto set = [&](std::vector<std::uint64_t> &b, std::size_t row, std::size_t bit) { b[row * words + bit / 64] |= std::uint64_t{1} << (bit % 64); };
  for (std::size_t i = 0; i < n; ++i) // positions are a topological order
    for (int j : s.after[i]) {
      for (std::size_t w = 0; w < words; ++w) anc[j * words + w] |= anc[i * words + w];
      set(anc, j, i);
    }
  for (std::size_t i = n; i-- > 0;)
    for (int j : s.after[i]) {
      for (std::size_t w = 0; w < words; ++w) desc[i * words + w] |= desc[j * words + w];
      set(desc, i, j);
    }
  std::vector<char> alone(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    std::size_t related = 0;
    for (std::size_t w = 0; w < words; ++w) related += static_cast<std::size_t>(__builtin_popcountll(anc[i * words + w] | desc[i * words + w]));
    alone[i] = related + 1 == n;
  }
  return alone;
}

LevelSchedule level_schedule(const h2f::Frontier &F, const std::vector<int> &boxes, int nclusters)
{
  // Greedy colouring in tree order: boxes of one colour have disjoint closed neighbourhoods, and
  // colour by colour is the order (a box waits only for earlier colours).
  std::vector<std::vector<int>> closed(boxes.size()), touching(nclusters);
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    closed[i] = F.neighbours(boxes[i]);
    closed[i].push_back(boxes[i]);
    for (int Y : closed[i]) touching[Y].push_back(static_cast<int>(i));
  }
  std::vector<int> colour(boxes.size(), -1);
  std::vector<std::vector<int>> classes;
  std::vector<char> used;
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    used.assign(classes.size() + 1, 0);
    for (int Y : closed[i])
      for (int j : touching[Y])
        if (colour[j] >= 0) used[colour[j]] = 1;
    int c = 0;
    while (used[c]) ++c;
    colour[i] = c;
    if (c == static_cast<int>(classes.size())) classes.emplace_back();
    classes[c].push_back(static_cast<int>(i));
  }
  LevelSchedule s;
  std::vector<int> position(boxes.size());
  for (const auto &cls : classes)
    for (int i : cls) {
      position[i] = static_cast<int>(s.order.size());
      s.order.push_back(boxes[i]);
    }
  s.waits.assign(boxes.size(), 0);
  s.after.resize(boxes.size());
  std::vector<int> seen(boxes.size(), -1);
  for (std::size_t i = 0; i < boxes.size(); ++i)
    for (int Y : closed[i])
      for (int j : touching[Y])
        if (position[j] < position[i] && seen[j] != static_cast<int>(i)) {
          seen[j] = static_cast<int>(i);
          ++s.waits[position[i]];
          s.after[position[j]].push_back(position[i]);
        }
  s.alone = lone_positions(s);
  return s;
}

/// Run step(X) for every box of the schedule on the OpenMP threads (OpenBLAS serial, but threaded
/// for a box that runs alone), each as soon as the boxes it waits for are done, the earliest
/// ready box first; finish(X) runs after step(X), one at a time, with no step starting
/// meanwhile; start(X) likewise before it. The first exception of any of them stops the level
/// and is rethrown after the region: the region itself allocates nothing (the ready boxes are a
/// heap in storage reserved before it) and lets nothing escape (std::terminate).
template <class Start, class Step, class Finish>
void run_schedule(const LevelSchedule &s, const Start &start, const Step &step, const Finish &finish)
{
  const int n = static_cast<int>(s.order.size());
  std::vector<int> waits = s.waits, ready; // ready: a min-heap of positions
  ready.reserve(n);
  for (int j = 0; j < n; ++j)
    if (waits[j] == 0) ready.push_back(j);
  std::make_heap(ready.begin(), ready.end(), std::greater<int>());
  std::mutex mu;
  std::condition_variable cv;
  int done = 0;
  std::exception_ptr error;
  const bool par = parallel_over_clusters(static_cast<std::size_t>(n));
  SerialBlas serial(par);
  // One box's turn: false when the level is over (all done, or an error).
  const auto turn = [&]() -> bool {
    int j = -1;
    bool alone = false, ok = false;
    {
      std::unique_lock<std::mutex> lock(mu);
      cv.wait(lock, [&] { return !ready.empty() || done == n || error; });
      if (done == n || error) return false;
      std::pop_heap(ready.begin(), ready.end(), std::greater<int>());
      j = ready.back();
      ready.pop_back();
      alone = par && s.alone[j]; // then nothing else runs or can start meanwhile
      if (alone) serial.widen(true);
      try {
        start(s.order[j]);
      } catch (...) {
        error = std::current_exception();
      }
      ok = !error; // read under the lock: another thread may be setting it
    }
    if (ok) try {
        step(s.order[j]);
      } catch (...) {
        std::lock_guard<std::mutex> lock(mu);
        if (!error) error = std::current_exception();
        ok = false;
      }
    {
      std::lock_guard<std::mutex> lock(mu);
      if (alone) serial.widen(false);
      if (ok) try {
          finish(s.order[j]);
        } catch (...) {
          if (!error) error = std::current_exception();
        }
      ++done;
      for (int k : s.after[j])
        if (--waits[k] == 0) { // within the capacity reserved above: no allocation
          ready.push_back(k);
          std::push_heap(ready.begin(), ready.end(), std::greater<int>());
        }
    }
    cv.notify_all();
    return true;
  };
#pragma omp parallel if (par)
  {
    try {
      while (turn()) {
      }
    } catch (...) { // the lock or the wait itself failed (std::system_error): stop every thread
      std::lock_guard<std::mutex> lock(mu);
      if (!error) error = std::current_exception();
      cv.notify_all();
    }
  }
  if (error) std::rethrow_exception(error);
}

} // namespace

void H2Factorization::eliminate_levels(h2f::Frontier &front, int l0, int last)
{
  const RankComm &comm = *m_comm;
  const ClusterTree &tree = m_K.tree();
  collectively(comm, [&] { m_stats.levels.reserve(static_cast<std::size_t>(tree.levels())); }); // push_back below never allocates
  const Progress progress("H2 factorization levels"); // the share of the unknowns eliminated
  for (int l = l0; l >= last; --l) {
    double active = static_cast<double>(front.active_total());
    comm.sum(&active, 1);
    progress.report(1.0 - active / m_f->pattern.dofs());
    if (active <= m_options.top_size || !comm.any(front.level_has_far_field(l))) break;
    std::vector<int> boxes; // this rank's boxes of the level
    const bool any = collectively(comm, [&] {
      bool some = false; // the same on every rank: every rank knows the frontier's boxes
      for (int X : tree.clusters_at_level(l))
        if (front.steps_at(X)) {
          some = true;
          if (front.mine(X)) boxes.push_back(X);
        }
      return some;
    });
    if (!any) break; // above the parts
    if (m_options.top_when_cheaper && dense_top_is_cheaper(front, boxes, active, comm, m_options.single_top_from)) break;
    Timer timer;
    H2FactorLevelStats ls;
    ls.level = l;
    ls.cross_blocks = front.cross_pairs();
    ls.cross_bytes = front.cross_bytes();
    eliminate_level(front, boxes, ls);
    front.note_bytes();
    if (l > last) {
      PhaseScope phase(Phase::H2Merge);
      Timer t;
      front.merge(l);
      m_stats.time_merge += t.seconds();
    }
    ls.seconds = timer.seconds();
    m_stats.levels.push_back(ls); // within the capacity reserved above
  }
}

void H2Factorization::eliminate_level(h2f::Frontier &front, const std::vector<int> &boxes, H2FactorLevelStats &ls)
{
  PhaseScope phase(Phase::H2Eliminate);
  const RankComm &comm = *m_comm;
  const int nc = m_K.tree().num_clusters();
  std::vector<h2f::Step> steps;
  std::vector<double> flops, t_skel, t_elim;
  std::vector<std::vector<h2f::NewFill>> fills;
  LevelSchedule schedule;
  collectively<H2Breakdown>(comm, [&] {
    steps.resize(nc);
    for (auto *v : {&flops, &t_skel, &t_elim}) v->assign(nc, 0.0);
    fills.resize(nc);
    schedule = level_schedule(front, boxes, nc);
    run_schedule(
      schedule, [&](int X) { front.claim(X); },
      [&](int X) {
        Timer t;
        const int m = static_cast<int>(front.active(X).size());
        front.precondition(X, &steps[X]);
        const h2f::BoxSkeleton sk = front.skeleton(X, m_options.rel_tol);
        t_skel[X] = t.seconds();
        t.restart();
        front.eliminate(X, sk, &steps[X], &flops[X], &fills[X]);
        front.rest(X);
        if (m_stats.single_panels) steps[X].demote();
        t_elim[X] = t.seconds();
        steps[X].candidates = m;
      },
      [&](int X) { front.add_fill(std::move(fills[X])); });
  });
  front.finish_level(); // the other sides of the cross blocks
  // The solve replays the steps in the schedule's order (dependencies come first in it).
  collectively(comm, [&] {
    for (int X : schedule.order) {
      const h2f::Step &st = steps[X];
      ls.boxes += 1;
      ls.mean_candidates += st.candidates;
      ls.max_candidates = std::max(ls.max_candidates, st.candidates);
      ls.mean_rank += static_cast<double>(st.S.size());
      ls.max_rank = std::max(ls.max_rank, static_cast<int>(st.S.size()));
      ls.eliminated += static_cast<long long>(st.R.size());
      m_stats.flops_schur += flops[X];
      m_stats.time_skeleton += t_skel[X];
      m_stats.time_eliminate += t_elim[X];
      ls.bytes += steps[X].bytes();
      m_f->steps.push_back(std::move(steps[X]));
    }
  });
  if (ls.boxes > 0) {
    ls.mean_candidates /= ls.boxes;
    ls.mean_rank /= ls.boxes;
  }
}

} // namespace hssbem
