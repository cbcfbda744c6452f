// A contact: its reference chosen and built, its engine, its frames and fields (see contact_session.hpp).
#include "hssbem/session/contact_session.hpp"

#include "hssbem/bem/body_force.hpp"
#include "hssbem/bem/rigid_modes.hpp"
#include "hssbem/core/fault.hpp"
#include "hssbem/core/progress.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/petsc/krylov.h"
#include "hssbem/petsc/log.h"
#include "hssbem/reference/composite_reference.hpp"
#include "hssbem/session/choice.hpp"
#include "hssbem/session/petsc_call.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <stdexcept>

namespace hssbem {

namespace {

/// The obstacles, checked (a degenerate triangle of an obstacle mesh, say) with the file named.
std::vector<Obstacle> obstacles_of(const ProblemSetup &s)
{
  std::vector<Obstacle> list;
  for (std::size_t i = 0; i < s.spec.contact.obstacles.size(); ++i) {
    list.push_back(s.spec.contact.obstacles[i]);
    try {
      const ObstacleGeometry check(list.back());
    } catch (const std::invalid_argument &e) {
      const std::string where = list.back().shape == Obstacle::Shape::Mesh ? " (" + list.back().mesh_path + ")" : "";
      throw ProblemError(s.spec.file + ": contact.obstacles[" + std::to_string(i) + "]" + where + ": " + e.what());
    }
  }
  return list;
}

ContactSettings settings_of(const ProblemSetup &s)
{
  ContactSettings c;
  c.friction = s.spec.contact.friction;
  c.bodies = s.spec.contact.bodies;
  if (s.spec.contact.where) {
    c.candidate.assign(s.mesh->vertices.size(), 0);
    for (int v : select_vertices(*s.spec.contact.where, *s.mesh, s.spec.file, "contact.where")) c.candidate[v] = 1;
  }
  return c;
}

/// Every frame's conditions, checked before frame 0: a contact scene keeps the base pattern.
std::vector<NodeConditions> frames_of(const ProblemSetup &s, const NodeConditions &base)
{
  std::vector<NodeConditions> out;
  if (s.spec.frames.empty()) return {base};
  for (std::size_t f = 0; f < s.spec.frames.size(); ++f) {
    out.push_back(frame_conditions(s.spec, f, *s.disc));
    if (out.back().displacement_prescribed != base.displacement_prescribed)
      throw ProblemError(s.spec.file + ": frames[" + std::to_string(f) +
                         "].boundary: a contact scene's frames may change the values of the base rules, not which components they prescribe (the reference factorization's pattern)");
  }
  return out;
}

/// The columns of K₀′ a dense reference keeps (DenseReferenceOptions::kept_columns): those the
/// contact may load (contact_loaded_unknowns) and those of every unknown that carries a non-zero
/// known value, or a pressure, in the base rules or a frame (the free responses' right-hand
/// sides). Frames not known ahead: every column.
std::vector<char> kept_columns(std::vector<char> kept, const ContactJob &job, bool body_force)
{
  if (job.frames.empty() || body_force) return {}; // a body force's homogeneous values load every traction unknown
  std::vector<const NodeConditions *> all{&job.base};
  for (const NodeConditions &nc : job.frames) all.push_back(&nc);
  for (std::size_t i = 0; 3 * i < kept.size(); ++i)
    for (const NodeConditions *nc : all)
      for (int k = 0; k < 3; ++k)
        if (nc->value[i][k] != 0 || (!nc->pressure.empty() && !std::isnan(nc->pressure[i]))) kept[3 * i + k] = 1;
  return kept;
}

bool has_pressure(const NodeConditions &nc)
{
  return std::any_of(nc.pressure.begin(), nc.pressure.end(), [](double p) { return !std::isnan(p); });
}

/// A contact solution with a non-finite value (a singular or overflowing system) is an error
/// before anything of it is written; `frame` < 0: not a frame of a scene.
void check_finite(const ContactSolution &sol, long long frame)
{
  for (const std::vector<Vec3> *field : {&sol.u, &sol.t})
    for (const Vec3 &v : *field)
      for (double c : v)
        if (!std::isfinite(c))
          throw std::runtime_error("contact: the solution" + (frame < 0 ? std::string() : " of frame " + std::to_string(frame)) +
                                   " is not finite (the contact system is singular or overflows)");
}

} // namespace

std::vector<std::vector<Pose>> contact_placements(const ProblemSpec &spec, const std::vector<Obstacle> &obstacles)
{
  const std::size_t no = spec.contact.obstacles.size();
  std::vector<std::vector<Pose>> out(std::max<std::size_t>(1, spec.frames.size()), std::vector<Pose>(no));
  for (std::size_t f = 0; f < spec.frames.size(); ++f)
    for (const auto &[name, offset] : spec.frames[f].obstacles)
      for (std::size_t o = 0; o < no; ++o) {
        if (spec.contact.obstacles[o].name != name) continue;
        const auto turn = spec.frames[f].turns.find(name);
        if (turn == spec.frames[f].turns.end()) {
          out[f][o] = Pose::translation(offset);
          continue;
        }
        const ObstacleTurn &r = turn->second;
        out[f][o] = Pose::turn(r.axis, r.angle_deg, r.about ? *r.about : ObstacleGeometry(obstacles[o]).default_centre(), offset);
      }
  return out;
}

ContactJob contact_job(const ProblemSetup &s)
{
  ContactJob job;
  job.obstacles = obstacles_of(s);
  job.settings = settings_of(s);
  job.base = apply_rules(s.spec.rules, *s.disc, s.spec.file);
  job.frames = frames_of(s, job.base);
  job.placements = contact_placements(s.spec, job.obstacles);
  return job;
}

ContactSession::ContactSession(std::shared_ptr<const SessionProblem> problem, ContactJob job, const SessionOptions &options, const MachineLimits &limits)
    : m_problem(std::move(problem)), m_job(std::move(job)), m_options(options), m_limits(limits)
{
  m_on_h2 = contact_references_on_h2(m_problem->disc(), options.operator_type, limits);
}

ContactSession::~ContactSession() = default;

std::string ContactSession::mat_type() const { return reference_mat_type(m_on_h2); }

/// One body's reference (the whole mesh's when it is one body): the dense LU with K₀′'s kept
/// columns, or the H² one.
std::unique_ptr<ReferenceFactorization> ContactSession::body_reference(const BemOperator &op, std::vector<char> pattern, std::vector<char> kept, bool pressure, int body)
{
  ContactBodyReport &rep = m_bodies[body];
  rep.unknowns = 3 * op.num_nodes();
  rep.h2 = m_on_h2[body] != 0;
  const Timer timer;
  std::unique_ptr<ReferenceFactorization> ref;
  if (!rep.h2) {
    DenseReferenceOptions ro;
    ro.with_pressure = pressure;
    ro.reference_columns_only = true; // contact reads K₀′ alone: 16 N² bytes at most, not 24 N²
    ro.kept_columns = std::move(kept);
    ref = std::make_unique<DenseReference>(op, std::move(pattern), ro);
  } else {
    H2ReferenceOptions ho = h2_reference_options(m_options);
    ho.with_pressure = pressure;
    auto h2 = std::make_unique<H2Reference>(op, std::move(pattern), ho, HssbemH2ReferenceKrylovCreate());
    rep.compress_seconds = h2->stats().compress_seconds, rep.factor_seconds = h2->stats().factor_seconds;
    ref = std::move(h2);
  }
  rep.seconds = timer.seconds();
  rep.bytes = static_cast<double>(ref->memory_bytes());
  return ref;
}

/// One body: its reference on the whole operator. Several: a CompositeReference, each body on
/// its own surface and operator (no integral across bodies), dense or H² per m_on_h2.
void ContactSession::make_reference()
{
  const bool pressure = has_pressure(m_job.base) || std::any_of(m_job.frames.begin(), m_job.frames.end(), has_pressure);
  std::vector<char> pattern = m_job.base.unknown_pattern();
  std::vector<char> kept = kept_unknowns();
  m_pre = std::make_shared<ContactPrecomputation>();
  m_pre->on_h2 = m_on_h2;
  m_bodies.assign(m_on_h2.size(), ContactBodyReport{});
  if (m_on_h2.size() == 1) {
    m_pre->reference = body_reference(m_problem->op(), std::move(pattern), std::move(kept), pressure, 0);
    return;
  }
  const BodyReferenceFactory make = [&](const BemOperator &body_op, std::vector<char> p, std::vector<char> k, int body) {
    return body_reference(body_op, std::move(p), std::move(k), pressure, body);
  };
  auto composite = std::make_unique<CompositeReference>(m_problem->op(), node_bodies(m_problem->disc()), std::move(pattern), std::move(kept), make);
  for (int b = 0; b < composite->num_bodies(); ++b) m_bodies[b].seconds = composite->body_seconds(b);
  m_pre->reference = std::move(composite);
}

void ContactSession::set_up()
{
  if (m_engine) return;
  const EventScope event(CNT_Setup);
  const Timer timer;
  const Progress progress("contact set-up"); // reported when it ends (the reference and the engine's columns)
  const Discretization &disc = m_problem->disc();
  m_drawn = std::make_unique<ContactObstacles>(m_problem->setup(), m_job.obstacles, vertex_displacement_prescribed(disc, m_job.base), m_job.settings.candidate,
                                               m_options.contact.reach, m_options.contact.depth);
  { // judged where the file describes the obstacles (an interference a frame presses in would look like facing away), then per frame
    std::vector<std::vector<Pose>> judged{std::vector<Pose>(m_job.obstacles.size())};
    judged.insert(judged.end(), m_job.placements.begin(), m_job.placements.end());
    m_drawn->check_facing(judged);
  }
  pin_floating();
  fault_point("ContactSetup");
  if (!m_pre) make_reference();
  m_engine = std::make_unique<ContactEngine>(disc, *m_pre->reference, m_job.obstacles, m_job.settings, m_options.contact, m_pre->columns);
  m_pre->columns = m_engine->columns();
  m_pre->fingerprint = fingerprint();
  if (!m_job.placements.empty()) m_engine->prefetch(m_job.placements);
  m_seconds["contact_setup"] += timer.seconds();
}

void ContactSession::adopt(std::shared_ptr<ContactPrecomputation> pre)
{
  const std::string why = fingerprint().difference(pre->fingerprint);
  if (!why.empty()) throw std::invalid_argument("the precomputation does not fit this contact: " + why);
  m_on_h2 = pre->on_h2;
  m_pre = std::move(pre);
}

void ContactSession::pin_floating()
{
  if (m_pinned) return;
  m_pinned = true;
  const Discretization &disc = m_problem->disc();
  std::vector<char> loaded(disc.mesh().num_vertices(), 0); // the vertices a load reaches: no pin there
  std::vector<const NodeConditions *> all{&m_job.base};
  for (const NodeConditions &nc : m_job.frames) all.push_back(&nc);
  for (const NodeConditions *nc : all)
    for (int i = 0; i < disc.num_nodes(); ++i)
      for (int c = 0; c < 3; ++c)
        if (!nc->displacement_prescribed[i][c] && (nc->value[i][c] != 0 || (!nc->pressure.empty() && !std::isnan(nc->pressure[i])))) loaded[disc.node(i).vertex] = 1;
  m_job.settings.pins = floating_pins(disc, m_job.base.displacement_prescribed, m_job.obstacles, m_job.settings, m_options.contact, loaded);
  pin(m_job.base);
  for (NodeConditions &nc : m_job.frames) pin(nc);
}

void ContactSession::pin(NodeConditions &nc) const
{
  for (int j : m_job.settings.pins) nc.displacement_prescribed[j / 3][j % 3] = true, nc.value[j / 3][j % 3] = 0;
}

SystemSelection ContactSession::pinned(SystemSelection values) const
{
  for (int j : m_job.settings.pins) values.displacement_known[j / 3][j % 3] = true, values.known[j / 3][j % 3] = 0;
  return values;
}

std::vector<char> ContactSession::kept_unknowns() const
{
  const ProblemSetup &s = m_problem->setup();
  const bool body_force = !s.body_force.zero() || std::any_of(s.spec.frames.begin(), s.spec.frames.end(), [](const FrameSpec &f) { return f.gravity.has_value(); });
  return kept_columns(contact_loaded_unknowns(m_problem->disc(), m_job.base.unknown_pattern(), m_job.obstacles, m_job.settings, m_options.contact), m_job, body_force);
}

/// The options that shape the precomputation: the operator's quadrature, the reference's type and
/// compression, the candidates' reach and depth (not the frames' solver, nor the interior's).
Fingerprint ContactSession::fingerprint() const
{
  const_cast<ContactSession *>(this)->pin_floating(); // the pins are part of the pattern
  OptionValues used = options_used();
  used["bem_mat_type"] = OptionValue::of(*find_option("bem_mat_type"), mat_type());
  for (auto it = used.begin(); it != used.end();)
    it = it->first == "contact_tol" || it->first == "contact_max_it" || it->first.rfind("bem_interior_", 0) == 0 ? used.erase(it) : std::next(it);
  const bool dense = std::none_of(m_on_h2.begin(), m_on_h2.end(), [](char h) { return h != 0; });
  return hssbem::fingerprint(*m_problem, m_job.base.unknown_pattern(), dense ? kept_unknowns() : std::vector<char>{}, used, 1);
}

/// With a body force the engine takes the homogeneous problem's values and adds the particular
/// displacement (docs/body-forces.md): its u is then the whole displacement, its t the
/// homogeneous traction, which the fields complete as the static path does.
const ContactFrameReport &ContactSession::solve(const SystemSelection &values, const std::vector<Pose> &poses, long long frame, const UniformBodyForce &force)
{
  set_up();
  const Discretization &disc = m_problem->disc();
  m_force = force;
  m_values = pinned(values);
  m_poses = poses;
  ParticularTraces p = force.zero() ? ParticularTraces{} : particular_traces(disc, force);
  m_engine->set_body_force(force.force_per_volume(), std::move(p.u), std::move(p.t));
  {
    const EventScope event(SCN_Frame);
    m_report = m_engine->solve(homogeneous_selection(m_values, disc, force), poses, m_sol);
  }
  check_finite(m_sol, frame);
  return m_report;
}

NodalSolution ContactSession::homogeneous() const
{
  NodalSolution h{m_sol.u, m_sol.t};
  if (m_force.zero()) return h;
  const std::vector<Vec3> up = particular_traces(m_problem->disc(), m_force).u;
  for (std::size_t i = 0; i < h.u.size(); ++i) h.u[i] = h.u[i] - up[i];
  return h;
}

const ContactFrameReport &ContactSession::step(const SystemSelection &values, const std::vector<Pose> &poses)
{
  return solve(values, poses, -1, m_problem->setup().body_force);
}

const ContactFrameReport &ContactSession::step(std::size_t i)
{
  if (i >= m_job.placements.size() || (!m_job.frames.empty() && i >= m_job.frames.size()))
    throw std::out_of_range("contact: frame " + std::to_string(i) + " of a job without it");
  fault_point("Frame");
  const SystemSelection values = selection_of(m_job.frames.empty() ? m_job.base : m_job.frames[i]);
  const ProblemSetup &s = m_problem->setup();
  return solve(values, m_job.placements[i], s.spec.frames.empty() ? -1 : static_cast<long long>(i), s.spec.frames.empty() ? s.body_force : frame_body_force(s, i));
}

FrameData ContactSession::frame_data(unsigned parts) const
{
  const ProblemSetup &s = m_problem->setup();
  FrameData f;
  NodeConditions nc;
  nc.displacement_prescribed = m_values.displacement_known;
  put_fields(surface_fields(s, homogeneous(), m_force, vertex_displacement_prescribed(*s.disc, nc), parts), f);
  f.attributes_real = {{"seconds", m_report.seconds}};
  f.attributes_int = {{"iterations", m_report.iterations}, {"active_vertices", m_report.active_vertices}};
  f.contact = contact_data(*m_engine, m_sol, m_report, m_job.settings.bodies);
  f.obstacle_vertices = m_drawn->placed(m_poses);
  return f;
}

ResultData ContactSession::base(int ranks) const
{
  ResultData r = result_base(m_problem->setup(), ranks);
  r.attributes_str["solver"] = "contact";
  r.attributes_str["mat_type"] = mat_type();
  r.obstacles = m_drawn->surfaces(std::vector<Pose>(m_job.obstacles.size())); // the base position
  put_options(options_used(), r);
  return r;
}

ResultData ContactSession::result(int ranks)
{
  const ProblemSetup &s = m_problem->setup();
  ResultData r = base(ranks);
  NodeConditions nc;
  nc.displacement_prescribed = m_values.displacement_known;
  const NodalSolution nodal = homogeneous();
  SurfaceFields f = surface_fields(s, nodal, m_force, vertex_displacement_prescribed(*s.disc, nc), kResultFields, &m_seconds);
  const std::vector<NodeStress> nodes = f.nodes;
  put_fields(std::move(f), r);
  interior_fields(PETSC_COMM_SELF, s, nodal, nodes, m_options.interior, r, m_seconds); // the contact run is one rank's
  r.contact = contact_data(*m_engine, m_sol, m_report, m_job.settings.bodies);
  r.obstacles = m_drawn->surfaces(m_poses);
  m_seconds["contact_solve"] += m_report.seconds;
  r.timings = m_seconds;
  return r;
}

H2ReferenceStats ContactSession::h2_stats() const
{
  std::vector<const ReferenceFactorization *> parts{m_pre->reference.get()};
  if (const auto *c = dynamic_cast<const CompositeReference *>(m_pre->reference.get())) {
    parts.clear();
    for (int b = 0; b < c->num_bodies(); ++b) parts.push_back(&c->body_reference(b));
  }
  H2ReferenceStats sum;
  for (const ReferenceFactorization *p : parts)
    if (const auto *h = dynamic_cast<const H2Reference *>(p)) {
      const H2ReferenceStats &st = h->stats();
      sum.columns += st.columns, sum.column_seconds += st.column_seconds, sum.solves += st.solves, sum.iterations += st.iterations, sum.solve_seconds += st.solve_seconds;
    }
  return sum;
}

OptionValues ContactSession::options_used() const { return option_values(m_options, kContact); }

} // namespace hssbem
