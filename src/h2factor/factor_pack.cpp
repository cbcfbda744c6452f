// The H² factorization's stored form and back (see H2Factorization::pack and its unpacking
// constructor): the steps and the top as the factorization left them, so that a solve after a
// load is the one before, bit for bit.
#include "factors.hpp"

#include "hssbem/core/phase.hpp"

#include <stdexcept>
#include <string>

namespace hssbem {

namespace {

[[noreturn]] void damaged(const std::string &what) { throw std::invalid_argument("damaged: " + what); }

enum TopKind { kNoTop = 0, kTopBlock = 1, kSpreadTop = 2 };

void pack_step(PackWriter &w, const h2f::Step &s)
{
  w.put(s.box), w.put(s.D), w.put(s.dpiv);
  w.put(s.S), w.put(s.R), w.put(s.I);
  w.put(s.T), w.put(s.LU), w.put(s.piv);
  w.put(s.Lp), w.put(s.Up), w.put(s.Lps), w.put(s.Ups);
  w.put(s.candidates);
}

/// Indices of this rank's rows (n of them).
void check_rows(const std::vector<int> &v, int n, const char *what)
{
  for (int g : v)
    if (g < 0 || g >= n) damaged(std::string("a step's ") + what + " out of this rank's rows");
}

/// A matrix of rows × cols whose entries are stored (or, with `floats`, in single precision).
void check_matrix(const DenseMatrix &M, std::size_t rows, std::size_t cols, const std::vector<float> *floats, const char *what)
{
  const std::size_t entries = rows * cols;
  const bool held = floats && !floats->empty() ? floats->size() == entries && M.a.empty() : M.a.size() == entries;
  if (static_cast<std::size_t>(M.m) != rows || static_cast<std::size_t>(M.n) != cols || !held) damaged(std::string("a step's ") + what + " does not fit the step");
}

h2f::Step unpack_step(PackReader &r, int n)
{
  h2f::Step s;
  r.get(s.box), r.get(s.D), r.get(s.dpiv);
  r.get(s.S), r.get(s.R), r.get(s.I);
  r.get(s.T), r.get(s.LU), r.get(s.piv);
  r.get(s.Lp), r.get(s.Up), r.get(s.Lps), r.get(s.Ups);
  s.candidates = r.get_int();
  for (const auto &[v, what] : {std::make_pair(&s.box, "box"), std::make_pair(&s.S, "skeleton"), std::make_pair(&s.R, "redundant"), std::make_pair(&s.I, "neighbours")}) check_rows(*v, n, what);
  const std::size_t b = s.box.size(), ks = s.S.size(), kr = s.R.size(), ki = s.I.size();
  // the solve reads what a step's sizes say (elimination_step.cpp): D and its pivots when the box
  // has unknowns, the rest when it has redundant ones (T with a skeleton, the panels with I)
  if (b > 0) check_matrix(s.D, b, b, nullptr, "diagonal block");
  if (s.dpiv.size() != (b > 0 ? b : s.dpiv.size()) || (kr > 0 && s.piv.size() != kr)) damaged("a step's pivots do not fit the step");
  if (kr > 0 && ks > 0) check_matrix(s.T, ks, kr, nullptr, "interpolation");
  if (kr > 0) check_matrix(s.LU, kr, kr, nullptr, "LU");
  if (kr > 0 && ki > 0) check_matrix(s.Lp, ki, kr, &s.Lps, "lower panel");
  if (kr > 0 && ki > 0) check_matrix(s.Up, kr, ki, &s.Ups, "upper panel");
  for (int p : s.dpiv)
    if (p < 1 || p > static_cast<int>(b)) damaged("a step's pivot out of range");
  for (int p : s.piv)
    if (p < 1 || p > static_cast<int>(kr)) damaged("a step's pivot out of range");
  return s;
}

void pack_options(PackWriter &w, const H2FactorOptions &o)
{
  w.put(o.rel_tol);
  w.put(o.leaf_size), w.put(o.sketch_columns), w.put(o.top_size), w.put(o.single_panels), w.put(o.single_top_from);
  w.put(o.top_when_cheaper ? 1 : 0), w.put(o.within_parts ? 1 : 0), w.put(o.spread_top ? 1 : 0);
}

H2FactorOptions unpack_options(PackReader &r)
{
  H2FactorOptions o;
  o.rel_tol = r.get_double();
  o.leaf_size = r.get_int(), o.sketch_columns = r.get_int(), o.top_size = r.get_int(), o.single_panels = r.get_int(), o.single_top_from = r.get_int();
  o.top_when_cheaper = r.get_int(0, 1, "option"), o.within_parts = r.get_int(0, 1, "option"), o.spread_top = r.get_int(0, 1, "option");
  return o;
}

/// The figures, as doubles (their times are the factorization's that made the file).
void pack_stats(PackWriter &w, const H2FactorStats &s)
{
  w.put(static_cast<int>(s.levels.size()));
  for (const H2FactorLevelStats &l : s.levels)
    for (double v : {double(l.level), double(l.boxes), l.mean_candidates, double(l.max_candidates), l.mean_rank, double(l.max_rank), double(l.eliminated), double(l.bytes), l.seconds,
                     double(l.cross_blocks), double(l.cross_bytes)})
      w.put(v);
  for (double v : {double(s.top_size), double(s.top_mixed), double(s.top_single), double(s.top_spread), double(s.bytes), double(s.top_bytes), double(s.workspace_bytes), s.time_sketch, s.time_init,
                   s.time_skeleton, s.time_eliminate, s.time_merge, s.time_top, s.flops_schur, double(s.sketch_columns), double(s.single_panels), double(s.parts), double(s.top_boxes)})
    w.put(v);
}

H2FactorStats unpack_stats(PackReader &r)
{
  H2FactorStats s;
  s.levels.resize(static_cast<std::size_t>(r.get_int(0, 64, "levels")));
  for (H2FactorLevelStats &l : s.levels) {
    l.level = static_cast<int>(r.get_double()), l.boxes = static_cast<int>(r.get_double()), l.mean_candidates = r.get_double(), l.max_candidates = static_cast<int>(r.get_double());
    l.mean_rank = r.get_double(), l.max_rank = static_cast<int>(r.get_double()), l.eliminated = static_cast<long long>(r.get_double()), l.bytes = static_cast<std::size_t>(r.get_double());
    l.seconds = r.get_double(), l.cross_blocks = static_cast<long long>(r.get_double()), l.cross_bytes = static_cast<std::size_t>(r.get_double());
  }
  s.top_size = static_cast<int>(r.get_double()), s.top_mixed = r.get_double() != 0, s.top_single = r.get_double() != 0, s.top_spread = static_cast<int>(r.get_double());
  s.bytes = static_cast<std::size_t>(r.get_double()), s.top_bytes = static_cast<std::size_t>(r.get_double()), s.workspace_bytes = static_cast<std::size_t>(r.get_double());
  s.time_sketch = r.get_double(), s.time_init = r.get_double(), s.time_skeleton = r.get_double(), s.time_eliminate = r.get_double(), s.time_merge = r.get_double();
  s.time_top = r.get_double(), s.flops_schur = r.get_double(), s.sketch_columns = static_cast<int>(r.get_double()), s.single_panels = r.get_double() != 0;
  s.parts = static_cast<int>(r.get_double()), s.top_boxes = static_cast<int>(r.get_double());
  return s;
}

} // namespace

void H2Factorization::pack(PackWriter &w) const
{
  const Factors &f = *m_f;
  w.put(m_comm->size()), w.put(m_comm->rank()), w.put(m_first), w.put(m_count);
  pack_options(w, m_options);
  w.put(f.pattern.slot), w.put(f.pattern.sign), w.put(f.pattern.phi), w.put(f.pattern.psi), w.put(f.pattern.c);
  w.put(static_cast<int>(f.steps.size()));
  for (const h2f::Step &s : f.steps) pack_step(w, s);
  w.put(f.spread ? 1 : 0), w.put(f.top_n), w.put(f.top_own), w.put(f.top_pos);
  if (const auto *t = dynamic_cast<const h2f::TopBlock *>(f.top.get())) {
    w.put(int(kTopBlock));
    t->pack(w);
  } else if (const auto *t = dynamic_cast<const h2f::SpreadTop *>(f.top.get())) {
    w.put(int(kSpreadTop));
    t->pack(w);
  } else {
    w.put(int(kNoTop));
  }
  pack_stats(w, m_stats);
}

H2Factorization::H2Factorization(const H2Matrix &K, const RankComm &comm, int first, int count, PackReader &r) : m_K(K), m_comm(&comm), m_first(first), m_count(count)
{
  PhaseScope whole(Phase::H2Factorization);
  const int N = 3 * K.tree().num_points(), n = 3 * count;
  collectively<std::invalid_argument>(comm, [&] {
    m_f = std::make_unique<Factors>();
    if (r.get_int() != comm.size() || r.get_int() != comm.rank() || r.get_int() != first || r.get_int() != count) damaged("the factors are another rank's");
    m_options = unpack_options(r);
    Factors &f = *m_f;
    r.get(f.pattern.slot), r.get(f.pattern.sign), r.get(f.pattern.phi), r.get(f.pattern.psi);
    f.pattern.c = r.get_double();
    if (f.pattern.dofs() != N || f.pattern.sign.size() != f.pattern.slot.size() || f.pattern.phi.size() != f.pattern.psi.size() || (!f.pattern.phi.empty() && f.pattern.phi.size() != 6u * N))
      damaged("the pattern does not fit the matrix");
    for (int s : f.pattern.slot)
      if (s < 0 || s >= K.col_block()) damaged("the pattern's slots");
    f.steps.resize(static_cast<std::size_t>(r.get_int(0, INT32_MAX, "steps")));
    for (h2f::Step &s : f.steps) s = unpack_step(r, n);
    f.spread = r.get_int(0, 1, "spread") == 1;
    f.top_n = r.get_int(0, N, "top size");
    r.get(f.top_own), r.get(f.top_pos);
    if (f.top_own.size() != f.top_pos.size()) damaged("the top's rows");
    check_rows(f.top_own, n, "top row");
    check_rows(f.top_pos, f.top_n, "top position");
    const int kind = r.get_int(kNoTop, kSpreadTop, "top kind");
    if (f.spread && kind != kSpreadTop) damaged("the top's kind");
    if (kind == kTopBlock) {
      auto t = std::make_unique<h2f::TopBlock>();
      t->unpack(r);
      f.top = std::move(t);
    } else if (kind == kSpreadTop) {
      auto t = std::make_unique<h2f::SpreadTop>();
      t->unpack(f.spread ? comm : f.one, r);
      f.top = std::move(t);
    }
    m_stats = unpack_stats(r);
    if (!r.done()) damaged("the factors are followed by more");
  });
}

} // namespace hssbem
