/// \file pattern_columns.hpp
/// From a boundary-condition pattern to products with a compressed K = [H, G(, Gn)] (docs/hss.md, A = K E_S),
/// shared by every compressed format (HSS, H²): A x = K E_S x and b = K (known values), where
/// column (j, c) of A is H's when u is unknown and −G's when t is unknown.
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/core/cluster_tree.hpp"

#include <vector>

namespace hssbem {

/// K's input for the right-hand side b = Σ_known −H u + G t (pressure nodes: −p Gn): w values
/// per node, mesh order. Throws std::logic_error for a pressure load when w < 7.
std::vector<double> pattern_rhs_input(const SystemSelection &sel, int nodes, int w);

/// The w values of node j in pattern_rhs_input, into out[0, w).
void pattern_rhs_node(const SystemSelection &sel, int j, int w, double *out);

/// The w values of node j in pattern_product_input from its 3 unknowns x3, into out[0, w).
void pattern_product_node(const SystemSelection &sel, int j, const double *x3, int w, double *out);

/// K's input for A x (x: 3 per node, mesh order): w values per node, mesh order.
std::vector<double> pattern_product_input(const SystemSelection &sel, const double *x, int nodes, int w);

/// y = K xk for a compressed K (M: HssMatrix or H2Matrix, which hold K S with column scales S),
/// xk with w values per node and y with 3, both in mesh order.
template <class M>
void apply_compressed_k(const M &K, std::vector<double> xk, double *y)
{
  const int n = K.tree().num_points(), w = K.col_block();
  for (int j = 0; j < n; ++j) // the matrix holds K S; feed it S⁻¹ x
    for (int q = 0; q < w; ++q) xk[static_cast<std::size_t>(w) * j + q] /= K.col_scale(q);
  std::vector<double> xc(xk.size()), yc(3L * n);
  K.tree().to_cluster_order(xk.data(), xc.data(), w);
  K.apply(xc.data(), w * n, yc.data(), 3 * n);
  K.tree().to_mesh_order(yc.data(), y, 3);
}

/// Slot of K's column that A uses for component c of node j, and its sign (−G where u is known).
inline int pattern_slot(const SystemSelection &sel, int j, int c, double *sign)
{
  const bool known = sel.displacement_known[j][c];
  *sign = known ? -1.0 : 1.0;
  return known ? 3 + c : c;
}

/// The diagonal of A for the pattern (3 per node, mesh order) from K's leaf diagonal blocks (M:
/// HssMatrix or H2Matrix, holding K S): block_entry(leaf, i, j) is entry (i, j) of K S(rows of
/// leaf, columns of leaf), 3 rows and col_block() columns per point.
template <class M, class BlockEntry>
std::vector<double> pattern_diagonal(const M &K, const SystemSelection &sel, const BlockEntry &block_entry)
{
  const ClusterTree &tree = K.tree();
  const int w = K.col_block();
  std::vector<double> d(3L * tree.num_points());
  for (int c : tree.leaves()) {
    const Cluster &cl = tree.cluster(c);
    for (int k = cl.begin; k < cl.end; ++k) {
      const int j = tree.perm()[k], local = k - cl.begin;
      for (int r = 0; r < 3; ++r) {
        double sign;
        const int slot = pattern_slot(sel, j, r, &sign);
        d[3L * j + r] = sign * block_entry(c, 3 * local + r, w * local + slot) / K.col_scale(slot);
      }
    }
  }
  return d;
}

/// K's input on this rank's points of a distributed system (positions first … first + count − 1
/// of K's tree, cluster order): w values per point from the pattern's known values (x null, for
/// the right-hand side) or from the unknowns x (3 per local point, for A x), divided by K's
/// column scales (the matrix holds K S). M: HssMatrix or H2Matrix.
template <class M>
std::vector<double> local_k_input(const M &K, int first, int count, const SystemSelection &sel, const double *x)
{
  const int w = K.col_block();
  std::vector<double> xk(static_cast<std::size_t>(w) * count);
  for (int k = 0; k < count; ++k) {
    const int j = K.tree().perm()[first + k];
    double *out = &xk[static_cast<std::size_t>(w) * k];
    if (x) pattern_product_node(sel, j, x + 3L * k, w, out);
    else pattern_rhs_node(sel, j, w, out);
    for (int q = 0; q < w; ++q) out[q] /= K.col_scale(q);
  }
  return xk;
}

/// The diagonal of A on this rank's points (3 per local point, cluster order) from the diagonal
/// blocks of the leaves K holds here; block_entry as for pattern_diagonal.
template <class M, class BlockEntry>
std::vector<double> local_pattern_diagonal(const M &K, int first, int count, const SystemSelection &sel, const BlockEntry &block_entry)
{
  const ClusterTree &tree = K.tree();
  const int w = K.col_block();
  std::vector<double> d(3L * count);
  for (int c : tree.leaves()) {
    if (!K.holds(c)) continue;
    const Cluster &cl = tree.cluster(c);
    for (int k = cl.begin; k < cl.end; ++k) {
      const int j = tree.perm()[k], local = k - cl.begin;
      for (int r = 0; r < 3; ++r) {
        double sign;
        const int slot = pattern_slot(sel, j, r, &sign);
        d[3L * (k - first) + r] = sign * block_entry(c, 3 * local + r, w * local + slot) / K.col_scale(slot);
      }
    }
  }
  return d;
}

} // namespace hssbem
