/// \file contact_session.hpp
/// A contact, whatever face drives it (the driver's problem file with "contact", the library's
/// ContactScene, the Python module): the reference factorization of the base pattern chosen
/// (dense; H²; one per body, each dense or H²; auto by the size and the machine: choice.hpp),
/// built, the contact engine over it (contact/contact_engine.hpp), the frames solved and their
/// fields. On one rank (the driver runs it on rank 0).
///
/// The contact's physics is contact/'s; this layer only assembles it: which reference, which
/// columns a dense reference keeps, which frames are known ahead, the result's fields.
#pragma once

#include "hssbem/contact/contact_engine.hpp"
#include "hssbem/core/size_limits.hpp"
#include "hssbem/io/hdf5_output.hpp"
#include "hssbem/reference/h2_reference.hpp"
#include "hssbem/session/contact_obstacles.hpp"
#include "hssbem/session/fingerprint.hpp"
#include "hssbem/session/options.hpp"
#include "hssbem/session/problem.hpp"
#include "hssbem/session/result_fields.hpp"

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace hssbem {

/// What a contact solves, whatever face made it.
struct ContactJob {
  NodeConditions base;               ///< the reference pattern (what holds the bodies) and the base values
  std::vector<Obstacle> obstacles;
  ContactSettings settings;
  /// The frames' conditions when they are known ahead (a problem file): they may change the base
  /// values, not the pattern, and only their unknowns with non-zero values need a dense
  /// reference's columns. Empty: values come per step (any unknown may carry one).
  std::vector<NodeConditions> frames;
  /// Per frame known ahead, the obstacles' poses (the engine computes their columns at once).
  std::vector<std::vector<Pose>> placements;
};

/// The contact of a problem file: its obstacles (checked: a degenerate triangle of an obstacle
/// mesh, say, names the file), settings, base rules and frames (each checked to keep the base
/// pattern) and placements (one frame, the single solve, when it has no "frames").
ContactJob contact_job(const ProblemSetup &s);

/// Per frame of `spec` (one entry, the single solve, when it has no "frames"), the obstacles'
/// poses in the order of `obstacles` (contact.obstacles'): x ↦ R (x − c) + c + t, c the frame's
/// "about" or the obstacle's default centre; an obstacle a frame does not name stays at its base.
std::vector<std::vector<Pose>> contact_placements(const ProblemSpec &spec, const std::vector<Obstacle> &obstacles);

/// What a contact precomputes, apart from the problem: per body whether its reference is the
/// H² one, the reference (a CompositeReference for several bodies), and the cache of W's columns
/// the engine fills (shared with it). The unit a saved precomputation keeps, with its fingerprint.
struct ContactPrecomputation {
  std::vector<char> on_h2;
  std::unique_ptr<ReferenceFactorization> reference;
  std::shared_ptr<ReferenceColumns> columns;
  Fingerprint fingerprint;
};

/// One body's reference as built, for the face's report.
struct ContactBodyReport {
  int unknowns = 0;
  bool h2 = false;
  double seconds = 0;          ///< its operator and reference (several bodies), or the reference alone
  double bytes = 0;
  double compress_seconds = 0, factor_seconds = 0; ///< H²
};

class ContactSession {
public:
  /// `limits`: the machine that auto's choice and the dense size check assume.
  ContactSession(std::shared_ptr<const SessionProblem> problem, ContactJob job, const SessionOptions &options, const MachineLimits &limits);
  ~ContactSession();
  ContactSession(const ContactSession &) = delete;
  ContactSession &operator=(const ContactSession &) = delete;

  /// Per body (one entry for one body), whether its reference will be the H² one.
  const std::vector<char> &on_h2() const { return m_on_h2; }
  /// "dense", "h2" or "dense,h2".
  std::string mat_type() const;

  /// Every mesh obstacle checked to face the bodies and every body to be held (ProblemError,
  /// ConstraintError naming the problem), the references built, the engine made and the columns
  /// of the frames known ahead computed.
  void set_up();
  /// A precomputation made before (a saved one) instead of set_up()'s references: refused with
  /// std::invalid_argument naming what differs when its fingerprint is not this session's.
  void adopt(std::shared_ptr<ContactPrecomputation> precomputation);
  /// What set_up() built (null before).
  const std::shared_ptr<ContactPrecomputation> &precomputation() const { return m_pre; }
  /// The fingerprint of this session's precomputation (the problem, the pattern, the kept
  /// columns of a dense reference as its candidate set, the options that shape it).
  Fingerprint fingerprint() const;
  /// Saves the precomputation (after set_up(); the columns frames added included) to `path`,
  /// which may not be one of `inputs` (session/precomputation_file.hpp: the format, the errors).
  void save(const std::string &path, const std::vector<std::string> &inputs = {}) const;
  /// Adopts the precomputation saved in `path` (before set_up(), which then builds the engine
  /// only). Throws SavedFileError naming what differs or what is damaged.
  void load(const std::string &path);

  /// Solves a frame: `values` the known values (the reference pattern's), the obstacles at their
  /// base positions at `poses` (one per obstacle, absolute; Pose::translation(offset) for a
  /// translation). Throws std::runtime_error when the solution is not finite or the frame does
  /// not converge.
  const ContactFrameReport &step(const SystemSelection &values, const std::vector<Pose> &poses);
  /// Frame i of the job's frames (the single solve: 0), with its placements.
  const ContactFrameReport &step(std::size_t i);
  /// The haptic call after a step: each obstacle's force for new offsets or poses.
  std::vector<Vec3> haptic_forces(const std::vector<Vec3> &offsets) { return m_engine->haptic_forces(offsets); }
  std::vector<Vec3> haptic_forces(const std::vector<Pose> &poses) { return m_engine->haptic_forces(poses); }

  const ContactSolution &solution() const { return m_sol; }
  const ContactFrameReport &report() const { return m_report; }
  /// The last step's fields (`parts`, result_fields.hpp), contact data and attributes, as a frame.
  FrameData frame_data(unsigned parts = kFrameFields) const;
  /// The last step as a whole result file (the single solve) of a run on `ranks` ranks: the
  /// problem's base, every field, the stress, the interior points, /contact, the options and the
  /// timings.
  ResultData result(int ranks);
  /// The part of a scene's result file that is no frame.
  ResultData base(int ranks) const;

  ContactEngine &engine() { return *m_engine; }
  const ContactEngine &engine() const { return *m_engine; }
  /// The obstacles' checks, notes and surfaces (after set_up()).
  ContactObstacles &obstacles() { return *m_drawn; }
  const ReferenceFactorization &reference() const { return *m_pre->reference; }
  /// Per body, how its reference was built.
  const std::vector<ContactBodyReport> &body_reports() const { return m_bodies; }
  /// The H² references' statistics, summed over the bodies on the H² path.
  H2ReferenceStats h2_stats() const;
  const ContactJob &job() const { return m_job; }
  const SessionProblem &problem() const { return *m_problem; }
  std::map<std::string, double> &timings() { return m_seconds; }
  OptionValues options_used() const;

private:
  const ContactFrameReport &solve(const SystemSelection &values, const std::vector<Pose> &poses, long long frame, const UniformBodyForce &force);
  /// The last step's homogeneous nodal solution (the particular displacement taken off u).
  NodalSolution homogeneous() const;
  std::unique_ptr<ReferenceFactorization> body_reference(const BemOperator &op, std::vector<char> pattern, std::vector<char> kept, bool pressure, int body);
  void make_reference();
  /// Per unknown, the columns of K₀′ a dense reference keeps (kept_columns(); empty: every one).
  std::vector<char> kept_unknowns() const;
  /// Once: the pins of the bodies contact alone holds (floating_pins) into the settings, the base
  /// pattern and the frames (prescribed, zero): the reference's pattern.
  void pin_floating();
  void pin(NodeConditions &nc) const;
  /// A frame's values with the pins (the face gives the values of the base rules' pattern).
  SystemSelection pinned(SystemSelection values) const;

  std::shared_ptr<const SessionProblem> m_problem;
  ContactJob m_job;
  SessionOptions m_options;
  MachineLimits m_limits;
  std::vector<char> m_on_h2;
  bool m_pinned = false;
  std::shared_ptr<ContactPrecomputation> m_pre;
  std::vector<ContactBodyReport> m_bodies;
  std::unique_ptr<ContactEngine> m_engine;
  std::unique_ptr<ContactObstacles> m_drawn;
  SystemSelection m_values;
  UniformBodyForce m_force;   ///< the last step's body force
  std::vector<Pose> m_poses; ///< the last step's obstacle poses
  ContactSolution m_sol;
  ContactFrameReport m_report;
  std::map<std::string, double> m_seconds;
};

} // namespace hssbem
