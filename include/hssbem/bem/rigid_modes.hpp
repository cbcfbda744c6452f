/// \file rigid_modes.hpp
/// The six rigid-body modes: how well a set of prescribed displacements constrains them, pins for
/// pure-traction problems, and removal of a rigid motion from a displacement field.
#pragma once

#include "hssbem/bem/discretization.hpp"

#include <stdexcept>
#include <string>
#include <vector>

namespace hssbem {

/// Raised when prescribed displacements leave some rigid motion free (but not all of them).
class ConstraintError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

struct ConstraintReport {
  int rank = 0;                       ///< number of rigid modes fixed by the prescribed displacements
  std::vector<std::string> free_modes; ///< readable description of each free mode
};

/// Rank of the prescribed displacement components on the rigid modes of the body.
ConstraintReport analyse_constraints(const Discretization &disc, const std::vector<std::array<bool, 3>> &displacement_known);

/// Six (node, component) pins at three far-apart nodes that together fix every rigid mode.
std::vector<std::pair<int, int>> choose_pins(const Discretization &disc);

/// Subtract the least-squares rigid motion from u (one Vec3 per dof node); returns the motion's
/// translation and rotation as {tx, ty, tz, wx, wy, wz} about the nodes' centroid.
std::array<double, 6> remove_rigid_motion(const Discretization &disc, std::vector<Vec3> &u);

/// Resultant force and moment (about the centroid) of nodal tractions, each relative to the
/// total load magnitude; used to refuse unbalanced loads on unconstrained bodies.
std::array<double, 2> load_imbalance(const Discretization &disc, const std::vector<Vec3> &t);

} // namespace hssbem
