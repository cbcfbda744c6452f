/// \file rigid_modes.hpp
/// The six rigid-body modes: how well a set of prescribed displacements constrains them, the
/// regularisation of pure-traction problems, and removal of a rigid motion from a displacement field.
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

/// A constraint on the displacement of one dof node along one direction (a prescribed Cartesian
/// component, or a contact normal).
struct NodeConstraint {
  int node;
  Vec3 direction;
};
/// Rank of general constraints on the rigid modes (of the nodes they name: restrict them to one
/// body to check that body alone).
ConstraintReport analyse_constraints(const Discretization &disc, const std::vector<NodeConstraint> &constraints);

/// The six rigid modes at the dof nodes as orthonormal columns: row-major (3 · nodes) × 6. A
/// pure-traction system H u = b is singular along them; H + c Φ Φᵀ is not, and its solution
/// differs from a solution of H u = b (projected on the range of H) by a rigid motion only.
std::vector<double> orthonormal_rigid_modes(const Discretization &disc);

/// Weight c of the rank-6 regularisation: the free term of a smooth boundary point, so the modes
/// get eigenvalues of the size of the rest of H's spectrum.
constexpr double rigid_regularization_weight = 0.5;

/// Subtract the least-squares rigid motion from u (one Vec3 per dof node); returns the motion's
/// translation and rotation as {tx, ty, tz, wx, wy, wz} about the nodes' centroid.
std::array<double, 6> remove_rigid_motion(const Discretization &disc, std::vector<Vec3> &u);

/// Resultant force and moment (about the centroid) of nodal tractions, each relative to the
/// total load magnitude; used to refuse unbalanced loads on unconstrained bodies.
std::array<double, 2> load_imbalance(const Discretization &disc, const std::vector<Vec3> &t);

} // namespace hssbem
