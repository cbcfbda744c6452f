// The simulator API of scene.hpp: a face of the scene session.
#include "hssbem/session/scene.hpp"

#include "hssbem/petsc/system.h"
#include "hssbem/post/post.hpp"
#include "hssbem/session/petsc_call.hpp"

#include <stdexcept>

namespace hssbem {

namespace {

SystemSelection node_selection(const Discretization &disc, const Scene::Pattern &pattern, const std::vector<Vec3> &values)
{
  SystemSelection sel;
  sel.displacement_known.resize(disc.num_nodes());
  sel.known.assign(disc.num_nodes(), Vec3{0, 0, 0});
  for (int n = 0; n < disc.num_nodes(); ++n) {
    const int v = disc.node(n).vertex;
    sel.displacement_known[n] = pattern[v];
    if (!values.empty()) sel.known[n] = values[v];
  }
  return sel;
}

} // namespace

Scene::Scene(const SurfaceMesh &mesh, const Material &material, const Pattern &reference, const SceneOptions &options, std::unique_ptr<KrylovSolver> krylov,
             double feature_angle_deg, const std::vector<char> &candidate_vertices, const std::string &load)
{
  if (reference.size() != mesh.vertices.size()) throw std::invalid_argument("Scene: the reference pattern needs one entry per vertex");
  if (options.with_pressure) throw std::invalid_argument("Scene: pressure loads are not part of the Scene API (give tractions)");
  if (!options.candidates.empty()) throw std::invalid_argument("Scene: give the candidates per vertex (candidate_vertices), not per unknown");
  if (!candidate_vertices.empty() && candidate_vertices.size() != mesh.vertices.size()) throw std::invalid_argument("Scene: candidate_vertices needs one entry per vertex");
  m_problem = std::make_shared<SessionProblem>(std::make_shared<ProblemSetup>(setup_in_memory(mesh, material, feature_angle_deg)), QuadratureOptions{});
  const Discretization &disc = m_problem->disc();
  SceneReference ref{node_selection(disc, reference, {}), "the reference pattern", {}, false};
  if (!candidate_vertices.empty()) {
    ref.candidates.resize(3 * static_cast<std::size_t>(disc.num_nodes()));
    for (int n = 0; n < disc.num_nodes(); ++n)
      for (int a = 0; a < 3; ++a) ref.candidates[3 * n + a] = candidate_vertices[disc.node(n).vertex] ? 1 : 0;
  }
  SessionOptions so;
  so.scene = options;
  MachineLimits limits;
  HssbemCallThrow(HssbemMachineLimits(PETSC_COMM_SELF, &limits));
  m_session = std::make_unique<SceneSession>(m_problem, std::move(ref), so, limits, std::move(krylov));
  if (!load.empty()) m_session->load(load);
  m_session->set_up(); // nothing left to do after a load
  m_pattern = reference;
  m_values.assign(mesh.vertices.size(), Vec3{0, 0, 0});
  m_area = node_areas(disc);
}

Scene::~Scene() = default;

void Scene::set_pattern(const Pattern &displacement_prescribed)
{
  if (displacement_prescribed.size() != m_problem->mesh().vertices.size()) throw std::invalid_argument("Scene::set_pattern: one entry per vertex expected");
  m_pattern = displacement_prescribed;
}

void Scene::set_values(const std::vector<Vec3> &values)
{
  if (values.size() != m_problem->mesh().vertices.size()) throw std::invalid_argument("Scene::set_values: one value per vertex expected");
  m_values = values;
}

SystemSelection Scene::selection() const { return node_selection(m_problem->disc(), m_pattern, m_values); }

const SceneFrameReport &Scene::solve()
{
  const SceneFrameReport &rep = m_session->step(selection());
  SurfaceFields f = surface_fields(m_problem->setup(), m_session->solution(), m_session->body_force(), {}, kMotion);
  m_u = std::move(f.displacement);
  m_t = std::move(f.traction);
  return rep;
}

std::vector<Scene::VertexForce> Scene::contact_forces()
{
  const SystemSelection sel = selection();
  std::vector<double> s;
  DenseScene &scene = m_session->engine();
  scene.solve_switched(sel, s);
  const std::vector<int> &J = scene.switched();
  std::vector<int> slot(m_problem->mesh().vertices.size(), -1);
  std::vector<VertexForce> out;
  for (std::size_t p = 0; p < J.size(); ++p) {
    const int node = J[p] / 3, comp = J[p] % 3;
    if (!sel.displacement_known[node][comp]) continue; // a released component: its unknown is a displacement
    const int v = m_problem->disc().node(node).vertex;
    if (slot[v] < 0) slot[v] = static_cast<int>(out.size()), out.push_back({v, Vec3{0, 0, 0}});
    out[slot[v]].force[comp] += s[p] * m_area[node];
  }
  return out;
}

} // namespace hssbem
