// The simulator API of contact_scene.hpp over the contact engine and the dense reference.
#include "hssbem/contact/contact_scene.hpp"

#include "hssbem/bem/post.hpp"

#include <stdexcept>

namespace hssbem {

ContactScene::ContactScene(const SurfaceMesh &mesh, const Material &material, const Pattern &held, std::vector<Obstacle> obstacles, const ContactSettings &settings,
                           const ContactOptions &options, double feature_angle_deg)
    : m_mesh(mesh)
{
  if (held.size() != mesh.vertices.size()) throw std::invalid_argument("ContactScene: the held pattern needs one entry per vertex");
  m_disc = std::make_unique<Discretization>(m_mesh, feature_angle_deg);
  m_op = std::make_unique<BemOperator>(*m_disc, material);
  const int nn = m_disc->num_nodes();
  m_sel.displacement_known.resize(nn);
  m_sel.known.assign(nn, Vec3{0, 0, 0});
  std::vector<char> pattern(3 * nn);
  for (int i = 0; i < nn; ++i) {
    m_sel.displacement_known[i] = held[m_disc->node(i).vertex];
    for (int c = 0; c < 3; ++c) pattern[3 * i + c] = m_sel.displacement_known[i][c];
  }
  check_bodies_held(*m_disc, m_sel.displacement_known, obstacles, settings, options);
  DenseReferenceOptions ro;
  ro.node_body = node_bodies(*m_disc);
  m_reference = std::make_unique<DenseReference>(*m_op, pattern, ro);
  m_poses.assign(obstacles.size(), Pose{});
  m_engine = std::make_unique<ContactEngine>(*m_disc, *m_reference, std::move(obstacles), settings, options);
}

ContactScene::~ContactScene() = default;

void ContactScene::set_values(const std::vector<Vec3> &values)
{
  if (values.size() != m_mesh.vertices.size()) throw std::invalid_argument("ContactScene::set_values: one value per vertex expected");
  for (int i = 0; i < m_disc->num_nodes(); ++i) m_sel.known[i] = values[m_disc->node(i).vertex];
}

int ContactScene::obstacle_index(const std::string &name) const
{
  for (int o = 0; o < m_engine->num_obstacles(); ++o)
    if (m_engine->obstacle_name(o) == name) return o;
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
  const ContactFrameReport &rep = m_engine->solve(m_sel, m_poses, m_sol);
  m_u = vertex_average(*m_disc, m_sol.u);
  m_t = vertex_average(*m_disc, m_sol.t);
  return rep;
}

std::vector<int> ContactScene::active_vertices() const
{
  std::vector<int> out;
  for (std::size_t v = 0; v < m_sol.status.size(); ++v)
    if (m_sol.status[v]) out.push_back(static_cast<int>(v));
  return out;
}

} // namespace hssbem
