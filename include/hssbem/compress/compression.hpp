/// \file compression.hpp
/// What every entries-only compression of the BEM operator K = [H, G(, Gn)] shares, whatever its
/// format (HSS in hss/, H² in h2/): the column layout of K, the default proxy-sphere size, the
/// checks of the common options and the points the cluster tree partitions.
///
/// K has 3 rows per dof node (collocation point) and, per node, 6 columns: the 3 of H (slots
/// 0–2) and the 3 of G (slots 3–5), optionally a 7th, Gn (slot 6: the response to a unit pressure
/// carried by facet normals, for pressure loads). Any boundary-condition pattern then gives the
/// system matrix A = K E_S (pattern_columns.hpp) without evaluating a kernel again.
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/core/geometry.hpp"

#include <stdexcept>
#include <string>
#include <vector>

namespace hssbem {

/// Columns per node of the compressed K (6, or 7 with pressure columns).
inline int k_columns_per_node(bool pressure_columns) { return pressure_columns ? 7 : 6; }

/// Number of proxy points used for a tolerance when the options' proxy_points is 0.
int default_proxy_points(double rel_tol);

/// Checks shared by every compression built on the skeletonizer: the options rel_tol, leaf_size,
/// proxy_ratio and max_rank of o (HssOptions, H2Options), and an operator without the 3-point far
/// rule. `format` ("HSS", "H2") starts each message. Throws std::invalid_argument.
template <class Opts>
void check_compression_inputs(const BemOperator &op, const Opts &o, const std::string &format)
{
  if (!(o.rel_tol > 0 && o.rel_tol < 1)) throw std::invalid_argument(format + ": the relative tolerance must lie in (0, 1)");
  if (o.leaf_size < 1) throw std::invalid_argument(format + ": the leaf size must be at least 1");
  if (!(o.proxy_ratio > 1)) throw std::invalid_argument(format + ": the proxy ratio must exceed 1");
  if (o.max_rank == 0 || o.max_rank < -1) throw std::invalid_argument(format + ": the rank cap must be positive (or -1 for none)");
  if (op.quadrature_options().far_ratio > 0)
    throw std::invalid_argument(format + ": the 3-point far rule (-mat_bem_far_ratio) breaks the smooth far field the compression relies on; set it to 0");
}

/// The collocation points of the dof nodes (mesh order): what the cluster tree partitions.
std::vector<Vec3> collocation_points(const Discretization &disc);

} // namespace hssbem
