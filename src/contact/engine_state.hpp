// Private to contact/: the contact engine's state (contact_engine.hpp), shared by the engine's set-up
// and free responses (contact_engine.cpp) and a frame's phases (contact_frame.cpp).
#pragma once

#include "hssbem/contact/contact_engine.hpp"

#include "contact_points.hpp"

#include <memory>
#include <string>
#include <vector>

namespace hssbem {

struct ContactEngine::State {
  State(const Discretization &d, const ReferenceFactorization &r, contact_detail::Geometry geometry, const ContactOptions &o)
      : disc(&d), ref(&r), opt(o), geo(std::move(geometry)), normal(d.num_nodes() * std::max(1, geo.partners))
  {
  }
  const Discretization *disc;
  const ReferenceFactorization *ref;
  ContactOptions opt;
  contact_detail::Geometry geo;
  std::shared_ptr<ReferenceColumns> columns;
  std::vector<int> node_position;      ///< per dof node: where its rows sit in the columns
  std::vector<contact_detail::ContactPoint> body_points, points;
  bool body_points_done = false;
  std::vector<Vec3> u_response;        ///< per dof node: the last frame's displacement minus its free response (the contact's share; zero before the first)
  bool responded = false;              ///< u_response is a solved frame's: the bodies may be paired again
  std::vector<Vec3> u_paired;          ///< per dof node: the displacement the body pairs were found at (zero: undeformed)
  std::vector<char> loadable;          ///< per dof node: may carry a pair's load (contact_loaded_unknowns: its columns are kept)
  std::vector<signed char> slave_of;   ///< per pair of bodies: which one is the slave, once chosen (body_points)
  std::vector<char> forced;            ///< per (vertex, obstacle): penetrated from beyond reach once; always a point since
  double tol_gap = 0;
  double size = 0;                     ///< the mesh's bounding-box diagonal
  // the free response of the last values
  bool has_free = false;
  SystemSelection free_values;
  std::vector<double> xf;
  SystemSelection solved_values;       ///< the values of the last free response solved (not scaled)
  std::vector<double> solved_xf;       ///< and that response
  bool exact = true;                   ///< the reference's columns are exact (its x_f is never corrected)
  std::vector<Vec3> u_free;
  std::vector<Vec3> u_particular, t_particular; ///< a body force's particular traces per dof node (empty: none)
  Vec3 body_force{0, 0, 0};            ///< b, force per volume
  // the frame
  std::unique_ptr<contact_detail::Compliance> D;
  std::vector<Vec3> wf, lambda, u_prev, warm_lambda;
  std::vector<double> gap;             ///< per point: the gap after the solve
  std::vector<std::int8_t> point_status;
  std::vector<char> warm_keys;         ///< per point key: touching in the last solve (round or frame)
  std::vector<char> zone, zone_keys;   ///< per point: watched by the iterations; per key: joined this frame
  std::vector<Pose> poses;             ///< the obstacles' poses of this frame
  std::vector<Pose> step_from;         ///< the poses the step starts from: the last solved frame's (this frame's for the first)
  std::vector<Pose> last_poses;        ///< the last solved frame's poses (empty: none yet)
  double worst_penetration = 0;        ///< of the last round's checks, relative to the mesh's size
  bool friction = false, solved = false;
  long long frame = -1;                ///< the frame being solved (solve() calls so far, from 0): errors name it
  contact_detail::NormalSolver normal;
  contact_detail::FrictionSolver friction_solver;
  ContactFrameReport report;
  std::vector<Pose> warm_poses;        ///< the obstacles' poses of the warm start
  TriangleBvh surface;                 ///< the mesh's triangles (the warm start's interpolation)
  // bodies held by contact alone (floating.cpp)
  /// A floating body: its free rigid motions q = Σ_k α_k modes[k] in the coordinates
  /// (a, L θ) — a translation and a rotation θ about the centroid x0 scaled by the body's size L —
  /// move its points by a + θ × (x − x0).
  struct Floating {
    int body = -1, lowest = -1;       ///< the body and its lowest vertex (errors name them)
    Vec3 x0{};
    double L = 1;
    std::vector<std::array<double, 6>> modes; ///< orthonormal, the motions its prescribed displacements leave free
    int first = 0;                    ///< its first entry in alpha
    double volume = 0;                ///< its volume (divergence theorem over its triangles)
    Vec3 xg{};                        ///< its volume centroid
  };
  std::vector<Floating> floating;
  std::vector<int> node_floating;      ///< per dof node: its floating body (index into floating) or -1
  std::vector<char> pinned;            ///< per unknown: a pin (ContactSettings::pins)
  std::vector<double> alpha;           ///< every floating body's motion coordinates (kept from frame to frame)

  void set_up_floating(const std::vector<int> &pins);
  /// Per motion coordinate, the body force's generalized force: the exact weight b V at the
  /// volume centroid, less the lumped Σ A t_p the homogeneous loads carry.
  std::vector<double> weight_correction() const;
  /// The motion of node i's body at it for the coordinates a (alpha's layout; zero for a held body).
  Vec3 rigid_at(int i, const std::vector<double> &a) const;
  /// Mode k of floating body f at node i.
  Vec3 mode_at(const Floating &f, int k, int i) const;
  /// The frame solved with the floating bodies balanced: the contact solved (rounds) at their
  /// motions, then Newton on the motions until the forces and moments on each balance.
  void settle(ContactSolution &out, ContactFrameReport &rep);
  /// Per motion coordinate, the generalized force on its body: the frame's loads and the contact
  /// tractions λ (their loads on the traction-known unknowns); `gross`: the sum of the forces'
  /// magnitudes (the balance's scale).
  std::vector<double> balance(const std::vector<Vec3> &lam, double *gross = nullptr) const;
  /// ∂balance/∂alpha on the current active set (and stick/slip states).
  std::vector<double> balance_jacobian(const std::vector<double> &r0);
  bool newton_step(const std::vector<double> &r, std::vector<double> &step, std::vector<double> &unresisted);
  /// λ for the free relative displacements w with the current active set (and states).
  std::vector<Vec3> resolve(const std::vector<Vec3> &w);
  /// The free relative displacements with the floating bodies moved by da more.
  std::vector<Vec3> moved_w(const std::vector<double> &da) const;
  /// Where the balance has no Newton step (the contact does not resist r's part `unresisted`):
  /// the motion along it that closes the nearest open point, or an error naming the body.
  std::vector<double> closing_move(const std::vector<double> &unresisted) const;
  std::string unbalanced_error(const std::vector<double> &unresisted) const;
  /// The rigid part of body b's displacement u (ContactSolution::body_translation, body_rotation).
  void rigid_part(int b, const std::vector<Vec3> &u, Vec3 &t, Vec3 &theta) const;

  void free_response(const SystemSelection &values);
  void set_u_free();
  /// The solve of a frame's points until no vertex went through (rounds of detection).
  void rounds(ContactSolution &out, ContactFrameReport &rep);
  void correct(const SystemSelection &values, ContactSolution &out, ContactFrameReport &rep);
  void detect();
  /// The body pairs (contact_detail::body_points): found in the undeformed geometry first, and
  /// again at the bodies' current positions once those moved relative to each other by more than
  /// pair_again times the reach since the last pairing (relative_motion()). The current positions: this frame's free response (its
  /// prescribed motion, and what that moves with it) plus the last frame's contact response (its
  /// solved displacement minus its free response); the first frame (a static solve) keeps the
  /// undeformed pairs. Returns whether it paired.
  bool pair_bodies();
  /// A bound on how far any two points of different bodies moved relative to each other between
  /// the displacements u_paired and u: the bodies' mean motions apart plus twice the largest
  /// motion of a node beside its body's mean. Pairs found within the reach r at u_paired hold
  /// every master surface within r minus this of a slave vertex at u.
  double relative_motion(const std::vector<Vec3> &u) const;
  /// Each obstacle point's rigid motion over the step (ContactPoint::motion).
  void set_motions();
  void solve_points(ContactFrameReport &rep);
  void fields(ContactSolution &out) const;
  void point_gaps(const ContactSolution &out, bool single);
  /// Frictionless: the touching points' gaps after the solve are zero to 1e-8 of the gaps the
  /// tractions closed (the capacitance solves checked by their residual); the largest, relative.
  double gap_residual() const;
  /// The fields in single precision: frictionless frames on exact columns only (friction
  /// measures the next frame's slip from the fields, and approximate columns are corrected
  /// against the fields to 1e-8, below single precision's 1e-7).
  bool single_fields() const { return opt.single_fields && !friction && ref->exact_columns(); }
  bool zone_violations();
  bool penetrations(const ContactSolution &out);
  void outputs(ContactSolution &out) const;
  /// The warm start of the next solve (round or frame): the active set and its tractions.
  void remember();
  Vec3 predicted_traction(int c);
  /// The rigid motion from pose `from` to pose `to` of obstacle p's material point touched at
  /// `from` (the obstacle's point closest to the vertex there): the obstacle's share of the slip.
  Vec3 step_motion(const contact_detail::ContactPoint &p, const Pose &to, const Pose &from) const;
  /// "contact: frame <f>: <what>".
  std::string frame_error(const std::string &what) const;
};

} // namespace hssbem
