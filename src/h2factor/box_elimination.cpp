// One box of the H² factorization: its joint skeleton, the sparsification and elimination of its
// redundant unknowns (see frontier.hpp; the solve replays them: elimination_step.cpp).
#include "frontier.hpp"

#include "hssbem/core/dense_ops.hpp"
#include "hssbem/core/interpolative.hpp"
#include "hssbem/core/lapack.hpp"
#include "hssbem/h2factor/h2_breakdown.hpp"

#include <algorithm>
#include <numeric>
#include <string>


namespace hssbem::h2f {

namespace {

/// G += op(P) op(P)ᵀ (upper triangle), op(P) = P (trans 'N', P m × q) or Pᵀ (trans 'T', P q × m).
void gram_add(DenseMatrix &G, const DenseMatrix &P, char trans)
{
  const int m = G.m, q = trans == 'N' ? P.n : P.m;
  if (m == 0 || q == 0) return;
  const double one = 1.0;
  const int ld = P.ld();
  dsyrk_("U", &trans, &m, &q, &one, P.data(), &ld, &one, G.data(), &m);
}

/// A box's skeleton from a row ID of its features (rows = its candidates).
BoxSkeleton from_id(const ColumnId &id)
{
  BoxSkeleton sk;
  sk.S = id.skeleton;
  sk.R = id.redundant;
  sk.T = DenseMatrix(id.rank(), static_cast<int>(sk.R.size()));
  std::copy(id.T.begin(), id.T.end(), sk.T.a.begin());
  return sk;
}

/// Skeleton from the features themselves (rows = candidates), by the ID of interpolative.hpp:
/// exact where the Gram's squared tolerance would approach rounding.
BoxSkeleton skeleton_from_features(const std::vector<DenseMatrix> &parts, int m, double tol)
{
  int nf = 0;
  for (const DenseMatrix &P : parts) nf += P.n;
  DenseMatrix F(m, nf);
  int off = 0;
  for (const DenseMatrix &P : parts) {
    dense::put(F, 0, off, P);
    off += P.n;
  }
  return from_id(row_id(F.data(), m, nf, F.ld(), IdOptions{tol, -1}));
}

DenseMatrix transposed(const DenseMatrix &B)
{
  DenseMatrix T(B.n, B.m);
  for (int j = 0; j < B.n; ++j)
    for (int i = 0; i < B.m; ++i) T(j, i) = B(i, j);
  return T;
}

DenseMatrix columns_at(const DenseMatrix &M, const std::vector<int> &idx)
{
  DenseMatrix out(M.m, static_cast<int>(idx.size()));
  for (std::size_t j = 0; j < idx.size(); ++j) std::copy_n(M.data() + static_cast<std::size_t>(idx[j]) * M.ld(), M.m, out.data() + j * out.ld());
  return out;
}

void keep_columns(DenseMatrix &M, int k)
{
  M.a.resize(static_cast<std::size_t>(M.m) * k);
  M.n = k;
}

/// A⁻¹ from its getrf factors (m × m).
DenseMatrix inverse(const DenseMatrix &LU, const std::vector<int> &piv)
{
  const int m = LU.m;
  DenseMatrix inv(m, m);
  for (int i = 0; i < m; ++i) inv(i, i) = 1.0;
  if (m > 0) lapack::getrs('N', m, m, LU.data(), LU.ld(), piv.data(), inv.data(), inv.ld());
  return inv;
}

/// A buffer per thread, grown as needed and kept: a box step's products and permutations go
/// through it rather than through fresh allocations of each block's size.
std::vector<double> &scratch(std::size_t size)
{
  thread_local std::vector<double> s;
  if (s.size() < size) s.resize(size);
  return s;
}

/// B ← B A⁻¹ (one product with the explicit inverse: a GEMM runs faster than two triangular solves).
void right_multiply(DenseMatrix &B, const DenseMatrix &inv)
{
  if (B.m == 0 || B.n == 0) return;
  std::vector<double> &w = scratch(B.a.size());
  lapack::gemm('N', 'N', B.m, B.n, B.n, 1.0, B.data(), B.ld(), inv.data(), inv.ld(), 0.0, w.data(), B.ld());
  std::copy_n(w.data(), B.a.size(), B.a.data());
}

/// B ← B(order, :) in place (order: a permutation of B's rows).
void permute_rows(DenseMatrix &B, const std::vector<int> &order)
{
  if (B.m == 0 || B.n == 0) return;
  std::vector<double> &w = scratch(B.a.size());
  std::copy_n(B.a.data(), B.a.size(), w.data());
  const std::size_t m = static_cast<std::size_t>(B.m);
  for (std::size_t j = 0; j < static_cast<std::size_t>(B.n); ++j) {
    const double *src = w.data() + j * m;
    double *dst = B.a.data() + j * m;
    for (std::size_t i = 0; i < m; ++i) dst[i] = src[order[i]];
  }
}

/// B ← B(:, order) in place (order: a permutation of B's columns).
void permute_columns(DenseMatrix &B, const std::vector<int> &order)
{
  if (B.m == 0 || B.n == 0) return;
  std::vector<double> &w = scratch(B.a.size());
  std::copy_n(B.a.data(), B.a.size(), w.data());
  const std::size_t m = static_cast<std::size_t>(B.m);
  for (std::size_t j = 0; j < order.size(); ++j) std::copy_n(w.data() + static_cast<std::size_t>(order[j]) * m, m, B.a.data() + j * m);
}

} // namespace

// ---------------------------------------------------------------------------------------------
// Step 0: the block-Jacobi change of variables.

void Frontier::precondition(int X, Step *st)
{
  DenseMatrix &XX = open(X, m_M[X].at(X));
  st->box = m_D[X];
  st->D = XX;
  if (!dense::lu_regular(st->D, st->dpiv))
    throw H2Breakdown("H2 factorization broke down: the diagonal block of box " + std::to_string(X) + " (" + std::to_string(XX.m) + " unknowns) is singular to working precision");
  const int m = XX.m;
  XX = DenseMatrix(m, m);
  for (int i = 0; i < m; ++i) XX(i, i) = 1.0;
  const DenseMatrix inv = inverse(st->D, st->dpiv);
  for (int Y : neighbours(X)) right_multiply(open(X, m_M[Y].at(X)), inv);
  for (StoredBlock *B : m_fill_col_blocks[X]) right_multiply(open(X, *B), inv);
  for (int Z : m_cross[X]) right_multiply(open(X, m_G[Z].at(X)), inv); // this side's copies in X's columns
  if (!m_cross[X].empty()) { // X's side for the other copies: eliminate() keeps the skeleton's columns
    m_side[X].recorded = true;
    m_side[X].C = inv;
  }
  // X's columns as the far field sees them, K(F, C) Ŵᵀ and c Φ Ψᵀ: Ŵ ← A_XX⁻ᵀ Ŵ, Ψ likewise.
  for (DenseMatrix *W : {&open(X, m_Ew[X]), &m_Psi[X]}) {
    if (W->n == 0 || W->m == 0) continue;
    DenseMatrix out(W->m, W->n);
    lapack::gemm('T', 'N', m, W->n, m, 1.0, inv.data(), inv.ld(), W->data(), W->ld(), 0.0, out.data(), out.ld());
    *W = std::move(out);
  }
}

// ---------------------------------------------------------------------------------------------
// Step 1: the skeleton.

BoxSkeleton Frontier::skeleton(int X, double tol) const
{
  const int m = static_cast<int>(m_D[X].size());
  std::vector<DenseMatrix> parts; // features as columns (rows = candidates)
  if (m_Eu[X].cols() > 0 && m_sketch.row[X].n > 0) parts.push_back(dense::product(m_Eu[X].value(), 'N', m_sketch.row[X], 'N'));
  if (m_Ew[X].cols() > 0 && m_sketch.col[X].n > 0) parts.push_back(dense::product(m_Ew[X].value(), 'N', m_sketch.col[X], 'N'));
  if (m_pat.regularised())
    for (const DenseMatrix *R : {&m_Phi[X], &m_Psi[X]}) {
      DenseMatrix P = *R;
      for (double &v : P.a) v *= m_pat.c;
      parts.push_back(std::move(P));
    }
  // The Gram loses what lies below the rounding of its squared entries: below ~1e-7, the ID.
  // Cross blocks (boxes of other parts) count as fill-in: X's rows of them, and this side's
  // copies of those in X's columns.
  if (tol < 1e-7) {
    for (const auto &e : m_F[X]) parts.push_back(e.second.value());
    for (const StoredBlock *B : m_fill_col_blocks[X]) parts.push_back(transposed(B->value()));
    for (int Y : m_cross[X]) parts.push_back(m_X[X].at(Y).value());
    for (int Z : m_cross[X]) parts.push_back(transposed(m_G[Z].at(X).value()));
    return skeleton_from_features(parts, m, tol);
  }
  DenseMatrix G(m, m);
  for (const DenseMatrix &P : parts) gram_add(G, P, 'N');
  for (const auto &e : m_F[X]) gram_add(G, e.second.value(), 'N');
  for (const StoredBlock *B : m_fill_col_blocks[X]) gram_add(G, B->value(), 'T');
  for (int Y : m_cross[X]) gram_add(G, m_X[X].at(Y).value(), 'N');
  for (int Z : m_cross[X]) gram_add(G, m_G[Z].at(X).value(), 'T');
  return from_id(gram_column_id(G.data(), m, IdOptions{tol, -1})); // pivoted Cholesky of the Gram: the ID's rule, squared
}

// ---------------------------------------------------------------------------------------------
// Steps 2 and 3: sparsify, eliminate, Schur complement.

void Frontier::eliminate(int X, const BoxSkeleton &sk, Step *out, double *flops, std::vector<NewFill> *fresh)
{
  const int k = static_cast<int>(sk.S.size()), r = static_cast<int>(sk.R.size());
  Step &st = *out;
  for (int i : sk.S) st.S.push_back(m_D[X][i]);
  for (int i : sk.R) st.R.push_back(m_D[X][i]);
  st.T = sk.T;
  if (m_side[X].recorded) { // the other side's copies keep the skeleton (all of X's unknowns when none is redundant)
    CrossSide &side = m_side[X];
    if (r == 0) {
      side.kept.resize(static_cast<std::size_t>(k));
      std::iota(side.kept.begin(), side.kept.end(), 0);
    } else
      side.kept = sk.S;
    side.C = columns_at(side.C, side.kept);
  }
  if (r == 0) return;
  std::vector<int> targets{X}; // X and its close neighbours: where the Schur complement goes
  const std::vector<int> nb = neighbours(X);
  targets.insert(targets.end(), nb.begin(), nb.end());
  sparsify(X, sk);
  std::vector<int> off(targets.size() + 1, 0); // rows of X's skeleton and of each neighbour in I
  for (std::size_t t = 0; t < targets.size(); ++t) off[t + 1] = off[t] + (t == 0 ? k : static_cast<int>(m_D[targets[t]].size()));
  panels(X, k, targets, off, st);
  schur_complement(X, targets, off, st, fresh);
  *flops += 2.0 * off.back() * off.back() * r;
  // X keeps its skeleton.
  DenseMatrix &XX = open(X, m_M[X].at(X));
  XX = dense::sub(XX, 0, k, 0, k);
  for (int Y : nb) {
    DenseMatrix &XY = open(X, m_M[X].at(Y));
    XY = dense::row_block(XY, 0, k);
    keep_columns(open(X, m_M[Y].at(X)), k);
  }
  m_D[X] = st.S;
  for (StoredBlock *E : {&m_Eu[X], &m_Ew[X]}) {
    DenseMatrix &e = open(X, *E);
    e = dense::rows_at(e, sk.S);
  }
  if (m_pat.regularised()) {
    m_Phi[X] = dense::rows_at(m_Phi[X], sk.S);
    m_Psi[X] = dense::rows_at(m_Psi[X], sk.S);
  }
  for (int Y : targets) st.I.insert(st.I.end(), m_D[Y].begin(), m_D[Y].end());
}

void Frontier::sparsify(int X, const BoxSkeleton &sk)
{
  const int k = static_cast<int>(sk.S.size()), r = static_cast<int>(sk.R.size());
  // Local order [S, R]; rows R -= Tᵀ rows S, columns R -= columns S T.
  std::vector<int> order = sk.S;
  order.insert(order.end(), sk.R.begin(), sk.R.end());
  const auto row_op = [&](DenseMatrix &B) {
    permute_rows(B, order);
    if (k > 0 && B.n > 0) lapack::gemm('T', 'N', r, B.n, k, -1.0, sk.T.data(), sk.T.ld(), B.data(), B.ld(), 1.0, B.data() + k, B.ld());
  };
  const auto col_op = [&](DenseMatrix &B) {
    permute_columns(B, order);
    if (k > 0 && B.m > 0) lapack::gemm('N', 'N', B.m, r, k, -1.0, B.data(), B.ld(), sk.T.data(), sk.T.ld(), 1.0, B.data() + static_cast<std::size_t>(k) * B.m, B.ld());
  };
  DenseMatrix &XX = open(X, m_M[X].at(X));
  row_op(XX);
  col_op(XX);
  for (int Y : neighbours(X)) {
    row_op(open(X, m_M[X].at(Y)));
    col_op(open(X, m_M[Y].at(X)));
  }
  // Fill-in beyond the neighbours, and this side's copies of the cross blocks (as fill-in: rows
  // kept as they are, columns as X's change of variables makes them; no Schur complement reaches
  // them): the sparsified redundant part is below the tolerance.
  const auto rows_kept = [&](StoredBlock &b) {
    DenseMatrix &B = open(X, b);
    row_op(B);
    B = dense::row_block(B, 0, k);
  };
  const auto columns_kept = [&](StoredBlock &b) {
    DenseMatrix &B = open(X, b);
    col_op(B);
    keep_columns(B, k);
  };
  for (auto &e : m_F[X]) rows_kept(e.second);
  for (StoredBlock *F : m_fill_col_blocks[X]) columns_kept(*F);
  for (int Y : m_cross[X]) rows_kept(m_X[X].at(Y));
  for (int Z : m_cross[X]) columns_kept(m_G[Z].at(X));
}

void Frontier::panels(int X, int k, const std::vector<int> &targets, const std::vector<int> &off, Step &st) const
{
  const DenseMatrix &XX = *m_M[X].at(X).peek(); // opened by sparsify()
  const int r = XX.m - k, nI = off.back();
  st.LU = dense::sub(XX, k, r, k, r);
  st.piv.resize(r);
  if (!dense::lu_regular(st.LU, st.piv))
    throw H2Breakdown("H2 factorization broke down: the pivot block of box " + std::to_string(X) + " (" + std::to_string(r) + " unknowns) is singular to working precision");
  st.Lp = DenseMatrix(nI, r);
  st.Up = DenseMatrix(r, nI);
  for (std::size_t t = 0; t < targets.size(); ++t) {
    const int Y = targets[t], rows = off[t + 1] - off[t];
    const DenseMatrix &AYR = t == 0 ? XX : *m_M[Y].at(X).peek(), &ARY = t == 0 ? XX : *m_M[X].at(Y).peek(); // opened by sparsify()
    for (int j = 0; j < r; ++j) {
      const double *src = AYR.data() + static_cast<std::size_t>(k + j) * AYR.m;
      std::copy(src, src + rows, &st.Lp(off[t], j));
    }
    for (int j = 0; j < rows; ++j) {
      const double *src = ARY.data() + static_cast<std::size_t>(j) * ARY.m + k;
      std::copy(src, src + r, &st.Up(0, off[t] + j));
    }
  }
  if (nI > 0) {
    lapack::trsm('R', 'U', 'N', 'N', nI, r, 1.0, st.LU.data(), st.LU.ld(), st.Lp.data(), st.Lp.ld());
    lapack::laswp(nI, st.Up.data(), st.Up.ld(), r, st.piv.data());
    lapack::trsm('L', 'L', 'N', 'U', r, nI, 1.0, st.LU.data(), st.LU.ld(), st.Up.data(), st.Up.ld());
  }
}

void Frontier::schur_complement(int X, const std::vector<int> &targets, const std::vector<int> &off, const Step &st, std::vector<NewFill> *fresh)
{
  // Block by block straight into the blocks it touches (a product of the whole |I| x |I| first
  // would allocate and clear up to a few hundred MB per box at the upper levels).
  const int r = st.LU.m;
  for (std::size_t ty = 0; ty < targets.size(); ++ty)
    for (std::size_t tz = 0; tz < targets.size(); ++tz) {
      const int Y = targets[ty], Z = targets[tz], my = off[ty + 1] - off[ty], mz = off[tz + 1] - off[tz];
      if (my == 0 || mz == 0) continue;
      DenseMatrix *B;
      if (ty == 0) B = &open(X, m_M[X].at(tz == 0 ? X : Z));
      else if (tz == 0) B = &open(X, m_M[Y].at(X));
      else if (m_part.is_close(Y, Z)) B = &open(X, m_M[Y].at(Z));
      else {
        const auto it = m_F[Y].find(Z);
        if (it != m_F[Y].end()) B = &open(X, it->second);
        else {
          fresh->push_back(NewFill{Y, Z, DenseMatrix(my, mz)});
          B = &fresh->back().B;
        }
      }
      lapack::gemm('N', 'N', my, mz, r, -1.0, st.Lp.data() + off[ty], st.Lp.ld(), st.Up.data() + static_cast<std::size_t>(off[tz]) * st.Up.ld(), st.Up.ld(), 1.0,
                   B->data(), B->ld());
    }
}

void Frontier::add_fill(std::vector<NewFill> &&fresh)
{
  for (NewFill &f : fresh) {
    m_fill_cols[f.col].push_back(f.row);
    settle(m_F[f.row].emplace(f.col, StoredBlock(std::move(f.B))).first->second);
  }
  fresh.clear();
}

} // namespace hssbem::h2f
