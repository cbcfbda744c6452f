/// \file contact_engine.hpp
/// Contact as physics: bodies pressed against rigid obstacles and each other, the contact area,
/// pressure and slip solved every frame on top of a reference factorization (reference.hpp).
///
/// Method (docs/contact.md has the derivation and the measurements). The reference pattern S₀
/// leaves every candidate vertex traction-known (the bodies' surface is traction-free but for
/// the base rules), so with W = A₀⁻¹ K₀′ the unknowns of any contact tractions λ are
/// x = x_f − Σ_j W(:, j) (L λ)_j, x_f the free response of the frame's known values. On the
/// frame's contact points (candidate vertices within reach of an obstacle or another body; one
/// point per dof node, a sharp vertex's nodes sharing its gap and normal) the relative displacement in local
/// frames (normal n, tangents t1, t2) is therefore w = w_f + D λ with the compliance (Delassus)
/// matrix D = −Mᵀ W L: a small dense problem, |C| points instead of N unknowns. Gap (small
/// deformations): g = g₀ + n·(u − u_other), g₀ measured along the obstacle's normal at the point
/// of it closest to the undeformed vertex; slip: the tangential displacement since the previous
/// frame (a single solve: since the undeformed state). Frictionless: primal–dual active set on
/// the Signorini conditions g ≥ 0, λ_n ≥ 0, λ_n g = 0, the inverse of the active block of D kept
/// by a CapacitanceInverse from iteration to iteration and frame to frame (warm start: the
/// previous frame's active set). Friction (Coulomb, |λ_T| ≤ μ λ_n): semismooth Newton on
/// Alart–Curnier's function. The fields then come from one product with the loaded columns.
///
/// Frictionless frames carry no history: each equals the static problem at its obstacle
/// positions. Frames with friction are quasi-static steps.
#pragma once

#include "hssbem/bem/discretization.hpp"
#include "hssbem/contact/bodies.hpp"
#include "hssbem/contact/obstacle.hpp"
#include "hssbem/core/option_table.hpp"
#include "hssbem/reference/reference.hpp"

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace hssbem {

/// What the bodies touch: set once per contact problem.
struct ContactSettings {
  double friction = 0;          ///< Coulomb coefficient of every pair (an obstacle's own wins); 0: frictionless
  bool bodies = false;          ///< contact between the mesh's bodies too (bodies.hpp)
  std::vector<char> candidate;  ///< per vertex: may touch (empty: every vertex); a vertex with three prescribed displacements never does
};

/// One iteration of a frame, for a monitor.
struct ContactIteration {
  int iteration = 0;           ///< 1, 2, ... (friction: Newton steps so far)
  long long active = 0;        ///< contact points touching
  long long changed = 0;       ///< points whose state changed
  double residual = 0;         ///< friction: max |Φ| relative to the traction scale; frictionless: 0
};

struct ContactOptions {
  /// Relative tolerance: a free point joins the active set once it penetrates by more than tol
  /// times the mesh's size; friction's Newton stops at max |Φ| ≤ tol × the traction scale.
  double tol = option_default::contact_tol;
  int max_it = option_default::contact_max_it; ///< iterations per frame before it is an error
  double reach = option_default::contact_reach; ///< candidates: vertices within this gap (0: 5 % of the mesh's bounding-box diagonal)
  double depth = option_default::contact_depth; ///< a vertex deeper than this behind an open mesh obstacle is not in contact with it (0: the reach; obstacle.hpp)
  bool warm_start = true;      ///< start from the previous frame's active set (and tractions)
  /// Frictionless frames: the fields' product with W's loaded columns in single precision (half
  /// the memory traffic); the contact's share of the fields then carries relative errors of
  /// about 1e-7 (the contact tractions themselves are solved in double). Frames with friction
  /// always use double: the next frame's slip is measured from these fields; so do frames on
  /// approximate columns (H2Reference), whose corrections compare the fields to 1e-8.
  bool single_fields = true;
  std::function<void(const ContactIteration &)> monitor; ///< called after every iteration (may be empty)
  /// On a reference whose columns are approximate (ReferenceFactorization::exact_columns()
  /// false: H2Reference), the frame's answer is corrected with accurate solves until one changes
  /// the unknowns by at most correction_tol relative to them (max_it corrections at most).
  double correction_tol = 1e-8;
};

/// What a frame did.
struct ContactFrameReport {
  long long iterations = 0;    ///< active-set iterations (frictionless) or Newton steps (friction), all rounds
  long long active_vertices = 0; ///< vertices touching (their facing node in the active set)
  long long stick = 0, slip = 0; ///< of them: sticking, slipping (frictionless: all slip)
  long long candidates = 0;    ///< contact points considered (one per dof node of a candidate vertex)
  int rounds = 1;              ///< solves: more than one when a vertex beyond reach penetrated
  bool rebuilt = false;        ///< the active block's inverse was rebuilt, not updated (frictionless)
  long long factorizations = 0; ///< friction: Newton matrices factored (the others' systems by GMRES on a kept one)
  long long products = 0;      ///< friction: products with the Newton matrix (GMRES)
  int corrections = 0;         ///< accurate solves that corrected the answer (approximate columns only)
  double correction = 0;       ///< the last correction's relative change of the unknowns
  double seconds = 0, detect_seconds = 0, solve_seconds = 0, fields_seconds = 0, correct_seconds = 0;
};

/// A frame's solution. Per dof node (u, t) and per vertex (the rest), mesh order.
struct ContactSolution {
  std::vector<double> x;            ///< the unknowns, 3 per dof node (t where S₀ prescribes u, u elsewhere)
  std::vector<Vec3> u, t;           ///< per dof node: displacement and traction (contact tractions included)
  std::vector<double> pressure;     ///< per vertex: normal contact traction, ≥ 0 (0 where free); both sides of a body pair
  std::vector<double> gap;          ///< per vertex: the gap after deformation (NaN: no contact point there)
  std::vector<std::int8_t> status;  ///< per vertex: 0 free, 1 stick, 2 slip (frictionless contact: 2)
  std::vector<Vec3> obstacle_force; ///< per obstacle: the force it exerts on the bodies
  std::vector<Vec3> body_force;     ///< per body: the force the other bodies exert on it (zero without "bodies")
};

/// Every body's rigid motions must be held. Throws ConstraintError (bem/rigid_modes.hpp) naming
/// the body (its number and lowest vertex) and its free motions when its prescribed
/// displacements (`known`, per dof node) leave some free: "held only by frictionless contact,
/// which leaves it free to ..." when the contact candidates at the obstacles' base positions
/// cannot hold it either, else that bodies held by contact alone are not supported yet.
void check_bodies_held(const Discretization &disc, const std::vector<std::array<bool, 3>> &known, const std::vector<Obstacle> &obstacles,
                       const ContactSettings &settings, const ContactOptions &options = {});

/// Per unknown, 1 where a contact of these obstacles and settings may load it in some frame (and
/// so ask its column of W): the candidates' unknowns, and the master nodes of the body pairs
/// (found once, in the undeformed geometry). What a dense reference must keep of K₀′
/// (DenseReferenceOptions::kept_columns), with the unknowns whose known values are not zero.
std::vector<char> contact_loaded_unknowns(const Discretization &disc, const std::vector<char> &pattern, const std::vector<Obstacle> &obstacles, const ContactSettings &settings,
                                          const ContactOptions &options = {});

class ContactEngine {
public:
  /// `reference` (whose pattern must leave the candidates traction-known where they are not
  /// held) must outlive the engine. `columns`: a cache of W's columns to share with other
  /// engines on the same reference (null: the engine's own, rows in spatial_order()). Throws
  /// std::invalid_argument for a bad obstacle, a candidate list of the wrong size or options
  /// out of range.
  ContactEngine(const Discretization &disc, const ReferenceFactorization &reference, std::vector<Obstacle> obstacles, const ContactSettings &settings,
                const ContactOptions &options = {}, std::shared_ptr<ReferenceColumns> columns = nullptr);
  ~ContactEngine();
  ContactEngine(const ContactEngine &) = delete;
  ContactEngine &operator=(const ContactEngine &) = delete;

  /// Computes now, in one blocked call, the columns of W every placement of `placements` (each
  /// one offset per obstacle) will need: a scene's frames are known ahead. Frictionless contact
  /// needs only the columns of the points that become active; on a reference whose columns
  /// cost solves (exact_columns() false) nothing is computed ahead, the iterations ask for them.
  void prefetch(const std::vector<std::vector<Vec3>> &placements);
  /// Solves a frame: `values` holds the known values (the reference pattern, its values), the
  /// obstacles are at their base positions translated by `offsets` (one per obstacle). Throws
  /// std::runtime_error when the iterations do not settle within the options' maximum.
  const ContactFrameReport &solve(const SystemSelection &values, const std::vector<Vec3> &offsets, ContactSolution &out);
  /// The haptic call: the force each obstacle exerts for new offsets, with the contact points,
  /// the active set (and stick/slip states) of the last solve: one small solve, no detection.
  std::vector<Vec3> haptic_forces(const std::vector<Vec3> &offsets);

  int num_obstacles() const;
  const std::string &obstacle_name(int o) const;
  const Bodies &bodies() const;
  double reach() const;
  /// Bytes held by the engine (the columns of W above all; not the reference's own).
  std::size_t memory_bytes() const;
  /// The cache of W's columns (shared with the engines given it).
  const std::shared_ptr<ReferenceColumns> &columns() const;
  /// The dof nodes in a spatial order, as a row order of the unknowns (ReferenceColumns' rows).
  static std::vector<int> spatial_order(const Discretization &disc);

private:
  struct State;
  std::unique_ptr<State> m;
};

} // namespace hssbem
