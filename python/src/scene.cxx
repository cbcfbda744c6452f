// hssbem.Scene: a scene of frames or a contact, set up once and driven frame by frame from
// Python, on rank 0 as in the driver (SceneSession, ContactSession). See bind.hpp.
#include "bind.hpp"

#include "hssbem/app/options.hpp"
#include "hssbem/petsc/krylov.h"
#include "hssbem/petsc/system.h"
#include "hssbem/session/choice.hpp"
#include "hssbem/session/contact_session.hpp"
#include "hssbem/session/petsc_call.hpp"
#include "hssbem/session/precomputation_file.hpp"
#include "hssbem/session/scene_session.hpp"

#include <pybind11/stl.h>

namespace hssbem::py_module {

namespace {

/// `from` into `into`'s storage when the sizes agree, so that numpy views of it stay valid and
/// follow the frames.
template <class T>
void refill(std::vector<T> &into, std::vector<T> &&from)
{
  if (into.size() == from.size()) std::copy(from.begin(), from.end(), into.begin());
  else into = std::move(from);
}

void refill(FrameData &into, FrameData &&from)
{
  refill(into.displacement, std::move(from.displacement));
  refill(into.traction, std::move(from.traction));
  refill(into.displacement_prescribed, std::move(from.displacement_prescribed));
  refill(into.stress.stress, std::move(from.stress.stress));
  refill(into.stress.von_mises, std::move(from.stress.von_mises));
  refill(into.stress.principal, std::move(from.stress.principal));
  refill(into.contact.pressure, std::move(from.contact.pressure));
  refill(into.contact.gap, std::move(from.contact.gap));
  refill(into.contact.status, std::move(from.contact.status));
  into.contact.forces = std::move(from.contact.forces);
  into.contact.iterations = from.contact.iterations, into.contact.active_vertices = from.contact.active_vertices;
  into.attributes_real = std::move(from.attributes_real), into.attributes_int = std::move(from.attributes_int), into.attributes_str = std::move(from.attributes_str);
}

class Scene {
public:
  Scene(const ProblemInput &in, OptionList options, std::optional<long long> comm, bool stress)
      : m_comm(comm_of(comm)), m_options(std::move(options)), m_parts(stress ? kFrameFields : kMotion | kPrescribed)
  {
    const CallEnvironment env(m_options, m_comm);
    guarded([&] { set_up(in); });
  }

  /// Frame `frame`: an index into the problem's "frames", or the JSON of one frame.
  py::dict step(const std::variant<long long, std::string> &frame)
  {
    const CallEnvironment env(m_options, m_comm);
    guarded([&] {
      run_collectively(m_comm, [&] {
        if (m_rank == 0) solve(frame);
      });
    });
    py::dict report;
    for (const auto &[k, v] : m_frame.attributes_real) report[py::str(k)] = v;
    for (const auto &[k, v] : m_frame.attributes_int) report[py::str(k)] = v;
    for (const auto &[k, v] : m_frame.attributes_str) report[py::str(k)] = v;
    if (m_contact) report["active_vertices"] = m_frame.contact.active_vertices, report["iterations"] = m_frame.contact.iterations;
    return report;
  }

  py::dict fields(py::object self) const
  {
    py::dict d;
    if (m_frame.displacement.empty()) return d;
    d["displacement"] = view_vec3(m_frame.displacement, self);
    d["traction"] = view_vec3(m_frame.traction, self);
    if (!m_frame.stress.stress.empty()) d["stress"] = view_voigt(m_frame.stress.stress, self);
    if (!m_frame.stress.von_mises.empty()) d["von_mises"] = view_doubles(m_frame.stress.von_mises, self);
    if (!m_frame.stress.principal.empty()) d["principal_stress"] = view_vec3(m_frame.stress.principal, self);
    if (!m_frame.displacement_prescribed.empty()) d["displacement_prescribed"] = view_mask(m_frame.displacement_prescribed, self);
    return d;
  }

  py::dict contact(py::object self) const { return contact_of(m_frame.contact, self); }

  /// The surface the fields live on (after the set-up's checks and orientation), on every rank.
  py::dict mesh(py::object self) const
  {
    py::dict d;
    d["vertices"] = view_vec3(m_setup->mesh->vertices, self);
    d["triangles"] = view_triangles(m_setup->mesh->triangles, self);
    return d;
  }

  /// The haptic call: per obstacle, its force for new poses, `obstacles` the JSON of a frame's
  /// "obstacles" ({"name": {"translate": [..], "rotate": {..}}}); obstacles not named keep the
  /// last frame's poses.
  py::dict haptic_forces(const std::string &obstacles)
  {
    if (!m_contact && m_rank == 0) throw Failure("haptic_forces: the problem has no \"contact\"");
    const CallEnvironment env(m_options, m_comm);
    std::vector<Vec3> forces;
    guarded([&] {
      if (m_rank != 0) return;
      const ProblemSpec spec = parse_frame(m_setup->spec, "{\"obstacles\": " + obstacles + "}", "haptic_forces");
      const std::vector<Pose> placed = contact_placements(spec, m_obstacles)[0];
      std::vector<Pose> poses = m_poses;
      for (const auto &entry : spec.frames[0].obstacles) poses[obstacle(entry.first)] = placed[obstacle(entry.first)];
      forces = m_contact->haptic_forces(poses);
    });
    py::dict d;
    for (std::size_t i = 0; i < forces.size(); ++i) d[py::str(m_names[i])] = copy_vec3(forces[i]);
    return d;
  }

  const std::vector<std::string> &obstacle_names() const { return m_names; }
  std::size_t num_frames() const { return m_setup ? m_setup->spec.frames.size() : 0; }
  std::string kind() const { return m_contact || (m_problem && m_problem->job() == JobKind::Contact) ? "contact" : "scene"; }

private:
  void set_up(const ProblemInput &in)
  {
    HssbemCallMPIThrow(MPI_Comm_rank(m_comm, &m_rank));
    PetscMPIInt size;
    HssbemCallMPIThrow(MPI_Comm_size(m_comm, &size));
    const DriverOptions o = read_driver_options(m_comm);
    m_setup = py_module::set_up(m_comm, in, o.overrides);
    run_collectively(m_comm, [&] { m_problem = std::make_shared<SessionProblem>(m_setup, o.session.quad); });
    MachineLimits limits;
    HssbemCallThrow(HssbemMachineLimits(m_comm, &limits));
    check_unused_options(m_comm, false);
    for (const Obstacle &ob : m_setup->spec.contact.obstacles) m_names.push_back(ob.name);
    if (m_problem->job() == JobKind::Contact) return set_up_contact(o, limits);
    SceneReference ref = m_setup->spec.frames.empty() ? SceneReference{m_setup->selection, "the base rules", {}, true} : scene_reference(*m_setup);
    check_scene(*m_problem, ref, o.session, limits); // every rank: the same error everywhere
    run_collectively(m_comm, [&] {
      if (m_rank != 0) return;
      m_scene = std::make_unique<SceneSession>(m_problem, std::move(ref), o.session, limits, HssbemSceneKrylovCreate());
      if (!o.load.empty()) m_scene->load(o.load); // a precomputation saved for this scene (docs/persistence.md)
      else m_scene->set_up();
      if (!o.save.empty()) m_scene->save(o.save, m_setup->input_files);
    });
  }

  /// The contact session takes its frames per step (any unknown may carry a value); the
  /// problem's own frames are kept to be stepped by their index. hssbem_load and hssbem_save as
  /// in the command line (dense references only).
  void set_up_contact(const DriverOptions &o, const MachineLimits &limits)
  {
    const std::string mat_type = reference_mat_type(contact_references_on_h2(m_problem->disc(), o.session.operator_type, limits)); // every rank: the same error everywhere
    if (!o.save.empty() || !o.load.empty()) check_contact_reference_saveable(mat_type, o.save.empty() ? "hssbem_load" : "hssbem_save");
    run_collectively(m_comm, [&] {
      if (m_rank != 0) return;
      ContactJob job = contact_job(*m_setup);
      m_base_pattern = job.base.displacement_prescribed;
      m_base_values = selection_of(frame_conditions(parse_frame(m_setup->spec, "{\"boundary\": []}", "frame"), 0, *m_setup->disc));
      m_file_frames = std::move(job.frames), m_file_placements = std::move(job.placements);
      job.frames.clear(), job.placements.clear();
      m_obstacles = job.obstacles;
      m_poses.assign(m_names.size(), Pose());
      m_contact = std::make_unique<ContactSession>(m_problem, std::move(job), o.session, limits);
      if (!o.load.empty()) m_contact->load(o.load); // a precomputation saved for this scene (docs/persistence.md)
      m_contact->set_up();
      if (!o.save.empty()) m_contact->save(o.save, m_setup->input_files);
    });
  }

  std::size_t obstacle(const std::string &name) const
  {
    for (std::size_t i = 0; i < m_names.size(); ++i)
      if (m_names[i] == name) return i;
    throw std::invalid_argument("no obstacle named '" + name + "'");
  }

  /// A frame on rank 0.
  void solve(const std::variant<long long, std::string> &frame)
  {
    const ProblemSetup &s = *m_setup;
    if (const long long *i = std::get_if<long long>(&frame)) {
      if (*i < 0 || static_cast<std::size_t>(*i) >= s.spec.frames.size())
        throw std::invalid_argument("frame " + std::to_string(*i) + ": the problem has " + std::to_string(s.spec.frames.size()) + " frames");
      if (m_scene) m_scene->step(static_cast<std::size_t>(*i));
      else step_contact(selection_of(m_file_frames[*i]), m_file_placements[*i]);
    } else {
      const ProblemSpec spec = parse_frame(s.spec, std::get<std::string>(frame), "frame");
      if (m_scene) {
        const NodeConditions nc = frame_conditions(spec, 0, *s.disc);
        check_frame_constraints(s, nc.displacement_prescribed, "frame");
        m_scene->step(selection_of(nc));
      } else step_contact_frame(spec);
    }
    refill(m_frame, m_scene ? m_scene->frame_data(m_parts) : m_contact->frame_data(m_parts));
  }

  /// A contact's frame given as a dict. One that moves obstacles only (no "boundary", no
  /// "gravity") has the base rules' values, taken from the set-up instead of applied over the
  /// mesh again: a simulator's frames cost the step, not a pass over the mesh.
  void step_contact_frame(const ProblemSpec &spec)
  {
    const FrameSpec &f = spec.frames[0];
    if (f.rules.empty() && !f.gravity) return step_contact(m_base_values, contact_placements(spec, m_obstacles)[0]);
    const NodeConditions nc = frame_conditions(spec, 0, *m_setup->disc);
    if (nc.displacement_prescribed != m_base_pattern)
      throw ProblemError(m_problem->where() + "frame.boundary: a contact's frames may change the values of the base rules, not which components they prescribe (the reference factorization's pattern)");
    step_contact(selection_of(nc), contact_placements(spec, m_obstacles)[0]);
  }

  void step_contact(const SystemSelection &values, const std::vector<Pose> &poses)
  {
    m_contact->step(values, poses);
    m_poses = poses;
  }

  MPI_Comm m_comm;
  OptionList m_options;
  unsigned m_parts;
  int m_rank = 0;
  std::shared_ptr<const ProblemSetup> m_setup;
  std::shared_ptr<const SessionProblem> m_problem;
  std::unique_ptr<SceneSession> m_scene;     ///< a scene, on rank 0
  std::unique_ptr<ContactSession> m_contact; ///< a contact, on rank 0
  std::vector<std::string> m_names;          ///< the obstacles
  std::vector<std::array<bool, 3>> m_base_pattern;
  SystemSelection m_base_values;             ///< a contact's frame without rules of its own: the base rules' values
  std::vector<NodeConditions> m_file_frames;
  std::vector<std::vector<Pose>> m_file_placements;
  std::vector<Obstacle> m_obstacles;         ///< the contact's obstacles (their default centres for a frame's turns)
  std::vector<Pose> m_poses;                 ///< the last frame's obstacle poses
  FrameData m_frame;                         ///< the last frame's fields: numpy views look into it
};

} // namespace

void bind_scene(py::module_ &m)
{
  py::class_<Scene>(m, "Scene", "hssbem.Scene's compiled part (internal).")
      .def(py::init<const ProblemInput &, OptionList, std::optional<long long>, bool>(), py::arg("problem"), py::arg("options"), py::arg("comm"), py::arg("stress"))
      .def("step", &Scene::step, py::arg("frame"))
      .def("fields", [](py::object self) { return self.cast<const Scene &>().fields(self); })
      .def("contact", [](py::object self) { return self.cast<const Scene &>().contact(self); })
      .def("mesh", [](py::object self) { return self.cast<const Scene &>().mesh(self); })
      .def("haptic_forces", &Scene::haptic_forces, py::arg("obstacles"))
      .def_property_readonly("obstacles", &Scene::obstacle_names)
      .def_property_readonly("num_frames", &Scene::num_frames)
      .def_property_readonly("kind", &Scene::kind);
}

} // namespace hssbem::py_module
