/// \file post.hpp
/// From the solution vector to fields per vertex, reactions per region and interior displacements.
#pragma once

#include "hssbem/bem/bem_operator.hpp"
#include "hssbem/bem/body_force.hpp"

#include <map>
#include <string>
#include <vector>

namespace hssbem {

/// Displacement and traction at every dof node.
struct NodalSolution {
  std::vector<Vec3> u, t;
};

/// Merge the unknowns x (3 per node, node order) with the known values of the selection.
NodalSolution split_unknowns(const SystemSelection &sel, const std::vector<double> &x);

/// The whole solution of a problem with a body force: the homogeneous solution `h` (what the
/// system gives, bem/body_force.hpp) plus the particular solution's traces at every dof node.
/// `h` itself when the force is zero.
NodalSolution with_particular(NodalSolution h, const Discretization &disc, const UniformBodyForce &force);

/// A pure-traction problem's answer is defined up to a rigid motion: removes from the
/// homogeneous displacement `u_h` the rigid motion of the whole one (u_h plus the particular
/// solution's u_p at the nodes), so that the whole field reported has none (remove_rigid_motion
/// of bem/rigid_modes.hpp, which this is without a body force).
void remove_whole_rigid_motion(const Discretization &disc, const UniformBodyForce &force, std::vector<Vec3> &u_h);

/// Per mesh vertex: the mean over the vertex's dof nodes (NaN for a vertex used by no triangle).
std::vector<Vec3> vertex_average(const Discretization &disc, const std::vector<Vec3> &nodal);

/// Traction of triangle t at its corner c (double nodes make it jump across sharp features).
std::vector<std::array<Vec3, 3>> corner_values(const Discretization &disc, const std::vector<Vec3> &nodal);

/// Integral of the traction over each region (keyed by region name, or tag when unnamed) and over
/// the whole surface ("total").
std::map<std::string, Vec3> reactions(const Discretization &disc, const std::vector<Vec3> &t);

/// Somigliana's identity at interior points: u(x) = ∫ u* t - ∫ p* u.
std::vector<Vec3> interior_displacement(const BemOperator &op, const NodalSolution &s, const std::vector<Vec3> &points);

/// Free term c(x) = -∫ p* over the surface: the identity inside the body, zero outside. Used to
/// refuse interior points that lie outside (or too close to the surface to be integrated).
double inside_indicator(const BemOperator &op, const Vec3 &x);

} // namespace hssbem
