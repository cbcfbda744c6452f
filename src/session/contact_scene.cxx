// The simulator API of contact_scene.hpp: a face of the contact session.
#include "hssbem/session/contact_scene.hpp"

#include "hssbem/petsc/system.h"
#include "hssbem/post/post.hpp"
#include "hssbem/session/petsc_call.hpp"

#include <stdexcept>

namespace hssbem {

ContactScene::ContactScene(const SurfaceMesh &mesh, const Material &material, const Pattern &held, std::vector<Obstacle> obstacles, const ContactSettings &settings,
                           const ContactOptions &options, double feature_angle_deg, const ContactSceneReference &reference)
{
  if (held.size() != mesh.vertices.size()) throw std::invalid_argument("ContactScene: the held pattern needs one entry per vertex");
  m_problem = std::make_shared<SessionProblem>(std::make_shared<ProblemSetup>(setup_in_memory(mesh, material, feature_angle_deg)), QuadratureOptions{});
  const Discretization &disc = m_problem->disc();
  const int nn = disc.num_nodes();
  ContactJob job;
  job.base.displacement_prescribed.resize(nn);
  job.base.value.assign(nn, Vec3{0, 0, 0});
  for (int i = 0; i < nn; ++i) job.base.displacement_prescribed[i] = held[disc.node(i).vertex];
  m_sel = selection_of(job.base);
  job.obstacles = std::move(obstacles);
  job.settings = settings;
  m_poses.assign(job.obstacles.size(), Pose{});
  SessionOptions so;
  so.contact = options;
  so.operator_type = reference.type;
  so.h2 = reference.h2;
  so.contact_h2_rtol = reference.h2_rtol;
  so.contact_h2_factor_tol = reference.h2_factor_tol;
  MachineLimits limits;
  HssbemCallThrow(HssbemMachineLimits(PETSC_COMM_SELF, &limits));
  m_session = std::make_unique<ContactSession>(m_problem, std::move(job), so, limits);
  m_session->set_up();
}

ContactScene::~ContactScene() = default;

void ContactScene::set_values(const std::vector<Vec3> &values)
{
  if (values.size() != m_problem->mesh().vertices.size()) throw std::invalid_argument("ContactScene::set_values: one value per vertex expected");
  for (int i = 0; i < m_problem->disc().num_nodes(); ++i) m_sel.known[i] = values[m_problem->disc().node(i).vertex];
}

int ContactScene::obstacle_index(const std::string &name) const
{
  for (int o = 0; o < engine().num_obstacles(); ++o)
    if (engine().obstacle_name(o) == name) return o;
  throw std::invalid_argument("ContactScene: no obstacle named '" + name + "'");
}

void ContactScene::set_obstacle_offset(const std::string &name, const Vec3 &offset) { m_poses[obstacle_index(name)] = Pose::translation(offset); }

void ContactScene::set_obstacle_pose(const std::string &name, const Pose &pose) { m_poses[obstacle_index(name)] = pose; }

void ContactScene::set_obstacle_offsets(const std::vector<Vec3> &offsets)
{
  if (offsets.size() != m_poses.size()) throw std::invalid_argument("ContactScene::set_obstacle_offsets: one offset per obstacle expected");
  for (std::size_t o = 0; o < offsets.size(); ++o) m_poses[o] = Pose::translation(offsets[o]);
}

void ContactScene::set_obstacle_poses(const std::vector<Pose> &poses)
{
  if (poses.size() != m_poses.size()) throw std::invalid_argument("ContactScene::set_obstacle_poses: one pose per obstacle expected");
  m_poses = poses;
}

const ContactFrameReport &ContactScene::solve()
{
  const ContactFrameReport &rep = m_session->step(m_sel, m_poses);
  SurfaceFields f = surface_fields(m_problem->setup(), NodalSolution{m_sol().u, m_sol().t}, {}, kMotion);
  m_u = std::move(f.displacement);
  m_t = std::move(f.traction);
  return rep;
}

std::vector<int> ContactScene::active_vertices() const
{
  std::vector<int> out;
  for (std::size_t v = 0; v < m_sol().status.size(); ++v)
    if (m_sol().status[v]) out.push_back(static_cast<int>(v));
  return out;
}

} // namespace hssbem
