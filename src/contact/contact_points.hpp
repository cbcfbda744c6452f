// Private to contact/: a frame's contact points (detect.cpp), their compliance from the
// reference's columns (compliance.cpp), and the two solvers on it (normal_solver.cpp,
// friction_solver.cpp). See contact_engine.hpp for the method.
#pragma once

#include "hssbem/bem/discretization.hpp"
#include "hssbem/contact/bodies.hpp"
#include "hssbem/contact/obstacle.hpp"
#include "hssbem/reference/capacitance.hpp"
#include "hssbem/reference/reference.hpp"

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

namespace hssbem::contact_detail {

/// One contact point: a candidate vertex against a partner — an obstacle or another body. Points
/// are keyed by (node, partner): a vertex may touch an obstacle and a body, or two bodies, at once,
/// each through points of its own. The point at the node facing the partner leads: Signorini's
/// and Coulomb's conditions are its. Every other dof node of the vertex (a sharp vertex's face
/// groups) follows it: closed while the lead is, its normal row bound to the partner like the
/// lead's (g = 0, its traction of either sign: it is a shear of its own face), and — for the
/// vertex's anchor partner (the nearest) with friction — its tangential rows tied to the anchor's
/// node along the anchor's friction tangents (equal and opposite forces, internal to the body):
/// a stuck vertex holds all its nodes, as a displacement rule reaches every node of a vertex.
/// Row k of its relative displacement is Σ_i mw[i][k] (frame[k] · u(node[i])) (the slave node,
/// minus the master triangle's nodes interpolated, or the anchor's node for a tie row); its
/// contact traction λ (local frame) loads node[i] with Σ_k lw[i][k] λ_k frame[k]: the slave node
/// with λ, the master's nodes with −β_i a_s / a_i λ (equal and opposite forces).
struct ContactPoint {
  int vertex = -1, node = -1;   ///< slave vertex and this point's dof node
  bool facing = true;           ///< a leading point (at the node facing its partner); false: a follower at another node of the vertex
  int lead = -1;                ///< a follower's leading point (its index in the frame's points); -1 for a leading point
  int obstacle = -1;            ///< the obstacle, or -1 for a pair of bodies
  int body = -1, other = -1;    ///< the slave's body; the master body (body pairs), else -1
  int partner = 0;              ///< the obstacle, or the number of obstacles plus the master body
  int key = -1;                 ///< node × partners + partner: the point from frame to frame (warm starts, kept inverses)
  int terms = 1;
  std::array<int, 5> term_node{};
  std::array<Vec3, 5> mw{}, lw{}; ///< per term, per local row k: the measure's and the load's weights
  std::array<Vec3, 3> frame{};  ///< n (from the obstacle or the master toward the slave), t1, t2
  std::array<bool, 3> held{};   ///< local components that carry no contact traction (prescribed, or dependent on the node's other rows)
  double g0 = 0;                ///< gap of the undeformed geometry
  double mu = 0;                ///< Coulomb coefficient
  double area = 0;              ///< the slave node's lumped area
  Vec3 anchor{};                ///< obstacle: its material point touched at the start of the step (base position)
  Vec3 motion{};                ///< obstacle: that point's rigid motion over the step (the obstacle's share of the slip)
};

/// What detection needs of the mesh, built once.
struct Geometry {
  const Discretization *disc = nullptr;
  Bodies bodies;
  std::vector<double> area;               ///< lumped area per dof node
  std::vector<char> candidate;            ///< per vertex: may touch (where, and not held in all three components)
  std::vector<TriangleBvh> body_bvh;      ///< per body, its triangles
  std::vector<ObstacleGeometry> obstacles;
  int partners = 0;                       ///< obstacles plus bodies: the partner numbers of ContactPoint
  double friction = 0;                    ///< the global coefficient
  bool bodies_touch = false;
  double reach = 0;
  const std::vector<char> *pattern = nullptr; ///< per unknown: 1 where u is prescribed (S₀)
};

/// The tangents of a unit normal: t1 ⟂ n along the coordinate axis least aligned with n, t2 = n × t1.
std::array<Vec3, 3> local_frame(const Vec3 &n);

/// The dof node of vertex v facing direction n (its smooth group's normal most opposite to n).
int facing_node(const Discretization &disc, int v, const Vec3 &n);

/// The obstacles' contact points at the poses `poses` (one per obstacle): per candidate vertex and
/// obstacle within reach (or at any distance when `forced[v × obstacles + o]`), a point per dof
/// node of the vertex whose displacement along the normal is not all prescribed.
std::vector<ContactPoint> obstacle_points(const Geometry &g, const std::vector<Pose> &poses, const std::vector<char> &forced);

/// Where the bodies are paired: the undeformed geometry (no displacement), or the bodies moved by
/// a displacement per dof node (their current positions: a frame's prescribed motion and the last
/// solved displacement), with their triangles' hierarchies at those positions.
struct BodyPlacement {
  BodyPlacement() = default;
  /// `loadable` (per dof node; empty: every node): the master nodes a pair may load (those whose
  /// columns the reference keeps); a pair whose master triangle has another node is not made.
  BodyPlacement(const Geometry &g, std::vector<Vec3> displacement, std::vector<char> loadable = {});
  std::vector<Vec3> u;             ///< per dof node (empty: the undeformed geometry)
  std::vector<char> loadable;      ///< per dof node (empty: every node)
  std::vector<Vec3> vertices;      ///< the vertices moved by u (their nodes' mean)
  std::vector<TriangleBvh> bvh;    ///< per body, its triangles at `vertices`
  std::vector<std::vector<int>> triangles_of; ///< per vertex, its triangles
};

/// The pairs of bodies: per candidate vertex of a slave body, the closest point of each other
/// body's surface within reach (node-to-surface, one pass per pair: the body with the finer
/// mesh near the contact is the slave), in the placement `at`. Moved bodies: the gap, normal and
/// closest point are those of the moved surfaces, and g0 is the gap linearised about `at.u`
/// (g0 + n · (u_s − Σ β_i u_i) is the moved configuration's gap at u = at.u). `slave_of` (per
/// pair a × bodies + b, a < b: 0 not chosen yet, 1 body a is the slave, 2 body b): a pair's
/// slave once chosen stays (found again, the points keep their keys and their side); null:
/// chosen afresh.
std::vector<ContactPoint> body_points(const Geometry &g, const BodyPlacement &at = {}, std::vector<signed char> *slave_of = nullptr);

/// A frame's points from the obstacles' and the bodies' (every (vertex, partner) kept), with their
/// local frames, the followers at the vertices' other nodes and their leads (ContactPoint::lead),
/// sorted by where their node's rows sit in the columns (`position`: per dof node). Per vertex
/// the constraint rows stay independent: its free directions (its components not prescribed)
/// carry the normals first (by gap, smallest first; an obstacle's point whose normal is parallel
/// to a nearer obstacle's is implied by it and dropped), then the friction tangents of each point
/// in the free directions no normal and no earlier tangent takes (a roller plane, a second
/// partner's normal take theirs); a tangent left without such a direction is held.
std::vector<ContactPoint> merge_points(const Geometry &g, std::vector<ContactPoint> a, const std::vector<ContactPoint> &b, const std::vector<int> &position = {});

/// The dof nodes in a spatial order (Morton's curve over their positions) as a row order of the
/// unknowns (3 per node, kept together): a contact's candidates then sit in a few runs of rows.
std::vector<int> spatial_row_order(const Discretization &disc);

/// The compliance of a frame's points: with x = x_f − Σ_j W(:, j) v_j, their local relative
/// displacements are w = w_f + D λ, D(ck, c'l) = −Σ m_ck(r) W(r, j) l_c'l(j) over the rows r
/// where u is unknown and the loaded columns j where t is known.
class Compliance {
public:
  /// Requires the columns the points load from `columns` (which must outlive the compliance).
  /// With `normal_only` (frictionless contact: tractions along the normals alone) only those a
  /// normal traction loads, and only as require() asks for them: a point's column is needed only
  /// once it is loaded (active), the others' gaps read the loaded columns' rows. block() must
  /// not be used then; normal() and apply_normal() are exact for required (loaded) points.
  Compliance(const std::vector<ContactPoint> &points, const std::vector<char> &pattern, ReferenceColumns &columns, bool normal_only = false);
  /// Makes sure the columns the points `cs` load are here (normal_only: in one blocked call).
  void require(const std::vector<int> &cs) const;

  int size() const { return static_cast<int>(m_points->size()); }
  const ContactPoint &point(int c) const { return (*m_points)[c]; }
  /// D(c, c') in the local frames (row k of c, column l of c').
  Mat3 block(int c, int cp) const;
  /// D(c n, c' n): the normal-normal entry.
  double normal(int c, int cp) const;
  /// Local component k of point c is held: its displacement is prescribed (a roller along a
  /// tangent, say) or its row depends on the node's other rows (ContactPoint::held), so it neither
  /// slips nor carries a contact traction.
  bool held(int c, int k) const { return m_held[c][k] != 0; }
  /// The free relative displacement of every point (local frame) from the nodal displacements
  /// u_free (prescribed where known) and u_prev (the last frame's; empty: zero): the gap, and the
  /// slip over the step — the body's displacement since u_prev relative to the partner's surface
  /// point: minus the obstacle point's rigid motion (ContactPoint::motion), or the master's nodes'
  /// own step (the pair's terms). A follower's tie rows: its whole displacement relative to the
  /// anchor's node (not a step).
  std::vector<Vec3> free_w(const std::vector<Vec3> &u_free, const std::vector<Vec3> &u_prev) const;
  /// out[r] += Σ_q D(rows[r] n, cols[q] :) λ[q]: the normal gaps of the points `rows` moved by
  /// the tractions λ (local frames) at the points `cols`, column by column (each column's rows
  /// read in increasing order: the points are sorted by their rows).
  void apply_normal(const std::vector<int> &rows, const std::vector<int> &cols, const Vec3 *lambda, double *out) const;
  /// The loads of the tractions λ (local frame, one per point): pairs (unknown j, value) with
  /// the traction-known unknowns only.
  void loads(const std::vector<Vec3> &lambda, std::vector<int> &unknowns, std::vector<double> &values) const;

private:
  /// Per point and term, the masked rows M (local k × Cartesian a: u unknown) and load columns L
  /// (Cartesian b × local l: t known), weights included.
  struct Terms {
    std::array<Mat3, 5> M, L;
    std::array<std::array<const double *, 3>, 5> col; ///< W's columns of the term's node (null: not loaded)
    std::array<int, 5> row;                           ///< where the term's node's rows sit in a column
  };
  /// Point c's column pointers from the cache (they stay valid for the cache's life).
  void attach(int c) const;
  const std::vector<ContactPoint> *m_points;
  ReferenceColumns *m_columns;
  bool m_normal_only;
  mutable std::vector<Terms> m_terms;  ///< column pointers attached as require() asks (a cache)
  mutable std::vector<char> m_attached;
  std::vector<std::array<char, 3>> m_held;
  const std::vector<char> *m_pattern;
};

/// The unknowns whose columns of W the points load (traction-known components of their terms'
/// nodes); with `normal_only`, only those a normal traction loads (a plane's points along z: one
/// column per node instead of three).
std::vector<int> loaded_unknowns(const std::vector<ContactPoint> &points, const std::vector<char> &pattern, bool normal_only);

/// Frictionless contact: primal–dual active set on the normal compliance, the inverse of the
/// active block kept by a CapacitanceInverse over the points' keys that lives from frame to frame.
class NormalSolver {
public:
  explicit NormalSolver(int num_keys);
  struct Result {
    int iterations = 0;
    bool rebuilt = false;
  };
  /// λ_n per point (local frame, tangential 0) for free gaps wf[c][0], starting from the points
  /// whose key is in `warm` (key flags); tol_gap: how deep an inactive point may sit before it
  /// joins. Leading points switch; a follower is active with its lead, its λ_n of either sign.
  /// Only the points of `zone` (per point) are watched: the caller checks the others' gaps in the
  /// fields and solves again with them when one went through. Throws std::runtime_error after
  /// max_it iterations, naming the residual (penetrations relative to `size`, the mesh's size).
  /// `monitor(it, active, changed)`.
  Result solve(const Compliance &D, const std::vector<Vec3> &wf, const std::vector<char> &warm, const std::vector<char> &zone, double tol_gap, double size, int max_it,
               std::vector<Vec3> &lambda, const std::function<void(int, long long, long long)> &monitor);
  /// λ_n of the current active set for other free gaps: the points must be those of the last solve.
  void resolve(const Compliance &D, const std::vector<Vec3> &wf, std::vector<Vec3> &lambda) const;
  /// The haptic call: as resolve(), but a leading point that would pull opens (with its
  /// followers) and an open one whose gap closes rejoins (open_pulling_points).
  void haptic(const Compliance &D, const std::vector<Vec3> &wf, double tol_gap, std::vector<Vec3> &lambda) const;
  /// Forget the kept inverse: the next solve rebuilds it (after a solve whose residual was too large).
  void reset();

private:
  class Entries;
  void sync(const Compliance &D, const std::vector<int> &active_keys, bool *rebuilt);
  std::shared_ptr<Entries> m_entries;
  CapacitanceInverse m_cap;
  std::vector<ContactPoint> m_signature; ///< per key in the capacitance set: the point it was added with
  int m_updates = 0;
  bool m_stale = false;                  ///< reset(): rebuild at the next sync
};

/// Coulomb friction: semismooth Newton on Alart–Curnier's function, warm-started from λ.
class FrictionSolver {
public:
  struct Result {
    int iterations = 0;     ///< Newton steps
    int factorizations = 0; ///< of them: the Newton matrix factored
    long long products = 0; ///< products with the Newton matrix (GMRES)
  };
  struct Preconditioner; ///< the Newton matrix of an earlier step, factored
  /// λ (local frames) for the free relative displacements wf; λ holds the initial guess.
  /// status per point: 0 open, 1 stick, 2 slip (a follower: 1 while closed). Newton runs on the
  /// points of `zone` (per point): the others keep λ = 0; the caller checks their gaps in the
  /// fields, as for the frictionless solver. Converged when max |Φ| ≤ tol × the traction scale on
  /// w = w_f + D λ computed afresh. Throws std::runtime_error after max_it iterations, naming the
  /// residual.
  Result solve(const Compliance &D, const std::vector<Vec3> &wf, const std::vector<char> &zone, double tol, int max_it, std::vector<Vec3> &lambda,
               std::vector<std::int8_t> &status, const std::function<void(int, long long, long long, double)> &monitor);
  /// The haptic call: λ with the stick and slip states (and slip directions) of the last solve
  /// fixed, for other free relative displacements (one solve with the factored fixed-state
  /// system); a leading point that would pull opens with its followers (open_pulling_points).
  void haptic(const Compliance &D, const std::vector<Vec3> &wf, double tol_gap, std::vector<Vec3> &lambda);
  /// The last solve's slipping points with friction held stuck in the fixed-state system (haptic()
  /// then answers as if they stuck): the floating bodies' Newton, where sliding points alone do not
  /// resist a motion that sticking ones would. The next solve sets the states afresh.
  void stick_slipping_points(const Compliance &D);
  /// λ of the fixed-state system alone for other free relative displacements: every point of
  /// the last solve closed in its state (no point opens; the answer is linear in wf).
  void fixed_states(const Compliance &D, const std::vector<Vec3> &wf, std::vector<Vec3> &lambda);

private:
  void factor_fixed_states(const Compliance &D);
  std::vector<double> fixed_state_answer(const Compliance &D, const std::vector<Vec3> &wf);
  std::vector<double> m_lu;          ///< the fixed-state system of the last solve, factored (haptic)
  std::vector<int> m_piv, m_rows;    ///< its pivots and the points it covers
  std::vector<std::int8_t> m_state;
  std::vector<Vec3> m_direction;     ///< slip directions (local tangential) of the last solve
  bool m_factored = false;
  std::shared_ptr<Preconditioner> m_pre; ///< kept from step to step and frame to frame
};

/// The haptic call's small active set on the last solve's closed points `points` (k rows each,
/// the normal row first), whose fixed-state system A is factored: y = A⁻¹ rhs is the answer with
/// every point closed. With O the open points, λ = y + A⁻¹(:, O) r, A⁻¹(O, O) r = −y(O): λ
/// vanishes on O and O's rows carry the residual r (a normal row's residual is the point's gap).
/// A leading point whose λ_n < 0 opens with its followers; an open one whose gap is below
/// −tol_gap closes again; repeated until nothing changes (nothing to do, and no work, when no
/// leading point pulls). `inverse_columns(rows, out)` fills the columns `rows` of A⁻¹ (k |points|
/// entries each, one after the other). Returns λ (k per point).
std::vector<double> open_pulling_points(const Compliance &D, const std::vector<int> &points, int k, const std::vector<double> &y,
                                        const std::function<void(const std::vector<int> &, double *)> &inverse_columns, double tol_gap);

} // namespace hssbem::contact_detail
