// A scene on the dense scene engine (see scene_session.hpp).
#include "hssbem/session/scene_session.hpp"

#include "hssbem/bem/rigid_modes.hpp"
#include "hssbem/core/fault.hpp"
#include "hssbem/core/timer.hpp"
#include "hssbem/petsc/log.h"
#include "hssbem/session/choice.hpp"
#include "hssbem/session/petsc_call.hpp"
#include "hssbem/session/precomputation_file.hpp"
#include "hssbem/io/saved_file.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hssbem {

namespace {

bool uses_pressure(const ProblemSpec &spec)
{
  auto any = [](const std::vector<BoundaryRule> &rules) {
    return std::any_of(rules.begin(), rules.end(), [](const BoundaryRule &r) { return r.kind == BoundaryRule::Kind::Pressure; });
  };
  if (any(spec.rules)) return true;
  return std::any_of(spec.frames.begin(), spec.frames.end(), [&](const FrameSpec &f) { return any(f.rules); });
}

/// Per vertex, the components `sel` prescribes (those of the vertex's first dof node).
std::vector<std::array<bool, 3>> prescribed_per_vertex(const Discretization &disc, const SystemSelection &sel)
{
  NodeConditions nc;
  nc.displacement_prescribed = sel.displacement_known;
  return vertex_displacement_prescribed(disc, nc);
}

} // namespace

long long SceneReference::count() const
{
  return candidates.empty() ? 3LL * static_cast<long long>(selection.displacement_known.size()) : std::count(candidates.begin(), candidates.end(), 1);
}

std::vector<char> SceneReference::pattern() const
{
  std::vector<char> out(3 * selection.displacement_known.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = selection.displacement_known[i / 3][i % 3];
  return out;
}

SceneReference scene_reference(const ProblemSetup &s)
{
  NodeConditions ref_nc = apply_rules(s.spec.rules, *s.disc, s.spec.file);
  std::string ref_name = "the base rules";
  if (analyse_constraints(*s.disc, ref_nc.displacement_prescribed).rank != 6) ref_nc = frame_conditions(s.spec, 0, *s.disc), ref_name = "frame 0";
  SceneReference ref{selection_of(ref_nc), ref_name, std::vector<char>(3 * static_cast<std::size_t>(s.disc->num_nodes()), 0), uses_pressure(s.spec)};
  for (std::size_t f = 0; f < s.spec.frames.size(); ++f) // a body force loads the unknowns its traces reach: the homogeneous frame's
    mark_scene_candidates(ref.selection, homogeneous_selection(selection_of(frame_conditions(s.spec, f, *s.disc)), *s.disc, frame_body_force(s, f)), ref.candidates);
  return ref;
}

void check_scene(const SessionProblem &problem, const SceneReference &reference, const SessionOptions &options, const MachineLimits &limits)
{
  check_scene_operator(options.operator_type);
  check_scene_size(problem.unknowns(), reference.count(), reference.pressure, options.scene.strategy, limits);
}

SceneSession::SceneSession(std::shared_ptr<const SessionProblem> problem, SceneReference reference, const SessionOptions &options, const MachineLimits &limits,
                           std::unique_ptr<KrylovSolver> krylov)
    : m_problem(std::move(problem)), m_ref(std::move(reference)), m_options(options), m_limits(limits), m_krylov(std::move(krylov))
{
  check_scene_operator(options.operator_type);
}

SceneSession::~SceneSession() = default;

SceneOptions SceneSession::engine_options() const
{
  SceneOptions so = m_options.scene;
  so.with_pressure = m_ref.pressure;
  so.candidates = m_ref.candidates;
  return so;
}

void SceneSession::set_up()
{
  if (m_scene) return;
  check_scene(*m_problem, m_ref, m_options, m_limits);
  const Timer timer;
  fault_point("SceneSetup");
  m_scene = std::make_unique<DenseScene>(m_problem->op(), m_ref.selection, engine_options(), std::move(m_krylov));
  m_seconds["scene_setup"] += timer.seconds();
}

void SceneSession::save(const std::string &path, const std::vector<std::string> &inputs) const { save_scene_precomputation(*this, path, inputs); }

void SceneSession::load(const std::string &path)
{
  if (m_scene) throw std::logic_error("SceneSession::load: the scene is set up already");
  check_scene(*m_problem, m_ref, m_options, m_limits);
  const Timer timer;
  DenseScene::Saved saved = load_scene_precomputation(*this, path);
  try {
    m_scene = std::make_unique<DenseScene>(m_problem->op(), std::move(saved), engine_options(), std::move(m_krylov));
  } catch (const std::invalid_argument &e) {
    throw SavedFileError("cannot load '" + path + "': " + e.what());
  }
  m_seconds["scene_load"] += timer.seconds();
}

const SceneFrameReport &SceneSession::step(const SystemSelection &frame)
{
  const ProblemSetup &s = m_problem->setup();
  m_force = s.body_force;
  return solve_homogeneous(homogeneous_selection(frame, *s.disc, m_force));
}

const SceneFrameReport &SceneSession::solve_homogeneous(const SystemSelection &homogeneous)
{
  set_up();
  const EventScope event(SCN_Frame);
  m_sel = homogeneous;
  m_report = m_scene->solve(m_sel, m_x);
  for (double v : m_x)
    if (!std::isfinite(v)) throw std::runtime_error("the solution is not finite (the frame's system is singular or overflows)");
  m_sol = split_unknowns(m_sel, m_x);
  return m_report;
}

const SceneFrameReport &SceneSession::step(std::size_t i)
{
  const ProblemSetup &s = m_problem->setup();
  const SystemSelection sel = selection_of(frame_conditions(s.spec, i, *s.disc)); // checked by setup_problem (check_every_frame)
  try {
    fault_point("Frame");
    m_force = frame_body_force(s, i);
    return solve_homogeneous(homogeneous_selection(sel, *s.disc, m_force));
  } catch (const std::exception &e) {
    throw std::runtime_error(m_problem->where() + "frames[" + std::to_string(i) + "]: " + e.what());
  }
}

FrameData SceneSession::frame_data(unsigned parts) const
{
  const ProblemSetup &s = m_problem->setup();
  FrameData f;
  put_fields(surface_fields(s, m_sol, m_force, prescribed_per_vertex(*s.disc, m_sel), parts), f);
  const SceneFrameReport &rep = m_report;
  f.attributes_real = {{"seconds", rep.seconds}, {"predicted_seconds", rep.predicted}};
  const double density = s.spec.density.value_or(0);
  if (density > 0) // the frame's body force, as gravity (density × gravity)
    for (int c = 0; c < 3; ++c) f.attributes_real[std::string("gravity_") + "xyz"[c]] = m_force.force_per_volume()[c] / density;
  f.attributes_int = {{"switched_unknowns", rep.switched}, {"changed_unknowns", rep.changed}, {"iterations", rep.iterations}, {"capacitance_rebuilt", rep.rebuilt}};
  f.attributes_str = {{"strategy", scene_strategy_name(rep.strategy)}};
  return f;
}

ResultData SceneSession::base(int ranks) const
{
  ResultData r = result_base(m_problem->setup(), ranks);
  r.attributes_str["solver"] = "scene";
  r.attributes_str["mat_type"] = "dense";
  r.attributes_str["scene_strategy"] = scene_strategy_name(m_options.scene.strategy);
  put_options(options_used(), r);
  return r;
}

OptionValues SceneSession::options_used() const { return option_values(m_options, kScene); }

Fingerprint SceneSession::fingerprint() const
{
  return hssbem::fingerprint(*m_problem, m_ref.pattern(), m_ref.candidates, options_used(), 1);
}

} // namespace hssbem
