/// \file contact_engine.hpp
/// Contact as physics: bodies pressed against rigid obstacles and each other, the contact area,
/// pressure and slip solved every frame on top of a reference factorization (reference.hpp).
///
/// Method (docs/contact.md has the derivation and the measurements). The reference pattern S₀
/// leaves every candidate vertex traction-known (the bodies' surface is traction-free but for
/// the base rules), so with W = A₀⁻¹ K₀′ the unknowns of any contact tractions λ are
/// x = x_f − Σ_j W(:, j) (L λ)_j, x_f the free response of the frame's known values. On the
/// frame's contact points the relative displacement in local frames (normal n, tangents t1, t2)
/// is therefore w = w_f + D λ with the compliance (Delassus) matrix D = −Mᵀ W L: a small dense
/// problem, |C| points instead of N unknowns.
///
/// Points are keyed by (dof node, partner): per candidate vertex and obstacle within reach, and
/// per candidate vertex of a slave body and other body within reach, so a vertex may touch an
/// obstacle and a body, or two bodies, at once. The point at the node facing the partner leads:
/// Signorini's and Coulomb's conditions are its. The vertex's other dof nodes follow it, as a
/// displacement rule reaches every node of a vertex: closed with it, their normal rows bound to the
/// partner (tractions of either sign) and, with friction, their tangential rows tied to the lead's
/// node. Per vertex the constraint rows stay independent: the normals (nearest partner first; an
/// obstacle's normal parallel to a nearer obstacle's is implied and dropped), then friction
/// tangents in the free directions left (a roller plane, a second partner's normal take theirs).
///
/// Gap (small deformations): g = g₀ + n·(u − u_other), g₀ measured along the obstacle's normal at
/// the point of it closest to the undeformed vertex, at the obstacle's pose. Slip, per frame (a
/// quasi-static step): the body's displacement since the previous frame relative to the
/// partner's surface point it touches — minus the rigid motion, from the previous frame's pose to
/// this one's, of the obstacle's material point touched at the previous pose; for a pair of
/// bodies minus the master surface's own step. An obstacle that moves tangentially drags what
/// sticks to it, and makes it slip once the Coulomb limit is reached. Frictionless: primal–dual
/// active set on the Signorini conditions g ≥ 0, λ_n ≥ 0, λ_n g = 0, the inverse of the active
/// block kept by a CapacitanceInverse from iteration to iteration and frame to frame (warm
/// start: the previous frame's active set), its solves checked by the touching points' gaps.
/// Friction (Coulomb, |λ_T| ≤ μ λ_n): semismooth Newton on Alart–Curnier's function, its
/// residual checked on w computed afresh. The fields then come from one product with the loaded
/// columns. A frame that does not meet the contact conditions within its iterations and rounds
/// is an error naming the frame and the residual.
///
/// Frictionless frames carry no history: each equals the static problem at its obstacle
/// poses. Frames with friction are quasi-static steps.
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
  /// Unknowns (3 · node + component) pinned to zero in the reference pattern to regularise the
  /// bodies that contact alone holds (floating_pins()): not boundary conditions. The engine adds
  /// each such body's free rigid motions as unknowns and its balance of forces as equations.
  std::vector<int> pins;
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
  /// Bodies that slide far: the body pairs are found again at the bodies' current positions (the
  /// frame's free response plus the last frame's contact response) once the bodies moved relative
  /// to each other by more than pair_again times the reach since the last pairing (a bound: their
  /// mean motions apart plus twice a node's own motion beside its body's) — 0.5 keeps every
  /// surface within half the reach of a slave vertex paired; 0: every frame; infinity: never
  /// (the undeformed pairs). Bodies that move together are not paired again.
  double pair_again = option_default::contact_pair_again;
};

/// What a frame did.
struct ContactFrameReport {
  long long iterations = 0;    ///< active-set iterations (frictionless) or Newton steps (friction), all rounds
  long long active_vertices = 0; ///< vertices touching (their facing node in the active set)
  long long stick = 0, slip = 0; ///< of them: sticking, slipping (frictionless: all slip)
  long long candidates = 0;    ///< contact points considered (per partner within reach, one per dof node of a candidate vertex)
  int rounds = 1;              ///< solves: more than one when a vertex beyond reach penetrated
  bool rebuilt = false;        ///< the active block's inverse was rebuilt, not updated (frictionless)
  long long factorizations = 0; ///< friction: Newton matrices factored (the others' systems by GMRES on a kept one)
  long long products = 0;      ///< friction: products with the Newton matrix (GMRES)
  int corrections = 0;         ///< accurate solves that corrected the answer (approximate columns only)
  double correction = 0;       ///< the last correction's relative change of the unknowns
  int balances = 0;            ///< floating bodies: solves of the contact until their forces balanced (1: none moved)
  double seconds = 0, detect_seconds = 0, solve_seconds = 0, fields_seconds = 0, correct_seconds = 0;
  bool paired = false;         ///< the bodies were paired again (at their current positions: they moved relative to each other by half the reach)
  double pair_seconds = 0;     ///< of detect_seconds: the bodies' pairing check (and pairing, when `paired`)
};

/// A frame's solution. Per dof node (u, t) and per vertex (the rest), mesh order.
struct ContactSolution {
  std::vector<double> x;            ///< the unknowns, 3 per dof node (t where S₀ prescribes u, u elsewhere)
  std::vector<Vec3> u, t;           ///< per dof node: displacement and traction (contact tractions included)
  std::vector<double> pressure;     ///< per vertex: normal contact traction, ≥ 0 (0 where free); both sides of a body pair; the largest of its partners'
  std::vector<double> gap;          ///< per vertex: the gap after deformation (NaN: no contact point there); the smallest of its partners'
  std::vector<std::int8_t> status;  ///< per vertex: 0 free, 1 stick, 2 slip (frictionless contact: 2); that of the partner pressing hardest
  /// per vertex: the contact traction of its partner pressing hardest (pressure along the normal,
  /// friction across it; Cartesian, zero where free). The nodal tractions `t` also carry the
  /// forces that hold a sharp vertex's nodes together, so Coulomb's law is read here.
  std::vector<Vec3> contact_traction;
  std::vector<Vec3> obstacle_force; ///< per obstacle: the force it exerts on the bodies
  std::vector<Vec3> body_force;     ///< per body: the force the other bodies exert on it (zero without "bodies")
  /// per body that contact alone holds (zero for the others): the rigid part of its displacement u,
  /// the least-squares fit t + θ × (x − x_c) over its dof nodes weighted by their areas — t the
  /// mean displacement of its surface (of its area centroid x_c), θ the rotation vector (radians).
  std::vector<Vec3> body_translation, body_rotation;
};

/// The pins of the bodies contact alone holds: per body whose prescribed displacements (`known`,
/// per dof node) leave rigid motions free, as few displacement components as fix them (at most
/// six, on every dof node of up to three vertices far apart, the farthest from the obstacles
/// and the other bodies at their base positions, off the vertices `loaded` marks where it can: a
/// pin's own load would be lost), as unknowns 3 · node + component, sorted. Empty when every body
/// is held. They go into the reference pattern with the value zero (ContactSettings::pins): the
/// reference of a free body is singular (docs/contact.md).
std::vector<int> floating_pins(const Discretization &disc, const std::vector<std::array<bool, 3>> &known, const std::vector<Obstacle> &obstacles,
                               const ContactSettings &settings, const ContactOptions &options = {}, const std::vector<char> &loaded = {});

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
  /// one pose per obstacle) will need: a scene's frames are known ahead. Frictionless contact
  /// needs only the columns of the points that become active; on a reference whose columns
  /// cost solves (exact_columns() false) nothing is computed ahead, the iterations ask for them.
  void prefetch(const std::vector<std::vector<Pose>> &placements);
  /// The same with the obstacles translated by offsets (one per obstacle).
  void prefetch(const std::vector<std::vector<Vec3>> &placements);
  /// Solves a frame: `values` holds the known values (the reference pattern, its values), the
  /// obstacles are at `poses` (one per obstacle, absolute: relative to their base positions).
  /// With friction the frame is a step from the last solved frame (its poses and displacements).
  /// Throws std::runtime_error "contact: frame <f>: ..." when the iterations or rounds do not meet
  /// the contact conditions, naming the residual; the haptic call then refuses to run until a
  /// frame is solved.
  const ContactFrameReport &solve(const SystemSelection &values, const std::vector<Pose> &poses, ContactSolution &out);
  /// The same with the obstacles translated by `offsets` (one per obstacle).
  const ContactFrameReport &solve(const SystemSelection &values, const std::vector<Vec3> &offsets, ContactSolution &out);
  /// The haptic call: the force each obstacle exerts at new poses, with the contact points and
  /// the active set (and stick/slip states) of the last solve: one small solve, no detection.
  /// The gaps move with the poses, and with friction so does the slip (the same rule as a frame:
  /// the step from the last solved frame's poses to these). A leading point that would pull
  /// opens, so a retracting tool feels no pulling force. Throws std::runtime_error when the last
  /// frame failed (or none was solved).
  std::vector<Vec3> haptic_forces(const std::vector<Pose> &poses);
  /// The same with the obstacles translated by `offsets`.
  std::vector<Vec3> haptic_forces(const std::vector<Vec3> &offsets);
  /// A uniform body force b (force per volume; zero: none) and its particular solution's traces
  /// per dof node (u_p, t_p: bem/body_force.hpp), from now on: the values the frames give are the
  /// homogeneous problem's (homogeneous_selection), and u_p is added to every frame's
  /// displacement, so the gaps, the slips and ContactSolution::u are the whole displacement's and
  /// λ the whole contact traction; ContactSolution::t stays the homogeneous traction. A floating
  /// body's balance takes its exact weight b V (V its volume, at its volume centroid) in place of
  /// the lumped Σ A t_p of the homogeneous loads (which differs by the discretisation: a lateral
  /// force a frictionless table could not balance).
  void set_body_force(const Vec3 &b, std::vector<Vec3> u_p, std::vector<Vec3> t_p);

  int num_obstacles() const;
  const std::string &obstacle_name(int o) const;
  const Bodies &bodies() const;
  /// The bodies contact alone holds (those of ContactSettings::pins), in increasing order.
  std::vector<int> floating_bodies() const;
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
