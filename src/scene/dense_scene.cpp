// The dense scene engine of dense_scene.hpp: reference factorization, Woodbury updates with an
// incrementally kept capacitance inverse, refactorization and Krylov, chosen per frame.
#include "hssbem/scene/dense_scene.hpp"

#include "hssbem/core/blas_threads.hpp"
#include "hssbem/core/cluster_tree.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/core/phase.hpp"
#include "hssbem/core/progress.hpp"
#include "hssbem/core/timer.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

namespace hssbem {

namespace {

constexpr double k_inf = std::numeric_limits<double>::infinity();
/// A frame's work (Woodbury solve, incremental capacitance update) runs on OpenMP threads with
/// OpenBLAS kept on one thread (SerialBlas, gemm_over_threads): on the cardioid (1 272 unknowns)
/// OpenMP and OpenBLAS threads spinning against each other made a frame 20x slower (5.6 ms
/// against 0.27 ms). Products over fewer matrix entries than this run on one thread.
constexpr double k_parallel_entries = 1e6;

std::size_t sq(int n) { return static_cast<std::size_t>(n) * n; }

/// Row ranges [first, second) of at most 4096 rows (32 kB of y per thread stays in cache while
/// the columns stream by) over the rows not skipped: runs of at least 256 skipped rows are left
/// out, shorter ones taken along (a chunk of rows streams best whole).
std::vector<std::pair<int, int>> row_chunks(const std::vector<char> &skip)
{
  constexpr int block = 4096, gap = 256;
  const int n = static_cast<int>(skip.size());
  const auto run_at = [&](int r) { // the skipped run starting at r
    int len = 0;
    while (r + len < n && skip[r + len]) ++len;
    return len;
  };
  std::vector<std::pair<int, int>> out;
  for (int r = 0; r < n;) {
    const int run = run_at(r);
    if (run >= gap || r + run == n) {
      r += run;
      continue;
    }
    const int r0 = r;
    for (r += run; r < n && r - r0 < block; ++r) {
      if (!skip[r]) continue;
      const int len = run_at(r);
      if (len >= gap) break;
      r += len - 1;
    }
    out.push_back({r0, std::min(r, n)});
  }
  return out;
}

/// y(rows) += Σ_i coef[i] M(rows, cols[i]) for the column-major n-row matrix M (double, or
/// single precision: the products and sums are in double either way) over the row ranges
/// `chunks`: a gathered product, threaded over the chunks (each thread streams its rows of the
/// chosen columns), eight columns per pass over a chunk (15 078 × 3 015 in single precision: 6.4
/// against 7.0 ms with four, two cores).
template <class T>
void gather_axpy(const T *M, int n, const std::vector<int> &cols, const std::vector<double> &coef, double *y, const std::vector<std::pair<int, int>> &chunks)
{
  if (cols.empty()) return;
  constexpr int width = 8;
  const int nb = static_cast<int>(chunks.size());
  const std::size_t nc = cols.size();
#pragma omp parallel for schedule(static) if (static_cast<double>(n) * nc > k_parallel_entries)
  for (int b = 0; b < nb; ++b) {
    const int r0 = chunks[b].first, r1 = chunks[b].second;
    std::size_t i = 0;
    for (; i + width <= nc; i += width) {
      const T *m[width];
      double c[width];
      for (int q = 0; q < width; ++q) m[q] = M + static_cast<std::size_t>(cols[i + q]) * n, c[q] = coef[i + q];
      for (int r = r0; r < r1; ++r) {
        double sum = 0;
        for (int q = 0; q < width; ++q) sum += c[q] * static_cast<double>(m[q][r]);
        y[r] += sum;
      }
    }
    for (; i < nc; ++i) {
      const T *m = M + static_cast<std::size_t>(cols[i]) * n;
      const double c = coef[i];
      for (int r = r0; r < r1; ++r) y[r] += c * static_cast<double>(m[r]);
    }
  }
}

template <class T>
void gather_axpy(const T *M, int n, const std::vector<int> &cols, const std::vector<double> &coef, double *y)
{
  gather_axpy(M, n, cols, coef, y, row_chunks(std::vector<char>(n, 0)));
}

bool has_pressure(const SystemSelection &sel, int node) { return !sel.pressure.empty() && !std::isnan(sel.pressure[node]); }

/// Whether a frame reads W's column j (3 · node + component): it switches the unknown (u known
/// differs from the reference's), or loads it with a non-zero known value that is not the
/// traction of a pressure load (that one goes through W_p). Sets *loads to the second case.
bool reads_column(const SystemSelection &sel, int j, bool u_known, bool reference_u_known, bool *loads)
{
  const int node = j / 3;
  *loads = u_known == reference_u_known && sel.known[node][j % 3] != 0.0 && !(!u_known && has_pressure(sel, node));
  return u_known != reference_u_known || *loads;
}

} // namespace

const char *scene_strategy_name(SceneStrategy s)
{
  switch (s) {
  case SceneStrategy::Auto: return "auto";
  case SceneStrategy::Solve: return "solve";
  case SceneStrategy::Update: return "update";
  case SceneStrategy::Refactor: return "refactor";
  case SceneStrategy::Krylov: return "krylov";
  }
  return "?";
}

std::optional<SceneStrategy> parse_scene_strategy(const std::string &s)
{
  for (SceneStrategy t : {SceneStrategy::Auto, SceneStrategy::Solve, SceneStrategy::Update, SceneStrategy::Refactor, SceneStrategy::Krylov})
    if (s == scene_strategy_name(t)) return t;
  return std::nullopt;
}

void mark_scene_candidates(const SystemSelection &reference, const SystemSelection &frame, std::vector<char> &candidates)
{
  const std::size_t nodes = reference.displacement_known.size();
  if (frame.displacement_known.size() != nodes || frame.known.size() != nodes) throw std::invalid_argument("mark_scene_candidates: the frame does not match the reference's nodes");
  candidates.resize(3 * nodes, 0);
  bool loads = false;
  for (std::size_t node = 0; node < nodes; ++node)
    for (int a = 0; a < 3; ++a)
      if (reads_column(frame, static_cast<int>(3 * node + a), frame.displacement_known[node][a], reference.displacement_known[node][a], &loads)) candidates[3 * node + a] = 1;
}

DenseScene::DenseScene(const BemOperator &op, const SystemSelection &reference, const SceneOptions &options, std::unique_ptr<KrylovSolver> krylov)
    : m_n(3 * op.num_nodes()), m_nodes(op.num_nodes()), m_opt(options), m_krylov(std::move(krylov)), m_cap(nullptr, 3 * op.num_nodes(), options.single_from)
{
  const Timer timer;
  if (static_cast<int>(reference.displacement_known.size()) != m_nodes) throw std::invalid_argument("DenseScene: the reference pattern does not match the operator's nodes");
  if (m_opt.refresh_every < 1) throw std::invalid_argument("DenseScene: refresh_every must be at least 1");
  const Progress progress("scene set-up"); // the reference LU (~1/4 of the flops), W = A0^-1 K0' (~3/4)
  {
    const PhaseScope phase(Phase::SceneSetup);
    factor_reference(op, reference, progress);
    measure_rates();
  }
  finish_set_up(op);
  progress.report(0.95);
  m_setup_seconds = timer.seconds();
}

DenseScene::DenseScene(const BemOperator &op, Saved saved, const SceneOptions &options, std::unique_ptr<KrylovSolver> krylov)
    : m_n(3 * op.num_nodes()), m_nodes(op.num_nodes()), m_opt(options), m_krylov(std::move(krylov)), m_cap(nullptr, 3 * op.num_nodes(), options.single_from)
{
  const Timer timer;
  auto require = [](bool ok, const char *what) {
    if (!ok) throw std::invalid_argument(std::string("DenseScene: the saved set-up does not fit: ") + what);
  };
  require(saved.reference && saved.reference->num_unknowns() == m_n, "the reference's unknowns");
  require(m_opt.candidates.empty() || static_cast<int>(m_opt.candidates.size()) == m_n, "one candidate flag per unknown");
  require(saved.reference->has_operator() == m_opt.keep_operator, "H and G kept or not as the options say");
  m_reference = std::move(saved.reference);
  m_ref = m_reference->pattern();
  const std::size_t kept = candidate_columns().size();
  require(saved.W.size() == static_cast<std::size_t>(m_n) * kept, "W's columns are the candidates'");
  require(saved.Wp.size() == (m_opt.with_pressure ? static_cast<std::size_t>(m_n) * m_nodes : 0), "W_p as the options' pressure says");
  m_W = std::move(saved.W), m_Wp = std::move(saved.Wp);
  m_bandwidth = saved.rates[0], m_flops = saved.rates[1], m_lu_flops = saved.rates[2];
  finish_set_up(op);
  m_setup_seconds = timer.seconds();
}

void DenseScene::finish_set_up(const BemOperator &op)
{
  single_copy(op);
  m_cap = CapacitanceInverse(std::make_shared<StoredColumns>(m_W.data(), m_n, &m_wcol), m_n, m_opt.single_from);
  m_cap.rebuild({});
  m_cap_pattern = m_ref;
}

DenseScene::~DenseScene() = default;

std::vector<int> DenseScene::stored(const std::vector<int> &js) const
{
  std::vector<int> out(js.size());
  for (std::size_t p = 0; p < js.size(); ++p) out[p] = m_wcol[js[p]];
  return out;
}

void DenseScene::check_candidates(const SystemSelection &sel, const std::vector<char> &pattern) const
{
  if (m_opt.candidates.empty()) return;
  bool loads = false;
  for (int j = 0; j < m_n; ++j)
    if (m_wcol[j] < 0 && reads_column(sel, j, pattern[j], m_ref[j], &loads))
      throw std::invalid_argument("scene frame: node " + std::to_string(j / 3) + " component " + std::to_string(j % 3) + (loads ? " carries a known value" : " switches its boundary condition") +
                                  " but is not among the scene's candidates (SceneOptions::candidates)");
}

std::vector<char> DenseScene::pattern_of(const SystemSelection &sel) const
{
  if (static_cast<int>(sel.displacement_known.size()) != m_nodes || static_cast<int>(sel.known.size()) != m_nodes)
    throw std::invalid_argument("scene frame: the boundary conditions do not match the scene's nodes");
  std::vector<char> p(m_n);
  for (int j = 0; j < m_n; ++j) p[j] = sel.displacement_known[j / 3][j % 3] ? 1 : 0;
  return p;
}

/// The reference factorization (reference.hpp), W = A₀⁻¹ K₀' (the candidates' columns) and W_p = A₀⁻¹ Gn.
void DenseScene::factor_reference(const BemOperator &op, const SystemSelection &reference, const Progress &progress)
{
  const int N = m_n;
  m_ref = pattern_of(SystemSelection{reference.displacement_known, std::vector<Vec3>(m_nodes), {}});
  DenseReferenceOptions ro;
  ro.with_pressure = m_opt.with_pressure;
  const Timer t_reference;
  m_reference = std::make_unique<DenseReference>(op, m_ref, ro);
  m_reference_seconds = t_reference.seconds();
  progress.report(0.25);
  if (!m_opt.candidates.empty() && static_cast<int>(m_opt.candidates.size()) != N) throw std::invalid_argument("DenseScene: one candidate flag per unknown");
  const std::vector<int> kept = candidate_columns();
  const Timer t_columns;
  m_W.resize(static_cast<std::size_t>(N) * kept.size());
  m_reference->columns(kept, m_W.data());
  m_columns_seconds = t_columns.seconds();
  progress.report(0.9);
  if (m_opt.with_pressure) {
    m_Wp.resize(static_cast<std::size_t>(N) * m_nodes);
    std::vector<int> nodes(m_nodes);
    std::iota(nodes.begin(), nodes.end(), 0);
    m_reference->pressure_columns(nodes, m_Wp.data());
  }
  if (!m_opt.keep_operator) m_reference->drop_operator(); // W and A₀ hold what the Woodbury path needs
}

std::vector<int> DenseScene::candidate_columns()
{
  std::vector<int> kept;
  m_wcol.assign(m_n, -1);
  for (int j = 0; j < m_n; ++j)
    if (m_opt.candidates.empty() || m_opt.candidates[j]) m_wcol[j] = static_cast<int>(kept.size()), kept.push_back(j);
  return kept;
}

/// W's single-precision copy for the fields: its rows in cluster order (core/cluster_tree.hpp),
/// room for every stored column (pages are touched only when a column is converted), and every
/// column converted now when the scene was given its candidates (they are the columns its
/// frames use: no frame pays for converting, 0.3 s of the 10k organ's first contact before).
void DenseScene::single_copy(const BemOperator &op)
{
  const int columns = static_cast<int>(m_W.size() / m_n);
  if (m_n < m_opt.single_fields_from || columns < m_opt.single_fields_from) return;
  std::vector<Vec3> points(m_nodes);
  for (int i = 0; i < m_nodes; ++i) points[i] = op.discretization().node_position(i);
  const ClusterTree tree(points);
  m_row_order.resize(m_n);
  m_row_position.resize(m_n);
  for (int k = 0; k < m_nodes; ++k)
    for (int a = 0; a < 3; ++a) m_row_order[3 * k + a] = 3 * tree.perm()[k] + a;
  for (int r = 0; r < m_n; ++r) m_row_position[m_row_order[r]] = r;
  m_Wf.reset(new float[m_W.size()]);
  m_wf_ready.assign(columns, 0);
  if (m_opt.candidates.empty()) return;
  std::vector<int> all(columns);
  std::iota(all.begin(), all.end(), 0);
  single_columns(all);
}

/// The cost model's rates: a gathered product over all of W's columns (bytes/s), a GEMM (flop/s).
void DenseScene::measure_rates()
{
  const int N = m_n;
  std::vector<int> cols(m_W.size() / N); // every stored column
  std::iota(cols.begin(), cols.end(), 0);
  std::vector<double> coef(N, 1e-3), y(N, 0.0);
  double best = k_inf;
  for (int rep = 0; rep < 3 && !cols.empty(); ++rep) { // no candidates: the default rate stays
    const Timer t;
    gather_axpy(m_W.data(), N, cols, coef, y.data());
    best = std::min(best, t.seconds());
  }
  if (!cols.empty()) m_bandwidth = 8.0 * static_cast<double>(m_W.size()) / std::max(best, 1e-7);
  const int m = std::min(N, 384);
  std::vector<double> A(sq(m), 1e-3), B(sq(m), 2e-3), C(sq(m), 0.0);
  best = k_inf;
  for (int rep = 0; rep < 3; ++rep) {
    const Timer t;
    lapack::gemm('N', 'N', m, m, m, 1.0, A.data(), m, B.data(), m, 0.0, C.data(), m);
    best = std::min(best, t.seconds());
  }
  m_flops = 2.0 * m * sq(m) / std::max(best, 1e-7);
  m_lu_flops = 0.8 * m_flops; // LAPACK's blocked LU at these sizes runs at about 80 % of GEMM
}

void DenseScene::reference_solve(const SystemSelection &sel, const std::vector<char> &pattern, std::vector<double> &y) const
{
  y.assign(m_n, 0.0);
  std::vector<int> cols, pcols; // W's stored columns, W_p's
  std::vector<double> coef, pcoef;
  for (int j = 0; j < m_n; ++j) {
    const int node = j / 3;
    if (!pattern[j] && has_pressure(sel, node)) continue; // traction of a pressure load: through W_p
    const double v = sel.known[node][j % 3];
    if (pattern[j] != m_ref[j]) y[j] -= v;
    else if (v != 0.0) cols.push_back(m_wcol[j]), coef.push_back(-v); // a candidate (check_candidates)
  }
  for (int node = 0; node < m_nodes; ++node)
    if (has_pressure(sel, node)) pcols.push_back(node), pcoef.push_back(-sel.pressure[node]);
  if (!pcols.empty() && m_Wp.empty()) throw std::invalid_argument("scene frame: pressure loads need a scene set up with pressure (SceneOptions::with_pressure)");
  gather_axpy(m_W.data(), m_n, cols, coef, y.data());
  gather_axpy(m_Wp.data(), m_n, pcols, pcoef, y.data());
}

void DenseScene::woodbury_solve(const SystemSelection &sel, const std::vector<char> &pattern, std::vector<double> &x) const
{
  reference_solve(sel, pattern, x);
  capacitance_correct(x.data());
}

void DenseScene::capacitance_correct(double *y) const
{
  const std::vector<int> &J = m_cap.indices();
  const int k = m_cap.size();
  std::vector<double> yJ(k), s(k), minus_s(k);
  for (int p = 0; p < k; ++p) yJ[p] = y[J[p]];
  const Timer t_cap;
  capacitance_solve(yJ.data(), s.data());
  m_cap_seconds += t_cap.seconds();
  const Timer t_fields;
  if (k >= m_opt.single_fields_from) single_fields_correct(s, y);
  else {
    for (int p = 0; p < k; ++p) minus_s[p] = -s[p];
    gather_axpy(m_W.data(), m_n, stored(J), minus_s, y);
    for (int p = 0; p < k; ++p) y[J[p]] += s[p];
  }
  m_fields_seconds += t_fields.seconds();
}

/// The same product from W's single-precision copy, over the rows outside J only: the switched
/// rows get x(J) = s. In exact arithmetic x(J) = y(J) − C s + s, and y(J) − C s is the refined
/// capacitance residual (≤ 1e-10 ‖y(J)‖, capacitance.hpp), so they keep that accuracy. The
/// copy's rows are in cluster order, where J (a contact patch) falls in runs of rows that the
/// product skips (row_chunks).
void DenseScene::single_fields_correct(const std::vector<double> &s, double *y) const
{
  const std::vector<int> &J = m_cap.indices();
  const int k = m_cap.size(), n = m_n;
  const std::vector<int> cols = stored(J);
  single_columns(cols);
  std::vector<char> skip(n, 0);
  for (int j : J) skip[m_row_position[j]] = 1;
  std::vector<double> minus_s(k), z(n, 0.0);
  for (int p = 0; p < k; ++p) minus_s[p] = -s[p];
  gather_axpy(m_Wf.get(), n, cols, minus_s, z.data(), row_chunks(skip));
  for (int r = 0; r < n; ++r)
    if (!skip[r]) y[m_row_order[r]] += z[r];
  for (int p = 0; p < k; ++p) y[J[p]] = s[p];
}

void DenseScene::single_columns(const std::vector<int> &cols) const
{
  std::vector<int> missing;
  for (int c : cols)
    if (!m_wf_ready[c]) missing.push_back(c);
  const std::size_t n = static_cast<std::size_t>(m_n);
#pragma omp parallel for schedule(static) if (missing.size() > 8)
  for (std::size_t q = 0; q < missing.size(); ++q) {
    const double *w = &m_W[static_cast<std::size_t>(missing[q]) * n];
    float *f = &m_Wf[static_cast<std::size_t>(missing[q]) * n];
    for (std::size_t i = 0; i < n; ++i) f[i] = static_cast<float>(w[m_row_order[i]]);
  }
  for (int c : missing) m_wf_ready[c] = 1;
}

void DenseScene::capacitance_solve(const double *r, double *s) const
{
  const bool ok = m_cap.solve(r, s);
  m_last_refinements += m_cap.last_iterations();
  if (ok) return;
  const std::vector<int> J = m_cap.indices(); // single precision no longer enough: rebuild in double
  m_cap.rebuild(J, true);
  m_cap.solve(r, s);
  m_last_refinements += m_cap.last_iterations();
}

double DenseScene::predict_update(const std::vector<char> &pattern, bool *rebuild) const
{
  long long drop = 0, add = 0, k_new = 0;
  for (int j = 0; j < m_n; ++j) {
    const bool now = pattern[j] != m_ref[j], before = m_cap_pattern[j] != m_ref[j];
    k_new += now;
    drop += before && !now;
    add += now && !before;
  }
  const double inc = CapacitanceInverse::update_flops(m_cap.size(), drop, add), full = CapacitanceInverse::rebuild_flops(k_new);
  // A single-precision inverse is refined against the exact C at every solve, which also notices
  // when rounding has built up (capacitance_solve then rebuilds): it can go 4x longer.
  const bool must = m_updates_since_rebuild >= m_opt.refresh_every * (m_cap.single() ? 4 : 1);
  *rebuild = must || full <= inc;
  if (drop == 0 && add == 0) *rebuild = false;
  const double flops = (drop == 0 && add == 0) ? 0.0 : (*rebuild ? full : inc);
  const bool single = *rebuild ? k_new >= m_opt.single_from : m_cap.single();
  return flops / (single ? 2 * m_flops : m_flops) + (single ? 3 * 8.0 * static_cast<double>(k_new) * k_new / m_bandwidth : 0.0);
}

void DenseScene::update_capacitance(const std::vector<char> &pattern)
{
  const PhaseScope phase(Phase::SceneUpdate);
  bool rebuild = false;
  predict_update(pattern, &rebuild);
  std::vector<int> drop, add, J;
  for (int j = 0; j < m_n; ++j) {
    const bool now = pattern[j] != m_ref[j], before = m_cap_pattern[j] != m_ref[j];
    if (now) J.push_back(j);
    if (before && !now) drop.push_back(j);
    if (now && !before) add.push_back(j);
  }
  m_report.rebuilt = rebuild;
  if (!rebuild) {
    try {
      const SerialBlas serial; // the update's products run on OpenMP threads (gemm_over_threads)
      m_cap.update(drop, add);
      ++m_updates_since_rebuild;
    } catch (const std::runtime_error &) { // a singular Schur complement on the way: start afresh
      rebuild = m_report.rebuilt = true;
    }
  }
  if (rebuild) {
    m_cap.rebuild(J); // throws when W(J, J) itself is singular: the pattern's system is
    m_updates_since_rebuild = 0;
  }
  m_cap_pattern = pattern;
}

void DenseScene::rhs(const SystemSelection &sel, const std::vector<char> &pattern, std::vector<double> &b) const { m_reference->rhs(sel, pattern, b); }

void DenseScene::apply_system(const std::vector<char> &pattern, const double *x, double *y) const { m_reference->apply(pattern, x, y); }

void DenseScene::refactor(const SystemSelection &sel, const std::vector<char> &pattern, std::vector<double> &x)
{
  const PhaseScope phase(Phase::SceneRefactor);
  if (!m_reference->has_operator()) throw std::invalid_argument("scene: refactor needs the operator (SceneOptions::keep_operator)");
  const int N = m_n;
  m_lu_pattern.clear();
  m_lu.resize(sq(N));
  m_reference->system_matrix(pattern, m_lu.data());
  m_piv.resize(N);
  const int info = lapack::getrf(N, m_lu.data(), N, m_piv.data());
  if (info != 0) throw std::runtime_error("scene frame: the system is singular (LU pivot " + std::to_string(info) + " is zero)");
  m_lu_pattern = pattern;
  lu_solve(sel, pattern, x);
}

void DenseScene::lu_solve(const SystemSelection &sel, const std::vector<char> &pattern, std::vector<double> &x) const
{
  rhs(sel, pattern, x);
  lapack::getrs('N', m_n, 1, m_lu.data(), m_n, m_piv.data(), x.data(), m_n);
}

void DenseScene::apply_previous(const double *r, double *z) const
{
  if (m_last_factor == Last::Lu) {
    std::copy_n(r, m_n, z);
    lapack::getrs('N', m_n, 1, m_lu.data(), m_n, m_piv.data(), z, m_n);
    return;
  }
  std::copy_n(r, m_n, z); // Woodbury form of the capacitance's pattern: (I + Z E_Jᵀ)⁻¹ A₀⁻¹ r
  m_reference->solve(z, 1);
  capacitance_correct(z);
}

/// A Krylov solve preconditioned by another pattern's inverse converges only when the columns
/// that switched are on one scale: with D = diag(1 for H columns, s for −G columns), s = ‖H‖/‖G‖,
/// the preconditioner is D_S D_prev⁻¹ A_prev⁻¹, so that A_S D_S (A_prev D_prev)⁻¹ = I + a
/// perturbation of the size of the switched columns (unscaled, −G against H columns differ by
/// μ/h, and GMRES stagnated on the cardioid).
void DenseScene::krylov(const SystemSelection &sel, const std::vector<char> &pattern, std::vector<double> &x)
{
  const PhaseScope phase(Phase::SceneKrylov);
  if (!m_krylov) throw std::invalid_argument("scene: the krylov strategy needs a Krylov solver (none was given)");
  std::vector<double> b;
  rhs(sel, pattern, b);
  x.assign(m_n, 0.0);
  if (!m_last_u.empty()) // the previous frame's fields, each unknown taking the quantity it now stands for
    for (int j = 0; j < m_n; ++j) x[j] = pattern[j] ? m_last_t[j / 3][j % 3] : m_last_u[j / 3][j % 3];
  const std::vector<char> prev = m_last_factor == Last::Lu ? m_lu_pattern : m_cap_pattern;
  m_report.iterations = m_krylov->solve(
      m_n, [&](const double *in, double *out) { apply_system(pattern, in, out); },
      [&](const double *in, double *out) {
        apply_previous(in, out);
        for (int j = 0; j < m_n; ++j) // see the comment above
          if (pattern[j] != prev[j]) out[j] *= pattern[j] ? m_reference->operator_scale() : 1.0 / m_reference->operator_scale();
      },
      b.data(),
      x.data(), m_opt.krylov_rtol, m_opt.krylov_max_it);
}

std::array<double, 5> DenseScene::predict(const SystemSelection &sel) const { return predict(sel, pattern_of(sel)); }

std::array<double, 5> DenseScene::predict(const SystemSelection &sel, const std::vector<char> &pattern) const
{
  const double N = m_n, bw = m_bandwidth;
  long long k = 0, nv = 0, changed_cap = 0, changed_prev = 0;
  const std::vector<char> &prev = m_last_factor == Last::Lu && !m_lu_pattern.empty() ? m_lu_pattern : m_cap_pattern;
  for (int j = 0; j < m_n; ++j) {
    k += pattern[j] != m_ref[j];
    nv += sel.known[j / 3][j % 3] != 0.0;
    changed_cap += pattern[j] != m_cap_pattern[j];
    changed_prev += pattern[j] != prev[j];
  }
  // the values' columns of W, the fields' product over W(:, J) (single: W's copy) and the
  // capacitance solve (single: C⁻¹ in float and C in double per refinement step, ~3 steps)
  const double field_bytes = k >= m_opt.single_fields_from ? 4.0 : 8.0, cap_bytes = k >= m_opt.single_from ? 3 * 12.0 : 8.0;
  const double apply = (8.0 * N * static_cast<double>(nv) + field_bytes * N * static_cast<double>(k) + cap_bytes * static_cast<double>(k) * k) / bw;
  const double lu_solve = 16.0 * N * N / bw + 8.0 * N * nv / bw;
  std::array<double, 5> t{};
  t[static_cast<int>(SceneStrategy::Auto)] = k_inf;
  t[static_cast<int>(SceneStrategy::Solve)] = changed_cap == 0 ? apply : (!m_lu_pattern.empty() && m_lu_pattern == pattern ? lu_solve : k_inf);
  bool rebuild = false;
  t[static_cast<int>(SceneStrategy::Update)] = predict_update(pattern, &rebuild) + apply;
  t[static_cast<int>(SceneStrategy::Refactor)] = !m_reference->has_operator() ? k_inf : 16.0 * N * N / bw + 2.0 / 3.0 * N * N * N / m_lu_flops + lu_solve;
  const double its = std::min<double>(static_cast<double>(changed_prev) + 1, m_opt.krylov_max_it);
  const double per_it = 32.0 * N * N / bw + 8.0 * N * static_cast<double>(m_cap.size()) / bw;
  t[static_cast<int>(SceneStrategy::Krylov)] = !m_reference->has_operator() || !m_krylov ? k_inf : its * per_it + 16.0 * N * N / bw;
  for (int s = 1; s < 5; ++s) t[s] *= m_correction[s];
  return t;
}

const SceneFrameReport &DenseScene::solve(const SystemSelection &sel, std::vector<double> &x, SceneStrategy force)
{
  const Timer timer;
  const std::vector<char> pattern = pattern_of(sel);
  check_candidates(sel, pattern);
  const std::array<double, 5> predicted = predict(sel, pattern);
  SceneStrategy s = force != SceneStrategy::Auto ? force : m_opt.strategy;
  const bool same = pattern == m_cap_pattern || (!m_lu_pattern.empty() && pattern == m_lu_pattern);
  if (s == SceneStrategy::Auto) {
    if (same) s = SceneStrategy::Solve;
    else {
      s = SceneStrategy::Update;
      for (SceneStrategy c : {SceneStrategy::Refactor, SceneStrategy::Krylov})
        if (predicted[static_cast<int>(c)] < predicted[static_cast<int>(s)]) s = c;
    }
  }
  if (s == SceneStrategy::Solve && !same)
    throw std::invalid_argument("scene frame: strategy 'solve' reuses a factorization, but the boundary-condition pattern changed (use update, refactor, krylov or auto)");
  m_report = SceneFrameReport{};
  m_report.strategy = s;
  m_last_refinements = 0;
  m_cap_seconds = m_fields_seconds = 0;
  const std::vector<char> &before = m_last_pattern.empty() ? m_ref : m_last_pattern;
  for (int j = 0; j < m_n; ++j) {
    m_report.switched += pattern[j] != m_ref[j];
    m_report.changed += pattern[j] != before[j];
    m_report.values += sel.known[j / 3][j % 3] != 0.0;
  }
  switch (s) {
  case SceneStrategy::Solve: {
    const PhaseScope phase(Phase::SceneApply);
    const SerialBlas serial;
    if (pattern == m_cap_pattern) woodbury_solve(sel, pattern, x);
    else lu_solve(sel, pattern, x);
    break;
  }
  case SceneStrategy::Update: {
    const Timer t_update;
    if (pattern != m_cap_pattern) update_capacitance(pattern);
    m_report.update_seconds = t_update.seconds();
    const PhaseScope phase(Phase::SceneApply);
    const SerialBlas serial;
    woodbury_solve(sel, pattern, x);
    m_last_factor = Last::Woodbury;
    break;
  }
  case SceneStrategy::Refactor:
    refactor(sel, pattern, x);
    m_last_factor = Last::Lu;
    break;
  case SceneStrategy::Krylov: krylov(sel, pattern, x); break;
  case SceneStrategy::Auto: break;
  }
  m_last_pattern = pattern;
  m_last_u.resize(m_nodes);
  m_last_t.resize(m_nodes);
  for (int j = 0; j < m_n; ++j) {
    const double known = sel.known[j / 3][j % 3];
    m_last_u[j / 3][j % 3] = pattern[j] ? known : x[j];
    m_last_t[j / 3][j % 3] = pattern[j] ? x[j] : known;
  }
  m_report.seconds = timer.seconds();
  m_report.refinements = m_last_refinements;
  m_report.capacitance_seconds = m_cap_seconds;
  m_report.fields_seconds = m_fields_seconds;
  m_report.predicted = predicted[static_cast<int>(s)];
  const int si = static_cast<int>(s);
  if (std::isfinite(m_report.predicted) && m_report.predicted > 0 && m_report.seconds > 0) // the model learns from what it measured
    m_correction[si] = std::exp(0.7 * std::log(m_correction[si]) + 0.3 * std::log(m_correction[si] * m_report.seconds / m_report.predicted));
  return m_report;
}

void DenseScene::solve_switched(const SystemSelection &sel, std::vector<double> &out)
{
  const std::vector<char> pattern = pattern_of(sel);
  check_candidates(sel, pattern);
  if (pattern != m_cap_pattern) throw std::invalid_argument("scene: solve_switched needs the pattern of the last update (solve the frame first)");
  const std::vector<int> &J = m_cap.indices();
  const int k = m_cap.size();
  std::vector<double> yJ(k, 0.0);
  for (int p = 0; p < k; ++p) {
    const int j = J[p];
    if (!(!pattern[j] && has_pressure(sel, j / 3))) yJ[p] = -sel.known[j / 3][j % 3];
  }
  for (int j = 0; j < m_n; ++j) {
    const int node = j / 3;
    if (pattern[j] != m_ref[j] || (!pattern[j] && has_pressure(sel, node))) continue;
    const double v = sel.known[node][j % 3];
    if (v == 0.0) continue;
    const double *w = &m_W[static_cast<std::size_t>(m_wcol[j]) * m_n];
    for (int p = 0; p < k; ++p) yJ[p] -= w[J[p]] * v;
  }
  for (int node = 0; node < m_nodes; ++node)
    if (has_pressure(sel, node)) {
      if (m_Wp.empty()) throw std::invalid_argument("scene frame: pressure loads need a scene set up with pressure (SceneOptions::with_pressure)");
      const double *w = &m_Wp[static_cast<std::size_t>(node) * m_n];
      for (int p = 0; p < k; ++p) yJ[p] -= w[J[p]] * sel.pressure[node];
    }
  out.resize(k);
  const SerialBlas serial;
  capacitance_solve(yJ.data(), out.data());
}

double DenseScene::residual(const SystemSelection &sel, const std::vector<double> &x) const
{
  const std::vector<char> pattern = pattern_of(sel);
  std::vector<double> b, Ax(m_n);
  rhs(sel, pattern, b);
  apply_system(pattern, x.data(), Ax.data());
  double r = 0, nb = 0;
  for (int i = 0; i < m_n; ++i) r += (Ax[i] - b[i]) * (Ax[i] - b[i]), nb += b[i] * b[i];
  return nb > 0 ? std::sqrt(r / nb) : std::sqrt(r);
}

std::size_t DenseScene::memory_bytes() const
{
  const std::size_t d = m_W.size() + m_Wp.size() + m_lu.size() + sq(m_cap.size());
  return 8 * d + 4 * static_cast<std::size_t>(m_n) * static_cast<std::size_t>(std::count(m_wf_ready.begin(), m_wf_ready.end(), 1)) + m_reference->memory_bytes();
}

} // namespace hssbem
