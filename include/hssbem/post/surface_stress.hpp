/// \file surface_stress.hpp
/// The stress tensor on the surface, from the boundary solution alone: the traction gives σ n,
/// the tangential derivatives of the displacement give the in-plane strains, and Hooke's law the
/// rest (the in-plane stresses, through the normal strain that σ_nn fixes).
///
/// At each dof node, with n its normal (the angle-weighted normal of its smooth group) and (e1,
/// e2) a tangent frame: the tangential gradient (∂u/∂e1, ∂u/∂e2) is fitted by least squares over
/// the corners of the node's triangles (its P1 support, which never crosses a sharp edge): a
/// quadratic fit where the fan is closed and holds at least six other corners (second order on a
/// smooth surface), else a linear one (exact for a linear field, as on a cube's faces, edges and
/// corners). Then in the frame (e1, e2, n):
///   σ_3k = t_k,  ε_11, ε_22, ε_12 from the gradient,  ε_33 = (σ_33 − λ(ε_11 + ε_22)) / (λ + 2μ),
///   σ_11 = λ tr ε + 2μ ε_11,  σ_22 = λ tr ε + 2μ ε_22,  σ_12 = 2μ ε_12,
/// and the full displacement gradient follows from σ_13, σ_23 and ε_33 as well.
#pragma once

#include "hssbem/bem/body_force.hpp"
#include "hssbem/bem/discretization.hpp"
#include "hssbem/bem/kelvin.hpp"
#include "hssbem/post/stress_kernels.hpp"

#include <array>
#include <vector>

namespace hssbem {

/// The state at one dof node: stress and the full displacement gradient G (G[3i + j] = ∂u_i/∂x_j).
struct NodeStress {
  Voigt stress{};
  Mat3 gradient{};
};

/// Stress and displacement gradient at every dof node from the nodal displacements u and
/// tractions t (node order; t at a node is σ n with the node's normal).
std::vector<NodeStress> node_stresses(const Discretization &disc, const Material &material, const std::vector<Vec3> &u, const std::vector<Vec3> &t);

/// The nodes' stress and gradient with a body force's particular solution added (its exact σ_p
/// and ∇u_p at each node's vertex), to those of the homogeneous solution: the whole field's.
std::vector<NodeStress> with_particular(std::vector<NodeStress> nodes, const Discretization &disc, const UniformBodyForce &force);

/// Per mesh vertex, the mean stress over its dof nodes (NaN for a vertex used by no triangle).
std::vector<Voigt> vertex_stress(const Discretization &disc, const std::vector<NodeStress> &nodes);

/// Stress of triangle t at its corner c (its corner's node: the stresses of different smooth
/// groups at a sharp vertex differ).
std::vector<std::array<Voigt, 3>> corner_stress(const Discretization &disc, const std::vector<NodeStress> &nodes);

/// The von Mises stress and the principal stresses (largest first) of each tensor; NaN in, NaN
/// out.
std::vector<double> von_mises_of(const std::vector<Voigt> &stress);
std::vector<Vec3> principal_of(const std::vector<Voigt> &stress);

} // namespace hssbem
