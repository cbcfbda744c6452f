/// \file quadrature_reach.hpp
/// How far the operator's quadrature reaches from each node and cluster: the skeletonizer sizes
/// its proxy spheres and picks the explicit (near) samples of an ID from it, and the H² block
/// partition bounds its cluster radii with it.
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/core/cluster_tree.hpp"

#include <vector>

namespace hssbem {

/// Geometry of the quadrature's reach, per node (mesh order) and per cluster.
struct QuadratureReach {
  std::vector<double> sigma;   ///< per node: every support triangle's near ball lies within this distance of the vertex
  std::vector<double> h;       ///< per node: largest support triangle diameter
  std::vector<double> row_r;   ///< per cluster: radius of its collocation points around the centre
  std::vector<double> src_r;   ///< per cluster: radius of its support triangles around the centre
  std::vector<double> reach_r; ///< per cluster: radius of its support triangles' near balls
};

QuadratureReach quadrature_reach(const BemOperator &op, const ClusterTree &tree);

} // namespace hssbem
