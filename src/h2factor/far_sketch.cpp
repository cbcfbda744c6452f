// Random sketches of the far-field couplings of an H² matrix (see far_sketch.hpp).
#include "hssbem/h2factor/far_sketch.hpp"

#include <algorithm>
#include <cmath>
#include <random>

namespace hssbem {

std::size_t FarFieldSketch::bytes() const
{
  std::size_t s = 0;
  for (const DenseMatrix &M : row) s += M.bytes();
  for (const DenseMatrix &M : col) s += M.bytes();
  return s;
}

namespace {

/// Copy the q columns of `part` (one per cluster) into columns [j0, j0 + q) of `whole`.
void put_columns(std::vector<DenseMatrix> &whole, const std::vector<DenseMatrix> &part, int j0)
{
  for (std::size_t c = 0; c < whole.size(); ++c) {
    const std::size_t m = static_cast<std::size_t>(part[c].m);
    if (m == 0) continue; // a cluster without a basis: nothing to copy (and no storage to point into)
    for (int j = 0; j < part[c].n; ++j) std::copy_n(part[c].a.data() + j * m, m, whole[c].a.data() + static_cast<std::size_t>(j0 + j) * whole[c].m);
  }
}

/// The sketch through a matrix's two far-field passes: far(X, ldx, q) and far_t(Y, ldy, q)
/// (collective on comm, failure-atomic), fed with this rank's rows (from point `first`) of
/// random inputs drawn for all n; the local work between them in agreements.
template <class Far, class FarT>
FarFieldSketch sketch_passes(const H2Matrix &K, const RankComm &comm, int p, unsigned seed, int first, const Far &far, const FarT &far_t)
{
  const ClusterTree &tree = K.tree();
  const int nc = tree.num_clusters(), n = tree.num_points(), w = K.col_block(), rb = K.row_block();
  FarFieldSketch s;
  s.columns = p;
  collectively(comm, [&] {
    s.row.resize(nc);
    s.col.resize(nc);
    for (int c = 0; c < nc; ++c) {
      s.row[c] = DenseMatrix(K.holds(c) ? K.row_interpolation(c).rank() : 0, p); // other ranks' clusters: no rows here
      s.col[c] = DenseMatrix(K.holds(c) ? K.col_interpolation(c).rank() : 0, p);
    }
  });
  std::mt19937_64 gen(seed);
  std::normal_distribution<double> normal;
  const double scale = 1.0 / std::sqrt(static_cast<double>(p));
  // As many columns at once as fit in 256 MB of inputs (each pass reads every far block once, so
  // fewer passes run faster: 20k sphere, p = 150, 32 at a time 2.6 s, all at once 2.0 s).
  const std::size_t per_column = sizeof(double) * static_cast<std::size_t>(std::max(w, rb)) * n;
  const int chunk = static_cast<int>(std::clamp<std::size_t>((std::size_t{256} << 20) / std::max<std::size_t>(per_column, 1), 32, std::max(p, 32)));
  std::vector<double> X, Y;
  for (int j0 = 0; j0 < p; j0 += chunk) {
    const int q = std::min(chunk, p - j0);
    // Random K inputs on H and G columns (slots 0-5; a pressure column, slot 6, takes no part).
    collectively(comm, [&] {
      X.assign(static_cast<std::size_t>(w) * n * q, 0.0);
      for (int j = 0; j < q; ++j)
        for (int k = 0; k < n; ++k)
          for (int t = 0; t < std::min(w, 6); ++t) X[static_cast<std::size_t>(j) * w * n + static_cast<std::size_t>(w) * k + t] = scale * normal(gen);
    });
    std::vector<DenseMatrix> part = far(X.data() + static_cast<std::size_t>(w) * first, w * n, q);
    collectively(comm, [&] {
      put_columns(s.row, part, j0);
      Y.resize(static_cast<std::size_t>(rb) * n * q);
      for (double &v : Y) v = scale * normal(gen);
    });
    part = far_t(Y.data() + static_cast<std::size_t>(rb) * first, rb * n, q);
    put_columns(s.col, part, j0); // copies into storage that exists: nothing to fail
  }
  return s;
}

} // namespace

FarFieldSketch far_field_sketch(const H2Matrix &K, int p, unsigned seed)
{
  return sketch_passes(
    K, SerialComm(), p, seed, 0, [&](const double *X, int ldx, int q) { return K.skeleton_far_field(X, ldx, q); },
    [&](const double *Y, int ldy, int q) { return K.skeleton_far_field_transposed(Y, ldy, q); });
}

FarFieldSketch far_field_sketch(const H2DistributedProduct &K, int p, unsigned seed)
{
  return sketch_passes(
    K.matrix(), K.comm(), p, seed, K.first_point(), [&](const double *X, int ldx, int q) { return K.skeleton_far_field(X, ldx, q); },
    [&](const double *Y, int ldy, int q) { return K.skeleton_far_field_transposed(Y, ldy, q); });
}

} // namespace hssbem
