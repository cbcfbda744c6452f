#include "hssbem/problem/setup.hpp"
#include "hssbem/bem/discretization.hpp"
#include "hssbem/bem/rigid_modes.hpp"
#include "hssbem/core/fault.hpp"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

namespace hssbem {

namespace {

Material material_of(const ProblemSpec &spec, const ProblemOverrides &o)
{
  double E = 0, nu = 0;
  if (spec.lambda && spec.mu) {
    const Material m = Material::from_lame(*spec.lambda, *spec.mu);
    E = m.E, nu = m.nu;
  }
  if (spec.E) E = *spec.E;
  if (spec.nu) nu = *spec.nu;
  if (o.E) E = *o.E;
  if (o.nu) nu = *o.nu;
  try {
    return Material::from_young(E, nu);
  } catch (const std::invalid_argument &e) {
    const std::string from = std::string(" (E from ") + (o.E ? "-E" : spec.file) + ", nu from " + (o.nu ? "-nu" : spec.file) + ")";
    throw std::invalid_argument(e.what() + from);
  }
}

std::string format(const char *fmt, double a, double b)
{
  char buf[256];
  std::snprintf(buf, sizeof(buf), fmt, a, b);
  return buf;
}

/// Pure traction: refuse an unbalanced load; the solver regularises along the rigid modes.
void accept_pure_traction(ProblemSetup &s)
{
  const auto imbalance = load_imbalance(*s.disc, s.selection.known);
  if (imbalance[0] > max_load_imbalance || imbalance[1] > max_load_imbalance)
    throw ConstraintError(s.spec.file + ": no displacement is prescribed anywhere and the load" + (s.body_force.zero() ? "" : " (with the body force)") + " is not balanced " +
                          format("(resultant force %.2g, moment %.2g of the total load); prescribe displacements to hold the body", imbalance[0], imbalance[1]));
  s.pure_traction = true;
  s.notices.push_back("no displacement is prescribed: pure traction problem; rigid motions are regularised and removed from the result");
}

void handle_rigid_modes(ProblemSetup &s)
{
  const ConstraintReport rep = analyse_constraints(*s.disc, s.selection.displacement_known);
  if (rep.rank == 6) return;
  if (rep.rank == 0) return accept_pure_traction(s);
  std::string free;
  for (const auto &m : rep.free_modes) free += (free.empty() ? "" : "; ") + m;
  throw ConstraintError(s.spec.file + ": the prescribed displacements leave the body free to move (" + free +
                        "); prescribe displacements that fix all six rigid motions, or none at all for a balanced pure-traction problem");
}

/// The centroid of the vertices the triangles use: the particular solution's origin.
Vec3 vertex_centroid(const SurfaceMesh &mesh)
{
  std::vector<char> used(mesh.vertices.size(), 0);
  for (const auto &t : mesh.triangles)
    for (int v : t) used[v] = 1;
  Vec3 sum{0, 0, 0};
  double count = 0;
  for (std::size_t v = 0; v < used.size(); ++v)
    if (used[v]) sum = sum + mesh.vertices[v], count += 1;
  return count > 0 ? (1.0 / count) * sum : sum;
}

UniformBodyForce body_force_of(const ProblemSetup &s, const std::optional<Vec3> &gravity)
{
  if (!gravity || !s.spec.density) return UniformBodyForce(s.material, {0, 0, 0}, vertex_centroid(*s.mesh));
  return UniformBodyForce(s.material, *s.spec.density * *gravity, vertex_centroid(*s.mesh));
}

} // namespace

UniformBodyForce frame_body_force(const ProblemSetup &s, std::size_t frame)
{
  const FrameSpec &f = s.spec.frames.at(frame);
  if (!f.gravity) return s.body_force;
  return body_force_of(s, f.gravity);
}

void check_every_frame(const ProblemSetup &s)
{
  for (std::size_t i = 0; i < s.spec.frames.size(); ++i) {
    const NodeConditions nc = frame_conditions(s.spec, i, *s.disc);
    if (!s.spec.contact.present) // contact may hold a body that a frame's rules leave free
      check_frame_constraints(s, nc.displacement_prescribed, "frames[" + std::to_string(i) + "]");
  }
}

SystemSelection selection_of(const NodeConditions &nc)
{
  return SystemSelection{nc.displacement_prescribed, nc.value, nc.pressure};
}

std::vector<std::array<bool, 3>> vertex_displacement_prescribed(const Discretization &disc, const NodeConditions &nc)
{
  const int                        nv = disc.mesh().num_vertices();
  std::vector<std::array<bool, 3>> out(nv, {false, false, false});
  for (int v = 0; v < nv; ++v)
    if (disc.node_count(v) > 0) out[v] = nc.displacement_prescribed[disc.first_node(v)];
  return out;
}

ProblemSetup setup_problem(ProblemSpec spec, const ProblemOverrides &o)
{
  ProblemSetup s;
  s.spec = std::move(spec);
  if (o.mesh) s.spec.mesh_path = *o.mesh;
  s.output = o.output ? *o.output : s.spec.output;
  s.input_files = {s.spec.file};
  if (!o.mesh_data) s.input_files.push_back(s.spec.mesh_path);
  s.material = material_of(s.spec, o);
  fault_point("MeshRead"); // tests: a mesh seen by some ranks only (kind unreadable: fault_path)
  s.mesh = std::make_unique<SurfaceMesh>(o.mesh_data ? *o.mesh_data : read_mesh(fault_path("MeshRead", s.spec.mesh_path)));
  validate_and_orient(*s.mesh, s.notices);
  s.disc = std::make_unique<Discretization>(*s.mesh, o.feature_angle_deg);
  s.body_force = body_force_of(s, s.spec.gravity);
  const NodeConditions nc = apply_rules(s.spec.rules, *s.disc, s.spec.file);
  s.selection = homogeneous_selection(selection_of(nc), *s.disc, s.body_force);
  s.vertex_displacement_prescribed = vertex_displacement_prescribed(*s.disc, nc);
  for (std::size_t i = 0; i < s.spec.contact.obstacles.size(); ++i) { // an unreadable obstacle mesh ends the run before any work
    Obstacle &o = s.spec.contact.obstacles[i];
    if (o.shape != Obstacle::Shape::Mesh) continue;
    try {
      SurfaceMesh m = read_mesh(o.mesh_path);
      o.vertices = std::move(m.vertices), o.triangles = std::move(m.triangles);
      s.input_files.push_back(o.mesh_path); // the result may not replace it either
    } catch (const MeshError &e) {
      throw MeshError(s.spec.file + ": contact.obstacles[" + std::to_string(i) + "].mesh: " + e.what());
    }
  }
  fault_point("Setup");
  if (!s.spec.frames.empty()) check_every_frame(s);                  // a scene: every frame's rules before the first frame
  else if (!s.spec.contact.present) handle_rigid_modes(s);           // contact checks each body
  return s;
}

bool check_frame_constraints(const ProblemSetup &s, const std::vector<std::array<bool, 3>> &displacement_known, const std::string &what)
{
  const ConstraintReport rep = analyse_constraints(*s.disc, displacement_known);
  if (rep.rank == 6) return true;
  std::string free;
  for (const auto &m : rep.free_modes) free += (free.empty() ? "" : "; ") + m;
  throw ConstraintError(s.spec.file + ": " + what + ": the prescribed displacements leave the body free to move (" + (free.empty() ? "all rigid motions" : free) +
                        "); every frame of a scene must fix all six rigid motions (pure-traction frames are not supported in scenes)");
}

ProblemSetup setup_in_memory(const SurfaceMesh &mesh, const Material &material, double feature_angle_deg)
{
  ProblemSetup s;
  s.material = material;
  s.mesh = std::make_unique<SurfaceMesh>(mesh);
  s.disc = std::make_unique<Discretization>(*s.mesh, feature_angle_deg);
  const NodeConditions nc = apply_rules({}, *s.disc, "");
  s.selection = selection_of(nc);
  s.vertex_displacement_prescribed = vertex_displacement_prescribed(*s.disc, nc);
  return s;
}

ProblemSetup setup_problem(const std::string &problem_file, const ProblemOverrides &o)
{
  return setup_problem(read_problem(problem_file), o);
}

} // namespace hssbem
