// The dense reference factorization of reference.hpp: H and G assembled by row chunks on the
// OpenMP threads, A₀ = LU, and W's columns by blocked getrs; the column cache.
#include "hssbem/reference/reference.hpp"

#include "hssbem/core/lapack.hpp"
#include "hssbem/core/timer.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <numeric>
#include <stdexcept>
#include <string>
#include <unordered_set>

namespace hssbem {

namespace {

std::size_t sq(int n) { return static_cast<std::size_t>(n) * n; }

bool has_pressure(const SystemSelection &sel, int node) { return !sel.pressure.empty() && !std::isnan(sel.pressure[node]); }

/// y += Σ_i coef[i] M(:, cols[i]) for the column-major n-row matrix M.
void add_columns(const std::vector<double> &M, int n, const std::vector<int> &cols, const std::vector<double> &coef, double *y)
{
  for (std::size_t i = 0; i < cols.size(); ++i) {
    const double *m = &M[static_cast<std::size_t>(cols[i]) * n];
    const double c = coef[i];
#pragma omp parallel for schedule(static) if (n > 20000)
    for (int r = 0; r < n; ++r) y[r] += c * m[r];
  }
}

} // namespace

DenseReference::DenseReference(const BemOperator &op, std::vector<char> pattern, const DenseReferenceOptions &options)
    : m_n(3 * op.num_nodes()), m_nodes(op.num_nodes()), m_opt(options)
{
  m_d.pattern = std::move(pattern);
  if (static_cast<int>(m_d.pattern.size()) != m_n) throw std::invalid_argument("DenseReference: the pattern needs one entry per unknown");
  check_options();
  assemble(op);
  if (!m_opt.node_body.empty()) separate_bodies(op);
  factor();
  if (!m_opt.keep_operator) drop_operator();
}

namespace {

/// Throws std::invalid_argument "DenseReference: the saved <what> do not fit" unless ok.
void require_fit(bool ok, const char *what)
{
  if (!ok) throw std::invalid_argument(std::string("DenseReference: the saved ") + what + " do not fit the reference");
}

} // namespace

DenseReference::DenseReference(DenseReferenceData data) : m_n(static_cast<int>(data.pattern.size())), m_nodes(m_n / 3), m_d(std::move(data))
{
  const std::size_t N = static_cast<std::size_t>(m_n);
  require_fit(m_n > 0 && m_n % 3 == 0, "pattern's entries");
  require_fit(m_d.lu.size() == N * N && m_d.piv.size() == N, "factors");
  require_fit(std::all_of(m_d.piv.begin(), m_d.piv.end(), [&](int p) { return p >= 1 && p <= m_n; }), "pivots");
  require_fit(m_d.H.size() == m_d.G.size() && (m_d.H.empty() || m_d.H.size() == N * N), "operator's columns");
  require_fit(m_d.Gn.empty() || m_d.Gn.size() == N * m_nodes, "pressure columns");
  const long long kept = std::count_if(m_d.kpos.begin(), m_d.kpos.end(), [](int k) { return k >= 0; });
  require_fit(m_d.kpos.empty() ? m_d.K.empty() : m_d.kpos.size() == N && m_d.K.size() == N * static_cast<std::size_t>(kept), "kept columns");
  std::vector<char> seen(static_cast<std::size_t>(kept), 0);
  for (int k : m_d.kpos) {
    require_fit(k >= -1 && k < kept && (k < 0 || !seen[k]), "kept columns");
    if (k >= 0) seen[k] = 1;
  }
  require_fit(std::all_of(m_d.pattern.begin(), m_d.pattern.end(), [](char c) { return c == 0 || c == 1; }), "pattern's entries");
}

DenseReference::~DenseReference() = default;

void DenseReference::check_options() const
{
  if (!m_opt.reference_columns_only) return;
  if (!m_opt.node_body.empty()) throw std::invalid_argument("DenseReference: reference_columns_only takes one body (CompositeReference keeps bodies apart)");
  if (!m_opt.kept_columns.empty() && static_cast<int>(m_opt.kept_columns.size()) != m_n)
    throw std::invalid_argument("DenseReference: kept_columns needs one entry per unknown");
}

/// Row block r0 .. r0 + rows: H and G into m_d.H and m_d.G, or (reference_columns_only) the columns
/// A₀ uses into m_d.lu and the others, where kept, into m_d.K. sums += ‖H‖², ‖G‖² of the block.
void DenseReference::place_rows(int r0, int rows, const double *H, const double *G, double sums[2])
{
  const int N = m_n;
  const bool compact = m_opt.reference_columns_only;
  for (int r = 0; r < 3 * rows; ++r) {
    const std::size_t row = 3 * static_cast<std::size_t>(r0) + r;
    const double *h = H + static_cast<std::size_t>(r) * N, *g = G + static_cast<std::size_t>(r) * N;
    for (int c = 0; c < N; ++c) {
      const std::size_t at = row + static_cast<std::size_t>(c) * N;
      sums[0] += h[c] * h[c], sums[1] += g[c] * g[c];
      if (!compact) {
        m_d.H[at] = h[c], m_d.G[at] = g[c];
        continue;
      }
      const bool u_known = m_d.pattern[c] != 0; // A₀ takes −G, K₀′ H; else A₀ H, K₀′ −G
      m_d.lu[at] = u_known ? -g[c] : h[c];
      if (m_d.kpos[c] >= 0) m_d.K[row + static_cast<std::size_t>(m_d.kpos[c]) * N] = u_known ? h[c] : -g[c];
    }
  }
}

/// H and G (and Gn) column-major, rows in chunks per thread with their own workspaces.
void DenseReference::assemble(const BemOperator &op)
{
  const int nn = m_nodes, N = m_n, chunk = 8;
  if (m_opt.reference_columns_only) {
    m_d.kpos.assign(N, -1);
    int kept = 0;
    for (int j = 0; j < N; ++j)
      if (m_opt.kept_columns.empty() || m_opt.kept_columns[j]) m_d.kpos[j] = kept++;
    m_d.lu.assign(sq(N), 0.0);
    m_d.K.assign(static_cast<std::size_t>(N) * kept, 0.0);
  } else {
    m_d.H.assign(sq(N), 0.0);
    m_d.G.assign(sq(N), 0.0);
  }
  if (m_opt.with_pressure) m_d.Gn.assign(static_cast<std::size_t>(N) * nn, 0.0);
  double h2 = 0, g2 = 0;
  std::vector<int> J(nn);
  std::iota(J.begin(), J.end(), 0);
  std::exception_ptr failure;
#pragma omp parallel
  {
    std::unique_ptr<BemOperator::Workspace> ws;
    std::vector<double> H, G, Gn;
    try {
      ws = std::make_unique<BemOperator::Workspace>(op);
      H.resize(3 * chunk * static_cast<std::size_t>(N));
      G.resize(H.size());
      if (m_opt.with_pressure) Gn.resize(3 * chunk * static_cast<std::size_t>(nn));
    } catch (...) {
#pragma omp critical(hssbem_reference_assembly)
      if (!failure) failure = std::current_exception();
    }
#pragma omp for schedule(dynamic, 1)
    for (int r0 = 0; r0 < nn; r0 += chunk) {
      if (!ws) continue;
      try {
        std::vector<int> I(std::min(chunk, nn - r0));
        std::iota(I.begin(), I.end(), r0);
        op.fill_hg(I, J, H.data(), G.data(), N, m_opt.with_pressure ? Gn.data() : nullptr, nn, *ws);
        double sums[2] = {0, 0};
        place_rows(r0, static_cast<int>(I.size()), H.data(), G.data(), sums);
#pragma omp atomic
        h2 += sums[0];
#pragma omp atomic
        g2 += sums[1];
        if (m_opt.with_pressure)
          for (std::size_t r = 0; r < 3 * I.size(); ++r)
            for (int c = 0; c < nn; ++c) m_d.Gn[3 * static_cast<std::size_t>(r0) + r + static_cast<std::size_t>(c) * N] = Gn[r * nn + c];
      } catch (...) {
#pragma omp critical(hssbem_reference_assembly)
        if (!failure) failure = std::current_exception();
      }
    }
  }
  if (failure) std::rethrow_exception(failure);
  m_d.scale_t = g2 > 0 ? std::sqrt(h2 / g2) : 1.0;
}

/// With H's row sums zero (a rigid translation gives no traction), the other bodies' part S of
/// row i's sum is exactly what the rigid-body term took from them: S moves onto the columns that
/// carry the term (rigid_body_columns: the node, or a moved node's triangle corners), and the
/// other bodies' entries of H, G and Gn become zero. Each body's rows then sum to zero on their own.
void DenseReference::separate_bodies(const BemOperator &op)
{
  const int N = m_n, nn = m_nodes;
  if (static_cast<int>(m_opt.node_body.size()) != nn) throw std::invalid_argument("DenseReference: node_body needs one entry per dof node");
  const std::vector<int> &body = m_opt.node_body;
#pragma omp parallel for schedule(dynamic, 16)
  for (int i = 0; i < nn; ++i) {
    double S[9] = {0};
    for (int j = 0; j < nn; ++j) {
      if (body[j] == body[i]) continue;
      for (int c = 0; c < 3; ++c) {
        const std::size_t col = static_cast<std::size_t>(3 * j + c) * N;
        for (int k = 0; k < 3; ++k) {
          S[3 * k + c] += m_d.H[col + 3 * i + k];
          m_d.H[col + 3 * i + k] = 0, m_d.G[col + 3 * i + k] = 0;
        }
      }
      if (!m_d.Gn.empty())
        for (int k = 0; k < 3; ++k) m_d.Gn[static_cast<std::size_t>(j) * N + 3 * i + k] = 0;
    }
    int cols[3];
    double w[3];
    const int nc = op.rigid_body_columns(i, cols, w);
    for (int q = 0; q < nc; ++q)
      for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k) m_d.H[static_cast<std::size_t>(3 * cols[q] + c) * N + 3 * i + k] += w[q] * S[3 * k + c];
  }
}

void DenseReference::factor()
{
  const int N = m_n;
  if (!m_opt.reference_columns_only) { // (compact: assembled into place)
    m_d.lu.resize(sq(N));
    system_matrix(m_d.pattern, m_d.lu.data());
  }
  if (!m_opt.node_body.empty()) { // the separated operator's scale
    double h2 = 0, g2 = 0;
    for (std::size_t i = 0; i < m_d.H.size(); ++i) h2 += m_d.H[i] * m_d.H[i], g2 += m_d.G[i] * m_d.G[i];
    m_d.scale_t = g2 > 0 ? std::sqrt(h2 / g2) : 1.0;
  }
  m_d.piv.resize(N);
  const int info = lapack::getrf(N, m_d.lu.data(), N, m_d.piv.data());
  if (info != 0) throw std::runtime_error("scene: the reference pattern's system is singular (LU pivot " + std::to_string(info) + " is zero); the base rules must hold the body");
}

void DenseReference::system_matrix(const std::vector<char> &pattern, double *A) const
{
  if (!has_operator()) throw std::invalid_argument("reference: the system matrix needs the operator (keep_operator)");
  const int N = m_n;
#pragma omp parallel for schedule(static)
  for (int j = 0; j < N; ++j) {
    const double *src = pattern[j] ? &m_d.G[static_cast<std::size_t>(j) * N] : &m_d.H[static_cast<std::size_t>(j) * N];
    double *a = A + static_cast<std::size_t>(j) * N;
    if (pattern[j])
      for (int i = 0; i < N; ++i) a[i] = -src[i];
    else std::copy_n(src, N, a);
  }
}

void DenseReference::drop_operator()
{
  std::vector<double>().swap(m_d.H);
  std::vector<double>().swap(m_d.G);
  std::vector<double>().swap(m_d.Gn);
  std::vector<double>().swap(m_d.K);
  std::vector<int>().swap(m_d.kpos);
}

void DenseReference::solve(double *X, int nrhs) const
{
  if (nrhs > 0) lapack::getrs('N', m_n, nrhs, m_d.lu.data(), m_n, m_d.piv.data(), X, m_n);
}

void DenseReference::reference_column(int j, double *col) const
{
  if (!has_operator()) {
    std::copy_n(&m_d.K[static_cast<std::size_t>(m_d.kpos[j]) * m_n], m_n, col);
    return;
  }
  const std::size_t off = static_cast<std::size_t>(j) * m_n;
  if (m_d.pattern[j]) std::copy_n(&m_d.H[off], m_n, col);
  else
    for (int i = 0; i < m_n; ++i) col[i] = -m_d.G[off + i];
}

void DenseReference::columns(const std::vector<int> &js, double *out) const
{
  if (js.empty()) return;
  for (int j : js) {
    if (j < 0 || j >= m_n) throw std::out_of_range("reference: column " + std::to_string(j) + " out of range");
    if (!has_column(j))
      throw std::invalid_argument(!m_d.kpos.empty() ? "reference: column " + std::to_string(j) + " of W was not kept (kept_columns)"
                                                  : "reference: new columns of W need the operator (keep_operator)");
  }
  const int k = static_cast<int>(js.size());
#pragma omp parallel for schedule(static)
  for (int q = 0; q < k; ++q) reference_column(js[q], out + static_cast<std::size_t>(q) * m_n);
  solve(out, k);
}

void DenseReference::pressure_columns(const std::vector<int> &nodes, double *out) const
{
  if (m_d.Gn.empty()) throw std::invalid_argument("reference: pressure loads need a reference set up with pressure");
  for (std::size_t q = 0; q < nodes.size(); ++q) std::copy_n(&m_d.Gn[static_cast<std::size_t>(nodes[q]) * m_n], m_n, out + q * m_n);
  solve(out, static_cast<int>(nodes.size()));
}

void DenseReference::rhs(const SystemSelection &sel, const std::vector<char> &pattern, std::vector<double> &b) const
{
  if (!has_operator() && (m_d.kpos.empty() || pattern != m_d.pattern)) throw std::invalid_argument("scene: this strategy needs the operator (SceneOptions::keep_operator)");
  b.assign(m_n, 0.0);
  std::vector<int> hc, gc, pc;
  std::vector<double> hv, gv, pv;
  for (int j = 0; j < m_n; ++j) {
    const int node = j / 3;
    const double v = sel.known[node][j % 3];
    if (pattern[j]) {
      if (v != 0.0) hc.push_back(j), hv.push_back(-v);
    } else if (!has_pressure(sel, node) && v != 0.0) gc.push_back(j), gv.push_back(v);
  }
  for (int node = 0; node < m_nodes; ++node)
    if (has_pressure(sel, node)) pc.push_back(node), pv.push_back(-sel.pressure[node]);
  if (!pc.empty() && m_d.Gn.empty()) throw std::invalid_argument("scene frame: pressure loads need a scene set up with pressure (SceneOptions::with_pressure)");
  if (!has_operator()) { // K₀′ alone: b = −Σ_j K₀′(:, j) v_j
    for (std::vector<int> *cols : {&hc, &gc})
      for (int &j : *cols) {
        if (m_d.kpos[j] < 0) throw std::invalid_argument("reference: a known value at unknown " + std::to_string(j) + ", whose column was not kept (kept_columns)");
        j = m_d.kpos[j];
      }
    for (double &v : gv) v = -v;
    add_columns(m_d.K, m_n, hc, hv, b.data());
    add_columns(m_d.K, m_n, gc, gv, b.data());
    add_columns(m_d.Gn, m_n, pc, pv, b.data());
    return;
  }
  add_columns(m_d.H, m_n, hc, hv, b.data());
  add_columns(m_d.G, m_n, gc, gv, b.data());
  add_columns(m_d.Gn, m_n, pc, pv, b.data());
}

void DenseReference::apply(const std::vector<char> &pattern, const double *x, double *y) const
{
  if (!has_operator()) throw std::invalid_argument("reference: the product needs the operator (keep_operator)");
  std::vector<double> xu(m_n), xt(m_n);
  for (int j = 0; j < m_n; ++j) (pattern[j] ? xt : xu)[j] = x[j];
  lapack::gemv('N', m_n, m_n, 1.0, m_d.H.data(), m_n, xu.data(), 0.0, y);
  lapack::gemv('N', m_n, m_n, -1.0, m_d.G.data(), m_n, xt.data(), 1.0, y);
}

void DenseReference::free_response(const SystemSelection &sel, std::vector<double> &y) const
{
  if (static_cast<int>(sel.displacement_known.size()) != m_nodes) throw std::invalid_argument("reference: the values do not match the reference's nodes");
  for (int j = 0; j < m_n; ++j)
    if (static_cast<char>(sel.displacement_known[j / 3][j % 3]) != m_d.pattern[j])
      throw std::invalid_argument("reference: the free response needs the reference pattern (unknown " + std::to_string(j) + " differs)");
  rhs(sel, m_d.pattern, y);
  solve(y.data(), 1);
}

std::size_t DenseReference::memory_bytes() const { return 8 * (m_d.H.size() + m_d.G.size() + m_d.Gn.size() + m_d.K.size() + m_d.lu.size()) + 4 * (m_d.piv.size() + m_d.kpos.size()); }

// --- the column cache ---------------------------------------------------------------------------

ReferenceColumns::ReferenceColumns(const ReferenceFactorization &reference, std::vector<int> row_order) : m_ref(&reference), m_order(std::move(row_order))
{
  const int n = reference.num_unknowns();
  if (m_order.empty()) return;
  if (static_cast<int>(m_order.size()) != n) throw std::invalid_argument("ReferenceColumns: the row order needs one entry per unknown");
  m_position.assign(n, -1);
  for (int p = 0; p < n; ++p) {
    if (m_order[p] < 0 || m_order[p] >= n || m_position[m_order[p]] >= 0) throw std::invalid_argument("ReferenceColumns: the row order is not a permutation");
    m_position[m_order[p]] = p;
  }
}

void ReferenceColumns::require(const std::vector<int> &js)
{
  std::vector<int> missing;
  std::unordered_set<int> seen;
  for (int j : js)
    if (!has(j) && seen.insert(j).second) missing.push_back(j);
  if (missing.empty()) return;
  const Timer timer;
  const std::size_t n = static_cast<std::size_t>(m_ref->num_unknowns()), k = missing.size();
  std::unique_ptr<double[]> block(new double[n * k]);
  m_ref->columns(missing, block.get());
  if (!m_order.empty()) {
#pragma omp parallel for schedule(static)
    for (std::size_t q = 0; q < k; ++q) {
      double *col = block.get() + q * n;
      const std::vector<double> natural(col, col + n);
      for (std::size_t p = 0; p < n; ++p) col[p] = natural[m_order[p]];
    }
  }
  keep(std::move(missing), std::move(block));
  m_seconds += timer.seconds();
}

void ReferenceColumns::keep(std::vector<int> js, std::unique_ptr<double[]> block)
{
  const std::size_t n = static_cast<std::size_t>(m_ref->num_unknowns()), k = js.size();
  std::unique_ptr<float[]> single(new float[n * k]);
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < n * k; ++i) single[i] = static_cast<float>(block[i]);
  for (std::size_t q = 0; q < k; ++q) m_index.emplace(js[q], block.get() + q * n), m_single.emplace(js[q], single.get() + q * n);
  m_columns += k;
  m_blocks.push_back(std::move(block));
  m_single_blocks.push_back(std::move(single));
  m_block_columns.push_back(std::move(js));
}

std::vector<ReferenceColumns::Block> ReferenceColumns::blocks() const
{
  std::vector<Block> out;
  for (std::size_t b = 0; b < m_blocks.size(); ++b) out.push_back(Block{m_block_columns[b], m_blocks[b].get()});
  return out;
}

void ReferenceColumns::adopt(std::vector<int> js, std::unique_ptr<double[]> block)
{
  std::unordered_set<int> seen;
  for (int j : js)
    if (j < 0 || j >= m_ref->num_unknowns() || has(j) || !seen.insert(j).second)
      throw std::invalid_argument("ReferenceColumns: a saved column " + std::to_string(j) + " is out of range or held twice");
  keep(std::move(js), std::move(block));
}

std::size_t ReferenceColumns::memory_bytes() const { return 12 * m_columns * static_cast<std::size_t>(m_ref->num_unknowns()); }

} // namespace hssbem
