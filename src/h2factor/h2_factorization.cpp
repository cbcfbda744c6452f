// The H² factorization: its phases in order, the options and the pattern (see
// h2_factorization.hpp; the levels: factor_levels.cpp, the top: factor_top.cpp, the solve:
// factor_solve.cpp).
#include "factors.hpp"
#include "frontier.hpp"

#include "hssbem/bem/rigid_modes.hpp"
#include "hssbem/compress/pattern_columns.hpp"
#include "hssbem/core/fault.hpp"
#include "hssbem/core/phase.hpp"
#include "hssbem/core/size_limits.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/core/tree_ownership.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>

namespace hssbem {

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
  FarFieldSketch s = m_dist ? far_field_sketch(*m_dist, p) : far_field_sketch(*m_K, p);
  collectively(comm(), [&] { m_sketches.push_back(std::make_unique<FarFieldSketch>(std::move(s))); });
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
/// nodes. With leaf_size 0 the leaves' level, or below rel_tol 1e-5 the level above it, where a
/// leaf's skeleton keeps most of its unknowns (docs/h2-factorization.md).
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

} // namespace

H2Factorization::H2Factorization(H2FactorCache &cache, const SystemSelection &sel, const H2FactorOptions &options, const std::vector<double> *rigid_modes)
  : m_K(cache.matrix()), m_comm(&cache.comm()), m_options(options)
{
  PhaseScope whole(Phase::H2Factorization);
  const FarFieldSketch &sketch = prepare(cache, sel, rigid_modes);
  const ClusterTree &tree = m_K.tree();
  Timer timer;
  // Blocks rest in single precision with the panels, unless everything goes to the dense top at
  // once: its singularity test (a pure-traction pattern without regularisation) needs them exact.
  const bool single_store = m_stats.single_panels && m_f->pattern.dofs() > m_options.top_size, parts = m_stats.parts > 1;
  std::vector<int> part;
  if (parts) part = collectively(*m_comm, [&] { return cluster_parts(tree); });
  std::optional<h2f::Frontier> front; // no allocation of its own before its collective construction
  front.emplace(m_K, sketch, m_f->pattern, single_store, std::move(part), *m_comm);
  const int last = last_level(tree, parts), l0 = std::max(first_level(tree, m_options.leaf_size, m_options.rel_tol), last);
  for (int l = tree.levels() - 1; l > l0; --l) front->merge(l);
  m_stats.time_init = timer.seconds();
  eliminate_levels(*front, l0, last);
  factor_top(front, single_store);
  m_stats.bytes = m_stats.top_bytes;
  for (const H2FactorLevelStats &ls : m_stats.levels) m_stats.bytes += ls.bytes;
}

const FarFieldSketch &H2Factorization::prepare(H2FactorCache &cache, const SystemSelection &sel, const std::vector<double> *rigid_modes)
{
  const ClusterTree &tree = m_K.tree();
  const int P = m_comm->size();
  collectively(*m_comm, [&] {
    m_f = std::make_unique<Factors>();
    check_options(m_options);
    if (P > 1 && tree.num_parts() != P) throw std::invalid_argument("H2 factorization: the tree has " + std::to_string(tree.num_parts()) + " parts for " + std::to_string(P) + " ranks");
    m_first = cache.first_point();
    m_count = cache.num_points();
  });
  m_options.within_parts = tree.num_parts() > 1 && (P > 1 || m_options.within_parts); // one rank with parts: as several would
  if (m_options.within_parts) m_stats.parts = tree.num_parts();
  const int p = m_options.sketch_columns > 0 ? m_options.sketch_columns : default_sketch_columns(m_options.rel_tol);
  const FarFieldSketch *sketch;
  {
    PhaseScope phase(Phase::H2Sketch);
    sketch = &cache.sketch(p, &m_stats.time_sketch); // collective
  }
  m_stats.sketch_columns = p;
  m_stats.single_panels = h2_single_panels(m_options.rel_tol, m_options.single_panels);
  collectively(*m_comm, [&] {
    fault_point("H2FSubtree"); // each rank's elimination of its part starts
    m_f->pattern = make_pattern(m_K, sel, rigid_modes);
  });
  return *sketch;
}

H2Factorization::~H2Factorization() = default;

double H2Factorization::top_trial() const { return m_f->top ? m_f->top->trial_error() : 0.0; }

int H2Factorization::steps_crossing_parts() const
{
  const ClusterTree &tree = m_K.tree();
  std::vector<int> part_of_dof(3 * static_cast<std::size_t>(tree.num_points()), 0);
  for (int p = 0; p < tree.num_parts(); ++p) {
    const Cluster &c = tree.cluster(tree.part_cluster(p));
    std::fill(part_of_dof.begin() + 3L * c.begin, part_of_dof.begin() + 3L * c.end, p);
  }
  const int offset = 3 * m_first; // the steps hold this rank's own rows
  int crossing = 0;
  for (const h2f::Step &st : m_f->steps) {
    std::set<int> seen;
    for (const std::vector<int> *v : {&st.box, &st.S, &st.R, &st.I})
      for (int g : *v) seen.insert(part_of_dof[g + offset]);
    crossing += seen.size() > 1;
  }
  return crossing;
}

} // namespace hssbem
