// The H² factorization: levels, colours, the dense top and the solve (see h2_factorization.hpp).
#include "hssbem/h2factor/h2_factorization.hpp"

#include "frontier.hpp"
#include "top_block.hpp"

#include "hssbem/bem/rigid_modes.hpp"
#include "hssbem/compress/pattern_columns.hpp"
#include "hssbem/core/allocator.hpp"
#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/fault.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/core/phase.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/core/tree_ownership.hpp"

#include <algorithm>
#include <cstdio>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <set>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace hssbem {

struct H2Factorization::Factors {
  h2f::Pattern pattern;
  std::vector<h2f::Step> steps;
  std::vector<int> top_dofs;
  h2f::TopBlock top;
  std::vector<int> top_own;                ///< distributed: this rank's top unknowns (its rows), in the order rank 0 expects
  std::vector<std::vector<int>> top_from;  ///< distributed, rank 0: positions in top_dofs of rank q's top unknowns
  std::unique_ptr<h2f::SpreadTop> spread;  ///< distributed: the top spread over the ranks (else rank 0's `top`)
  std::vector<int> top_pos;                ///< with `spread`: the positions of top_own in the top
};

int default_sketch_columns(double rel_tol)
{
  // Enough to carry the far field's directions down to the tolerance (skeletons measured: ~50 at
  // 3e-3, ~150 per side at 1e-7); at 40k, 3e-3: p = 40, 60, 85 gave ||I - A F^-1|| 4.2e-2, 3.8e-2,
  // 3.6e-2 and the same iterations.
  const double digits = std::max(1.0, -std::log10(rel_tol));
  return std::clamp(static_cast<int>(std::lround(10 + 20 * digits)), 48, 320);
}

const FarFieldSketch &H2FactorCache::sketch(int p, double *made)
{
  if (made) *made = 0;
  for (const auto &s : m_sketches)
    if (s->columns == p) return *s;
  Timer t;
  const SerialComm one;
  const RankComm &comm = m_dist ? m_dist->comm() : one;
  FarFieldSketch s = m_dist ? far_field_sketch(*m_dist, p) : far_field_sketch(*m_K, p);
  collectively(comm, [&] { m_sketches.push_back(std::make_unique<FarFieldSketch>(std::move(s))); });
  if (made) *made = t.seconds();
  return *m_sketches.back();
}

namespace {

void check_options(const H2FactorOptions &o)
{
  if (!(o.rel_tol > 0 && o.rel_tol < 1)) throw std::invalid_argument("H2 factorization: the relative tolerance must lie in (0, 1)");
  if (o.leaf_size < 0) throw std::invalid_argument("H2 factorization: the leaf size must be 0 (the matrix's) or positive");
  if (o.sketch_columns < 0 || o.sketch_columns > kMaxSketchColumns)
    throw std::invalid_argument("H2 factorization: the sketch size must be 0 (from the tolerance) or at most " + std::to_string(kMaxSketchColumns));
  if (o.top_size < 0) throw std::invalid_argument("H2 factorization: the top size must be >= 0");
}

/// The columns of A-hat (slots and signs, cluster order) and the regularisation, if any.
h2f::Pattern make_pattern(const H2Matrix &K, const SystemSelection &sel, const std::vector<double> *modes)
{
  const ClusterTree &tree = K.tree();
  const int n = tree.num_points();
  const std::size_t N = 3 * static_cast<std::size_t>(n);
  if (sel.displacement_known.size() != static_cast<std::size_t>(n)) throw std::invalid_argument("H2 factorization: the pattern has the wrong number of nodes");
  h2f::Pattern p;
  p.slot.resize(N);
  p.sign.resize(N);
  for (int k = 0; k < n; ++k)
    for (int a = 0; a < 3; ++a) p.slot[3 * k + a] = pattern_slot(sel, tree.perm()[k], a, &p.sign[3 * k + a]);
  if (modes) {
    if (modes->size() != 6 * N) throw std::invalid_argument("H2 factorization: rigid modes of the wrong size");
    p.c = rigid_regularization_weight;
    p.phi.resize(6 * N);
    p.psi.resize(6 * N);
    for (int k = 0; k < n; ++k)
      for (int a = 0; a < 3; ++a)
        for (int j = 0; j < 6; ++j) {
          const std::size_t g = 3 * static_cast<std::size_t>(k) + a;
          p.phi[g + j * N] = (*modes)[(3 * static_cast<std::size_t>(tree.perm()[k]) + a) * 6 + j];
          p.psi[g + j * N] = p.phi[g + j * N] * K.col_scale(p.slot[g]);
        }
  }
  return p;
}

/// The level of the first boxes factored: the highest whose clusters hold at most leaf_size
/// nodes. With leaf_size 0 the leaves' level, or below rel_tol 1e-5 the level above it: there a
/// leaf's skeleton keeps most of its unknowns (20k sphere: 155 of 157 at 1e-7, 143 at 1e-6, 121 at
/// 1e-5), so its elimination costs a level's time for little (starting one level up: 1e-7 34.4 ->
/// 29.8 s, 1e-6 23.5 -> 20.8 s).
int first_level(const ClusterTree &tree, int leaf_size, double rel_tol)
{
  int l = tree.levels() - 1;
  if (leaf_size <= 0) return rel_tol < 1e-5 ? std::max(1, l - 1) : l;
  while (l > 1) {
    int largest = 0;
    for (int c : tree.clusters_at_level(l - 1)) largest = std::max(largest, tree.cluster(c).size());
    if (largest > leaf_size) break;
    --l;
  }
  return l;
}

/// The finest level the factorization may merge up to: with parts eliminated separately, the
/// deepest part root's. Above the parts a part's root never merges, so a tree whose parts' roots
/// lie on different levels (a number of parts that is not a power of two: 3 parts sit at levels
/// 1, 2, 2) would otherwise put a part's root of level 1 into one frontier with boxes of level 2,
/// a pair that the H² partition never met and that no far block lies above. 1 without parts.
int last_level(const ClusterTree &tree, bool parts)
{
  int l = 1;
  if (parts)
    for (int p = 0; p < tree.num_parts(); ++p) l = std::max(l, tree.cluster(tree.part_cluster(p)).level);
  return l;
}

/// Whether the top's LU runs in single precision alone (TopBlock::factor_single): when the
/// panels rest in single precision (the factorization is a preconditioner) and the top is large
/// enough for the mixed LU. The mixed LU would refine each of its solves to double against a
/// copy of the top in double that the single-precision steps below it cannot use, and it takes
/// three times the memory: on 2 ranks of an 80k sphere at 2e-3, rank 0's 5 174-unknown top took
/// 306 MB, the single LU 102 MB.
bool top_in_single(double n, const H2FactorOptions &o) { return o.mixed_top_from > 0 && n >= o.mixed_top_from; }

/// The trial solve's bound for a single-precision top: the factorization's own tolerance (at
/// most 1e-3, so that the top never adds more than the steps).
double single_trial_tol(const H2FactorOptions &o) { return std::min(o.rel_tol, 1e-3); }

std::string top_breakdown(const h2f::TopBlock &top)
{
  std::string what = "H2 factorization broke down: the top block (" + std::to_string(top.size()) + " unknowns) is singular to ";
  if (!top.single()) return what + "working precision";
  char trial[64];
  std::snprintf(trial, sizeof trial, "%.1e", top.trial_error());
  return what + "single precision (a trial solve is off by " + trial + "; a tolerance below 1e-5 factors it in double)";
}

/// Whether factoring the remaining unknowns densely now costs less than eliminating level l
/// first. The level's Schur complements cost at most Σ_X 2 |I_X|² |D_X| flops (I_X: X and its
/// close neighbours, every active unknown of X redundant at worst) at the eliminations' BLAS rate;
/// the dense top (2/3) n³, in single precision at twice that rate when n reaches
/// mixed_top_from. At the upper levels of a tight factorization on a small surface, a box's close
/// neighbours hold most of what is left and its skeleton most of its unknowns: at 1e-7 on a 20k
/// sphere, the level with 16 boxes of ~600 unknowns cost 7.0 s to eliminate (7.5e11 Schur flop in
/// all) where the 9 600-unknown dense top it left behind takes about 3 s.
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

H2Factorization::H2Factorization(H2FactorCache &cache, const SystemSelection &sel, const H2FactorOptions &options, const std::vector<double> *rigid_modes)
  : m_K(cache.matrix()), m_options(options), m_f(std::make_unique<Factors>())
{
  PhaseScope whole(Phase::H2Factorization);
  check_options(options);
  if (cache.distributed() && !cache.matrix().holds_all()) throw std::invalid_argument("H2 factorization: a distributed matrix needs the distributed constructor");
  const ClusterTree &tree = m_K.tree();
  const int p = options.sketch_columns > 0 ? options.sketch_columns : default_sketch_columns(options.rel_tol);
  const FarFieldSketch *sketch;
  {
    PhaseScope phase(Phase::H2Sketch);
    sketch = &cache.sketch(p, &m_stats.time_sketch);
  }
  m_stats.sketch_columns = p;
  m_stats.single_panels = options.single_panels < 0 ? options.rel_tol >= 1e-5 : options.single_panels == 1;
  m_f->pattern = make_pattern(m_K, sel, rigid_modes);
  m_slot = m_f->pattern.slot;

  Timer timer;
  // Blocks rest in single precision with the panels, unless everything goes to the dense top at
  // once: its singularity test (a pure-traction pattern without regularisation) needs them exact.
  std::vector<int> parts;
  if (options.within_parts && tree.num_parts() > 1) {
    parts = cluster_parts(tree);
    m_stats.parts = tree.num_parts();
  }
  const bool single_store = m_stats.single_panels && m_f->pattern.dofs() > options.top_size;
  const int last = last_level(tree, !parts.empty());
  auto front = std::make_unique<h2f::Frontier>(m_K, *sketch, m_f->pattern, single_store, std::move(parts));
  const int l0 = std::max(first_level(tree, options.leaf_size, options.rel_tol), last);
  for (int l = tree.levels() - 1; l > l0; --l) front->merge(l);
  m_stats.time_init = timer.seconds();
  const SerialComm one;
  eliminate_levels(*front, one, l0, last);
  PhaseScope phase(Phase::H2Top);
  timer.restart();
  m_stats.top_boxes = static_cast<int>(front->boxes().size());
  const bool single_top = single_store && top_in_single(static_cast<double>(front->active_total()), options);
  return_free_memory(); // what the levels freed, before the top is allocated
  h2f::BlockGrid grid;
  h2f::SingleTop lone;
  h2f::GridSink to_grid(grid);
  h2f::SingleSink to_single(lone);
  front->take_top(&m_f->top_dofs, single_top ? static_cast<h2f::TopSink &>(to_single) : to_grid);
  const std::size_t front_peak = front->peak_bytes(), front_left = front->store_bytes();
  front.reset(); // spent: its memory goes before the top's LU
  return_free_memory();
  const bool ok = single_top ? m_f->top.factor_single(std::move(lone), single_trial_tol(options)) : m_f->top.factor(std::move(grid), options.mixed_top_from);
  if (!ok) throw H2Breakdown(top_breakdown(m_f->top));
  m_stats.time_top = timer.seconds();
  m_stats.workspace_bytes = std::max(front_peak, front_left + m_f->top.bytes());
  m_stats.top_size = m_f->top.size();
  m_stats.top_mixed = m_f->top.mixed();
  m_stats.top_single = m_f->top.single();
  m_stats.top_bytes = m_f->top.bytes();
  m_stats.bytes = m_stats.top_bytes;
  for (const H2FactorLevelStats &ls : m_stats.levels) m_stats.bytes += ls.bytes;
}

H2Factorization::H2Factorization(H2FactorCache &cache, const RankComm &comm, const SystemSelection &sel, const H2FactorOptions &options, const std::vector<double> *rigid_modes)
  : m_K(cache.matrix()), m_comm(&comm), m_options(options)
{
  PhaseScope whole(Phase::H2Factorization);
  const ClusterTree &tree = m_K.tree();
  const int P = comm.size(), me = comm.rank();
  collectively(comm, [&] {
    m_f = std::make_unique<Factors>();
    check_options(options);
    if (!cache.distributed()) throw std::invalid_argument("H2 factorization: the distributed factorization needs a distributed matrix's cache");
    if (P > 1 && tree.num_parts() != P) throw std::invalid_argument("H2 factorization: the tree has " + std::to_string(tree.num_parts()) + " parts for " + std::to_string(P) + " ranks");
    m_first = cache.distributed()->first_point();
    m_count = cache.distributed()->num_points();
  });
  m_options.within_parts = true;
  const int p = options.sketch_columns > 0 ? options.sketch_columns : default_sketch_columns(options.rel_tol);
  const FarFieldSketch *sketch;
  {
    PhaseScope phase(Phase::H2Sketch);
    sketch = &cache.sketch(p, &m_stats.time_sketch); // collective
  }
  m_stats.sketch_columns = p;
  m_stats.single_panels = options.single_panels < 0 ? options.rel_tol >= 1e-5 : options.single_panels == 1;
  collectively(comm, [&] {
    fault_point("H2FSubtree"); // each rank's elimination of its part starts
    m_f->pattern = make_pattern(m_K, sel, rigid_modes);
    m_slot = m_f->pattern.slot;
  });
  if (tree.num_parts() > 1) m_stats.parts = tree.num_parts();

  Timer timer;
  const bool single_store = m_stats.single_panels && m_f->pattern.dofs() > options.top_size;
  std::vector<int> parts;
  if (tree.num_parts() > 1) parts = collectively(comm, [&] { return cluster_parts(tree); });
  std::optional<h2f::Frontier> front; // no allocation of its own before its collective construction
  front.emplace(m_K, *sketch, m_f->pattern, single_store, std::move(parts), &comm);
  const int last = last_level(tree, tree.num_parts() > 1);
  const int l0 = std::max(first_level(tree, options.leaf_size, options.rel_tol), last);
  for (int l = tree.levels() - 1; l > l0; --l) front->merge(l);
  m_stats.time_init = timer.seconds();
  eliminate_levels(*front, comm, l0, last);
  PhaseScope phase(Phase::H2Top);
  timer.restart();
  m_stats.top_boxes = static_cast<int>(front->boxes().size());
  double top_n = static_cast<double>(front->active_total());
  comm.sum(&top_n, 1);
  const bool single_top = single_store && top_in_single(top_n, options);
  return_free_memory(); // what the levels freed, before the top is allocated
  // The top spread over the ranks (single precision, several ranks), or on rank 0.
  const bool spread = single_top && P > 1 && options.spread_top;
  std::optional<h2f::BlockGrid> grid;
  h2f::SingleTop lone;
  std::optional<h2f::GridSink> to_grid;
  h2f::SingleSink to_single(lone);
  std::vector<float> columns;
  std::vector<double> row_sums;
  int spread_n = 0;
  collectively(comm, [&] {
    if (spread) m_f->spread = std::make_unique<h2f::SpreadTop>();
    else to_grid.emplace(grid.emplace());
  });
  if (spread)
    spread_n = front->take_top_spread(h2f::SpreadTop::kBlock, &columns, &row_sums, &m_f->top_own, &m_f->top_pos);
  else
    front->take_top_ranks(&m_f->top_dofs, &m_f->top_from, &m_f->top_own, single_top ? static_cast<h2f::TopSink &>(to_single) : *to_grid);
  const std::size_t front_peak = front->peak_bytes(), front_left = front->store_bytes();
  front.reset(); // spent: its memory goes before the top's LU
  return_free_memory();
  collectively<H2Breakdown>(comm, [&] {
    fault_point("H2FTop");
    if (!spread && me == 0 && !(single_top ? m_f->top.factor_single(std::move(lone), single_trial_tol(options)) : m_f->top.factor(std::move(*grid), options.mixed_top_from)))
      throw H2Breakdown(top_breakdown(m_f->top));
    // This rank's steps and top unknowns on its own rows (the steps touch no other rank's).
    const int offset = 3 * m_first, n = 3 * m_count;
    const auto shift = [&](std::vector<int> &v) {
      for (int &g : v) {
        g -= offset;
        if (g < 0 || g >= n) throw std::logic_error("H2 factorization: a step reaches another rank's unknowns");
      }
    };
    for (h2f::Step &st : m_f->steps)
      for (std::vector<int> *v : {&st.box, &st.S, &st.R, &st.I}) shift(*v);
    shift(m_f->top_own);
  });
  if (spread) m_f->spread->factor(comm, spread_n, std::move(columns), std::move(row_sums), single_trial_tol(options)); // collective; throws H2Breakdown on every rank
  m_stats.time_top = timer.seconds();
  m_stats.top_size = static_cast<int>(comm.max(spread ? spread_n : m_f->top.size()));
  m_stats.top_spread = spread ? P : 0;
  m_stats.top_bytes = spread ? m_f->spread->bytes() : m_f->top.bytes();
  m_stats.workspace_bytes = std::max(front_peak, front_left + m_stats.top_bytes);
  m_stats.top_mixed = m_f->top.mixed();
  m_stats.top_single = spread || m_f->top.single();
  m_stats.bytes = m_stats.top_bytes;
  for (const H2FactorLevelStats &ls : m_stats.levels) m_stats.bytes += ls.bytes;
}

void H2Factorization::eliminate_levels(h2f::Frontier &front, const RankComm &comm, int l0, int last)
{
  const ClusterTree &tree = m_K.tree();
  const H2FactorOptions &options = m_options;
  Timer timer;
  collectively(comm, [&] { m_stats.levels.reserve(static_cast<std::size_t>(tree.levels())); }); // push_back below never allocates
  for (int l = l0; l >= last; --l) {
    double active = static_cast<double>(front.active_total());
    comm.sum(&active, 1);
    if (active <= options.top_size || !comm.any(front.level_has_far_field(l))) break;
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
    if (options.top_when_cheaper && dense_top_is_cheaper(front, boxes, active, comm, options.mixed_top_from)) break;
    H2FactorLevelStats ls;
    ls.level = l;
    ls.cross_blocks = front.cross_pairs();
    ls.cross_bytes = front.cross_bytes();
    timer.restart();
    {
      PhaseScope phase(Phase::H2Eliminate);
      std::vector<h2f::Step> steps;
      std::vector<double> flops, t_skel, t_elim;
      std::vector<std::vector<h2f::NewFill>> fills;
      LevelSchedule schedule;
      collectively<H2Breakdown>(comm, [&] {
        const std::size_t nc = static_cast<std::size_t>(tree.num_clusters());
        steps.resize(nc);
        for (auto *v : {&flops, &t_skel, &t_elim}) v->assign(nc, 0.0);
        fills.resize(nc);
        schedule = level_schedule(front, boxes, tree.num_clusters());
        run_schedule(
          schedule, [&](int X) { front.claim(X); },
          [&](int X) {
            Timer t;
            const int m = static_cast<int>(front.active(X).size());
            front.precondition(X, &steps[X]);
            const h2f::BoxSkeleton sk = front.skeleton(X, options.rel_tol);
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
    }
    if (ls.boxes > 0) {
      ls.mean_candidates /= ls.boxes;
      ls.mean_rank /= ls.boxes;
    }
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

H2Factorization::~H2Factorization() = default;

double H2Factorization::top_trial() const { return m_f->spread ? m_f->spread->trial_error() : m_f->top.trial_error(); }

int H2Factorization::num_unknowns() const { return m_f->pattern.dofs(); }

int H2Factorization::steps_crossing_parts() const
{
  const ClusterTree &tree = m_K.tree();
  std::vector<int> part_of_dof(3 * static_cast<std::size_t>(tree.num_points()), 0);
  for (int p = 0; p < tree.num_parts(); ++p) {
    const Cluster &c = tree.cluster(tree.part_cluster(p));
    std::fill(part_of_dof.begin() + 3L * c.begin, part_of_dof.begin() + 3L * c.end, p);
  }
  const int offset = m_comm ? 3 * m_first : 0; // a distributed factorization's steps hold its own rows
  int crossing = 0;
  for (const h2f::Step &st : m_f->steps) {
    std::set<int> seen;
    for (const std::vector<int> *v : {&st.box, &st.S, &st.R, &st.I})
      for (int g : *v) seen.insert(part_of_dof[g + offset]);
    crossing += seen.size() > 1;
  }
  return crossing;
}

void H2Factorization::solve(const double *b, double *x) const
{
  PhaseScope phase(Phase::H2Solve);
  if (m_comm) throw std::logic_error("H2 factorization: a distributed factorization solves with solve_local");
  const ClusterTree &tree = m_K.tree();
  const int n = tree.num_points();
  std::vector<double> y(3 * static_cast<std::size_t>(n)), work;
  for (int k = 0; k < n; ++k)
    for (int a = 0; a < 3; ++a) y[3 * k + a] = b[3 * tree.perm()[k] + a];
  for (const h2f::Step &s : m_f->steps) s.forward(y.data(), work);
  const int nt = static_cast<int>(m_f->top_dofs.size());
  if (nt > 0) {
    work.resize(nt);
    for (int i = 0; i < nt; ++i) work[i] = y[m_f->top_dofs[i]];
    m_f->top.solve(work.data());
    for (int i = 0; i < nt; ++i) y[m_f->top_dofs[i]] = work[i];
  }
  for (auto it = m_f->steps.rbegin(); it != m_f->steps.rend(); ++it) it->backward(y.data(), work);
  // A-hat = A D: x = D y, back in mesh order.
  for (int k = 0; k < n; ++k)
    for (int a = 0; a < 3; ++a) x[3 * tree.perm()[k] + a] = y[3 * k + a] * m_K.col_scale(m_slot[3 * k + a]);
}

void H2Factorization::solve_local(const double *b, double *x) const
{
  PhaseScope phase(Phase::H2Solve);
  if (!m_comm) throw std::logic_error("H2 factorization: solve_local needs a distributed factorization");
  const RankComm &comm = *m_comm;
  const int P = comm.size(), me = comm.rank();
  const std::size_t n = 3 * static_cast<std::size_t>(m_count);
  std::vector<double> y, work;
  if (m_f->spread) { // every rank holds the top's right-hand side whole, and solves its part
    std::vector<double> t;
    collectively(comm, [&] {
      y.assign(b, b + n);
      t.assign(static_cast<std::size_t>(m_f->spread->size()), 0.0);
      for (const h2f::Step &s : m_f->steps) s.forward(y.data(), work);
      for (std::size_t i = 0; i < m_f->top_own.size(); ++i) t[m_f->top_pos[i]] = y[m_f->top_own[i]];
    });
    comm.sum(t.data(), static_cast<int>(t.size()));
    m_f->spread->solve(t.data());
    collectively(comm, [&] {
      for (std::size_t i = 0; i < m_f->top_own.size(); ++i) y[m_f->top_own[i]] = t[m_f->top_pos[i]];
      for (auto it = m_f->steps.rbegin(); it != m_f->steps.rend(); ++it) it->backward(y.data(), work);
      for (std::size_t i = 0; i < n; ++i) x[i] = y[i] * m_K.col_scale(m_slot[3 * static_cast<std::size_t>(m_first) + i]);
    });
    return;
  }
  std::vector<std::vector<double>> send, recv;
  collectively(comm, [&] {
    y.assign(b, b + n);
    send.resize(P);
    recv.resize(P);
    for (const h2f::Step &s : m_f->steps) s.forward(y.data(), work);
    const std::vector<int> &own = m_f->top_own;
    if (me != 0)
      for (int i : own) send[0].push_back(y[i]);
    else
      for (int q = 1; q < P; ++q) recv[q].resize(m_f->top_from[q].size());
  });
  comm.exchange(send, recv); // the top's right-hand side to rank 0
  collectively(comm, [&] {
    for (auto &v : send) v.clear();
    if (me != 0) {
      recv[0].assign(m_f->top_own.size(), 0.0);
      return;
    }
    const std::vector<std::vector<int>> &from = m_f->top_from;
    std::vector<double> t(m_f->top_dofs.size());
    for (std::size_t i = 0; i < from[0].size(); ++i) t[from[0][i]] = y[m_f->top_own[i]];
    for (int q = 1; q < P; ++q)
      for (std::size_t i = 0; i < from[q].size(); ++i) t[from[q][i]] = recv[q][i];
    if (!t.empty()) m_f->top.solve(t.data());
    for (std::size_t i = 0; i < from[0].size(); ++i) y[m_f->top_own[i]] = t[from[0][i]];
    for (int q = 1; q < P; ++q) {
      for (int pos : from[q]) send[q].push_back(t[pos]);
      std::vector<double>().swap(recv[q]); // nothing comes back to rank 0
    }
  });
  comm.exchange(send, recv); // and its unknowns back
  collectively(comm, [&] {
    if (me != 0)
      for (std::size_t i = 0; i < m_f->top_own.size(); ++i) y[m_f->top_own[i]] = recv[0][i];
    for (auto it = m_f->steps.rbegin(); it != m_f->steps.rend(); ++it) it->backward(y.data(), work);
    // A-hat = A D: x = D y (this rank's rows).
    for (std::size_t i = 0; i < n; ++i) x[i] = y[i] * m_K.col_scale(m_slot[3 * static_cast<std::size_t>(m_first) + i]);
  });
}

} // namespace hssbem

namespace hssbem {

double h2_top_peak_bytes(const H2FactorOptions &o, long long unknowns, long long top_unknowns, int ranks)
{
  const double n2 = static_cast<double>(top_unknowns) * static_cast<double>(top_unknowns);
  // As the factorization decides (single_store): panels in single precision, and levels below the top.
  const bool single_panels = (o.single_panels < 0 ? o.rel_tol >= 1e-5 : o.single_panels == 1) && unknowns > o.top_size;
  const bool reduced = top_in_single(static_cast<double>(top_unknowns), o);
  const double vectors = 32.0 * static_cast<double>(top_unknowns); // pivots, offsets, the trial's and the solves' vectors
  if (!reduced) return 16 * n2 + vectors;
  if (!single_panels) return 12 * n2 + vectors;
  if (ranks > 1 && o.spread_top) return 12 * n2 / ranks + vectors;
  return 8 * n2 + vectors;
}

long long h2_top_unknowns_from_options(const H2FactorOptions &o, long long unknowns) { return unknowns <= o.top_size ? unknowns : 0; }

double estimate_inverse_error(const H2Factorization &F, const std::function<void(const double *, double *)> &apply_a, int iterations, unsigned seed)
{
  const std::size_t N = static_cast<std::size_t>(F.num_unknowns());
  std::mt19937_64 gen(seed);
  std::normal_distribution<double> normal;
  std::vector<double> v(N), z(N), w(N);
  for (double &x : v) x = normal(gen);
  const auto norm = [](const std::vector<double> &x) {
    double s = 0;
    for (double e : x) s += e * e;
    return std::sqrt(s);
  };
  double worst = 0;
  for (int it = 0; it < iterations; ++it) {
    const double nv = norm(v);
    if (!(nv > 0)) break;
    F.solve(v.data(), z.data());
    apply_a(z.data(), w.data());
    for (std::size_t i = 0; i < N; ++i) w[i] = v[i] - w[i];
    const double nw = norm(w);
    worst = std::max(worst, nw / nv);
    for (std::size_t i = 0; i < N; ++i) v[i] = w[i] / nw;
  }
  return worst;
}

} // namespace hssbem
