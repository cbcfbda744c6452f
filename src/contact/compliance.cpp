// The compliance of a frame's contact points from the reference's columns (contact_points.hpp).
#include "contact_points.hpp"

#include <algorithm>
#include <unordered_map>

namespace hssbem::contact_detail {

std::vector<int> loaded_unknowns(const std::vector<ContactPoint> &points, const std::vector<char> &pattern, bool normal_only)
{
  std::vector<int> loaded;
  for (const ContactPoint &p : points)
    for (int i = 0; i < p.terms; ++i)
      for (int b = 0; b < 3; ++b)
        if (!pattern[3 * p.term_node[i] + b] && (!normal_only || p.lw[i][0] * p.frame[0][b] != 0.0)) loaded.push_back(3 * p.term_node[i] + b);
  return loaded;
}

Compliance::Compliance(const std::vector<ContactPoint> &points, const std::vector<char> &pattern, ReferenceColumns &columns, bool normal_only)
    : m_points(&points), m_columns(&columns), m_normal_only(normal_only), m_terms(points.size()), m_attached(points.size(), 0), m_held(points.size()),
      m_pattern(&pattern)
{
  if (!normal_only) columns.require(loaded_unknowns(points, pattern, false));
  for (std::size_t c = 0; c < points.size(); ++c) {
    const ContactPoint &p = points[c];
    Terms &t = m_terms[c];
    for (int i = 0; i < p.terms; ++i) {
      const int m = p.term_node[i];
      for (int k = 0; k < 3; ++k)
        for (int a = 0; a < 3; ++a) {
          const bool u_unknown = !pattern[3 * m + a]; // and so t known: the column is loaded
          t.M[i][3 * k + a] = u_unknown ? p.mw[i][k] * p.frame[k][a] : 0.0;
          t.L[i][3 * a + k] = u_unknown ? p.lw[i][k] * p.frame[k][a] : 0.0;
        }
      t.row[i] = columns.position(3 * m);
    }
    for (int k = 0; k < 3; ++k) { // the slave node's measure along frame k: zero when prescribed
      const Mat3 &M = t.M[0];
      m_held[c][k] = p.held[k] || std::abs(M[3 * k]) + std::abs(M[3 * k + 1]) + std::abs(M[3 * k + 2]) <= 1e-12;
    }
    if (!normal_only) attach(static_cast<int>(c));
  }
}

void Compliance::attach(int c) const
{
  const ContactPoint &p = (*m_points)[c];
  Terms &t = m_terms[c];
  for (int i = 0; i < p.terms; ++i)
    for (int b = 0; b < 3; ++b) {
      const int j = 3 * p.term_node[i] + b;
      t.col[i][b] = (*m_pattern)[j] || !m_columns->has(j) ? nullptr : m_columns->column(j);
    }
  m_attached[c] = 1;
}

void Compliance::require(const std::vector<int> &cs) const
{
  std::vector<ContactPoint> missing;
  std::vector<int> which;
  for (int c : cs)
    if (!m_attached[c]) missing.push_back((*m_points)[c]), which.push_back(c);
  if (which.empty()) return;
  m_columns->require(loaded_unknowns(missing, *m_pattern, m_normal_only));
  for (int c : which) attach(c);
}

Mat3 Compliance::block(int c, int cp) const
{
  const ContactPoint &p = (*m_points)[c], &q = (*m_points)[cp];
  const Terms &tp = m_terms[c], &tq = m_terms[cp];
  Mat3 D{};
  for (int j = 0; j < q.terms; ++j) {
    Mat3 X{}; // (local k of c) × (Cartesian b of the loaded node)
    for (int b = 0; b < 3; ++b) {
      if (!tq.col[j][b]) continue;
      for (int i = 0; i < p.terms; ++i) {
        const double *w = tq.col[j][b] + tp.row[i];
        const Mat3 &M = tp.M[i];
        for (int k = 0; k < 3; ++k) X[3 * k + b] += M[3 * k] * w[0] + M[3 * k + 1] * w[1] + M[3 * k + 2] * w[2];
      }
    }
    const Mat3 &L = tq.L[j];
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l) D[3 * k + l] -= X[3 * k] * L[l] + X[3 * k + 1] * L[3 + l] + X[3 * k + 2] * L[6 + l];
  }
  return D;
}

double Compliance::normal(int c, int cp) const
{
  const ContactPoint &p = (*m_points)[c], &q = (*m_points)[cp];
  const Terms &tp = m_terms[c], &tq = m_terms[cp];
  double d = 0;
  for (int j = 0; j < q.terms; ++j)
    for (int b = 0; b < 3; ++b) {
      if (!tq.col[j][b] || tq.L[j][3 * b] == 0.0) continue;
      double x = 0;
      for (int i = 0; i < p.terms; ++i) {
        const double *w = tq.col[j][b] + tp.row[i];
        x += tp.M[i][0] * w[0] + tp.M[i][1] * w[1] + tp.M[i][2] * w[2];
      }
      d -= x * tq.L[j][3 * b];
    }
  return d;
}

namespace {

/// One measured row of apply_normal: where its node's rows sit and the normal row of M.
struct NormalRow {
  int pos;
  double m[3];
};

} // namespace

/// The measured rows of the points are packed first (their terms' positions and normal rows of
/// M, 32 bytes a term instead of the Terms' 700), then each thread takes a block of them and
/// runs over every loaded column: the columns stream once per block, the packed rows stay in cache.
void Compliance::apply_normal(const std::vector<int> &rows, const std::vector<int> &cols, const Vec3 *lambda, double *out) const
{
  std::vector<int> first(rows.size() + 1, 0);
  std::vector<NormalRow> packed;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const ContactPoint &pr = (*m_points)[rows[r]];
    const Terms &tr = m_terms[rows[r]];
    for (int i = 0; i < pr.terms; ++i) packed.push_back({tr.row[i], {tr.M[i][0], tr.M[i][1], tr.M[i][2]}});
    first[r + 1] = static_cast<int>(packed.size());
  }
  std::vector<const double *> col;
  std::vector<double> coef;
  for (std::size_t q = 0; q < cols.size(); ++q) {
    const ContactPoint &pq = (*m_points)[cols[q]];
    const Terms &tq = m_terms[cols[q]];
    for (int j = 0; j < pq.terms; ++j)
      for (int b = 0; b < 3; ++b) {
        const Mat3 &L = tq.L[j];
        const double c = -(L[3 * b] * lambda[q][0] + L[3 * b + 1] * lambda[q][1] + L[3 * b + 2] * lambda[q][2]);
        if (tq.col[j][b] && c != 0.0) col.push_back(tq.col[j][b]), coef.push_back(c);
      }
  }
  const int nr = static_cast<int>(rows.size()), block = 256;
#pragma omp parallel for schedule(dynamic, 1) if (static_cast<double>(nr) * col.size() > 2e5)
  for (int r0 = 0; r0 < nr; r0 += block) {
    const int r1 = std::min(nr, r0 + block);
    for (std::size_t q = 0; q < col.size(); ++q) {
      const double *w = col[q], c = coef[q];
      for (int r = r0; r < r1; ++r) {
        double x = 0;
        for (int k = first[r]; k < first[r + 1]; ++k) {
          const double *wi = w + packed[k].pos;
          x += packed[k].m[0] * wi[0] + packed[k].m[1] * wi[1] + packed[k].m[2] * wi[2];
        }
        out[r] += c * x;
      }
    }
  }
}

std::vector<Vec3> Compliance::free_w(const std::vector<Vec3> &u_free, const std::vector<Vec3> &u_prev) const
{
  std::vector<Vec3> w(m_points->size());
  for (std::size_t c = 0; c < w.size(); ++c) {
    const ContactPoint &p = (*m_points)[c];
    for (int k = 0; k < 3; ++k) {
      // the gap; the slip over the step (a follower's tie rows: the whole relative displacement)
      const bool step = k > 0 && !u_prev.empty() && p.lead < 0;
      double d = 0;
      for (int i = 0; i < p.terms; ++i) d += p.mw[i][k] * dot(p.frame[k], step ? u_free[p.term_node[i]] - u_prev[p.term_node[i]] : u_free[p.term_node[i]]);
      w[c][k] = k == 0 ? p.g0 + d : d - dot(p.frame[k], p.motion); // relative to the obstacle's surface point (pairs: the master's terms move too)
    }
  }
  return w;
}

void Compliance::loads(const std::vector<Vec3> &lambda, std::vector<int> &unknowns, std::vector<double> &values) const
{
  std::unordered_map<int, double> acc;
  for (std::size_t c = 0; c < m_points->size(); ++c) {
    const ContactPoint &p = (*m_points)[c];
    if (lambda[c][0] == 0 && lambda[c][1] == 0 && lambda[c][2] == 0) continue;
    for (int i = 0; i < p.terms; ++i)
      for (int b = 0; b < 3; ++b) {
        const Mat3 &L = m_terms[c].L[i];
        const double v = L[3 * b] * lambda[c][0] + L[3 * b + 1] * lambda[c][1] + L[3 * b + 2] * lambda[c][2];
        if (v != 0.0) acc[3 * p.term_node[i] + b] += v;
      }
  }
  unknowns.clear(), values.clear();
  for (const auto &[j, v] : acc) unknowns.push_back(j);
  std::sort(unknowns.begin(), unknowns.end()); // a fixed order: the same sums whatever the hashing
  for (int j : unknowns) values.push_back(acc[j]);
}

} // namespace hssbem::contact_detail
