// One engine behind every face (session/): the same problem through the driver (run_driver, as
// the command line runs it, its result file read back) and through the library (StaticSession,
// ContactScene, Scene) gives the same numbers. On the dense path and the H² path the two faces
// run the same code on the same inputs, so the static fields are bit-identical and the H² solve
// takes the same iterations; a contact or a scene through the library computes W's columns as
// its frames ask for them where the driver computes the frames' columns in one block ahead, so
// they agree to round-off (bounds below, measured values printed).
#include "solve_helpers.hpp"

#include "hssbem/app/run.hpp"
#include "hssbem/reference/composite_reference.hpp"
#include "hssbem/session/contact_scene.hpp"
#include "hssbem/session/scene.hpp"
#include "hssbem/session/static_session.hpp"
#include "test_paths.hpp"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

using namespace hssbem;
using namespace hssbem::test;

namespace {

/// A fresh directory for a test's files.
std::string temp_dir()
{
  char tmpl[] = "/tmp/hssbem-session-XXXXXX";
  const char *d = mkdtemp(tmpl);
  if (!d) throw std::runtime_error("mkdtemp failed");
  return d;
}

void write_text(const std::string &path, const std::string &text)
{
  std::ofstream f(path);
  f << text;
}

void write_off(const std::string &path, const SurfaceMesh &m)
{
  std::ofstream f(path);
  f.precision(17);
  f << "OFF\n" << m.num_vertices() << " " << m.num_triangles() << " 0\n";
  for (const Vec3 &v : m.vertices) f << v[0] << " " << v[1] << " " << v[2] << "\n";
  for (const auto &t : m.triangles) f << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
}

/// The driver in this process on the command line `args` ("-key value" pairs; a key alone is a
/// flag), as the hssbem executable runs it; the options are removed again afterwards.
void run_driver_with(const std::vector<std::pair<std::string, std::string>> &args)
{
  for (const auto &[k, v] : args) PetscCallAbort(PETSC_COMM_WORLD, PetscOptionsSetValue(NULL, k.c_str(), v.empty() ? NULL : v.c_str()));
  run_driver(PETSC_COMM_WORLD);
  for (const auto &[k, v] : args) PetscCallAbort(PETSC_COMM_WORLD, PetscOptionsClearValue(NULL, k.c_str()));
}

/// A dataset of a result file, flattened (doubles).
std::vector<double> read_dataset(const std::string &path, const std::string &name)
{
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (f < 0) throw std::runtime_error("cannot open " + path);
  const hid_t d = H5Dopen2(f, name.c_str(), H5P_DEFAULT);
  const hid_t s = H5Dget_space(d);
  std::vector<double> out(static_cast<std::size_t>(H5Sget_simple_extent_npoints(s)));
  H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data());
  H5Sclose(s);
  H5Dclose(d);
  H5Fclose(f);
  return out;
}

/// An integer attribute of `object` (a group, "/" the root) of a result file.
long long read_int_attribute(const std::string &path, const std::string &object, const std::string &name)
{
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t a = H5Aopen_by_name(f, object.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT);
  long long v = -1;
  H5Aread(a, H5T_NATIVE_LLONG, &v);
  H5Aclose(a);
  H5Fclose(f);
  return v;
}

std::vector<double> flat(const std::vector<Vec3> &v)
{
  std::vector<double> out;
  for (const Vec3 &x : v) out.insert(out.end(), x.begin(), x.end());
  return out;
}

std::vector<double> flat(const std::vector<Voigt> &v)
{
  std::vector<double> out;
  for (const Voigt &x : v) out.insert(out.end(), x.begin(), x.end());
  return out;
}

/// max |a − b| / max |b|, with b not all zero (a comparison that cannot pass on empty fields).
double rel_diff(const std::vector<double> &a, const std::vector<double> &b)
{
  EXPECT_EQ(a.size(), b.size());
  double d = 0, m = 0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) d = std::max(d, std::abs(a[i] - b[i])), m = std::max(m, std::abs(b[i]));
  EXPECT_GT(m, 0);
  return d / m;
}

/// The static session of a problem file through the library, with the options `given`.
std::unique_ptr<StaticSession> library_static(const std::string &file, const OptionValues &given)
{
  auto setup = std::make_shared<ProblemSetup>(setup_problem(file, ProblemOverrides{}));
  const SessionOptions o = session_options(given);
  auto problem = std::make_shared<SessionProblem>(setup, o.quad);
  auto s = std::make_unique<StaticSession>(PETSC_COMM_WORLD, problem, o);
  s->solve();
  return s;
}

OptionValue value(const char *name, const std::string &text) { return OptionValue::of(*find_option(name), text); }
OptionValue value(const char *name, double v) { return OptionValue::of(*find_option(name), v); }

/// The unit sphere of sphere_l0.msh pushed down by `delta` at its north cap onto a table at its
/// south pole (frictionless), and a second copy `gap` above it when `two` (the top one pushed, the
/// bottom one's south cap clamped, contact between the bodies): per vertex, the pattern and values.
struct SphereContact {
  SurfaceMesh mesh;
  ContactScene::Pattern held;
  std::vector<Vec3> values;
  bool two = false;

  SphereContact(bool two_bodies, double delta, double gap) : two(two_bodies)
  {
    const SurfaceMesh one = read_mesh(mesh_file("sphere_l0.msh"));
    mesh = one;
    if (two) {
      for (const Vec3 &v : one.vertices) mesh.vertices.push_back(v + Vec3{0, 0, 2 + gap});
      for (const auto &t : one.triangles) mesh.triangles.push_back({t[0] + one.num_vertices(), t[1] + one.num_vertices(), t[2] + one.num_vertices()});
      mesh.triangle_region.insert(mesh.triangle_region.end(), one.triangle_region.begin(), one.triangle_region.end());
    }
    std::vector<std::string> notices;
    validate_and_orient(mesh, notices);
    held.assign(mesh.vertices.size(), {false, false, false});
    values.assign(mesh.vertices.size(), Vec3{0, 0, 0});
    const double top = two ? 3 + gap : 1;
    for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
      const double z = mesh.vertices[v][2];
      if (z > top - 0.2) held[v] = {true, true, true}, values[v] = {0, 0, -delta};
      if (two && z < -0.8) held[v] = {true, true, true};
    }
  }

  /// The same as a problem file on `mesh_path` (the boxes select the vertices above).
  std::string problem_json(const std::string &mesh_path, double delta, double gap) const
  {
    const double top = two ? 3 + gap : 1;
    char text[1024];
    std::snprintf(text, sizeof text,
                  R"({"mesh": "%s", "material": {"E": 1000.0, "nu": 0.3},
 "boundary": [{"where": {"box": [[-2, -2, %.17g], [2, 2, 10]]}, "displacement": [0, 0, %.17g]}%s],
 "contact": {"obstacles": [%s]%s}})",
                  mesh_path.c_str(), top - 0.2, -delta, two ? R"(, {"where": {"box": [[-2, -2, -10], [2, 2, -0.8]]}, "displacement": [0, 0, 0]})" : "",
                  two ? "" : R"({"name": "table", "plane": {"point": [0, 0, -1], "normal": [0, 0, 1]}})", two ? R"(, "bodies": true)" : "");
    return text;
  }
};

} // namespace

TEST(DriverAndLibrary, StaticDenseIsBitIdentical)
{
  const std::string dir = temp_dir(), out = dir + "/dense.h5", file = std::string(HSSBEM_MESHES) + "/examples/cube_tension.json";
  run_driver_with({{"-problem", file}, {"-o", out}, {"-bem_mat_type", "dense"}});
  const auto lib = library_static(file, {{"bem_mat_type", value("bem_mat_type", "dense")}});
  const ResultData r = lib->result();
  for (const auto &[name, field] : {std::make_pair("/fields/displacement", flat(r.displacement)), std::make_pair("/fields/traction", flat(r.traction)),
                                    std::make_pair("/fields/stress", flat(r.stress.stress))}) {
    const std::vector<double> file_values = read_dataset(out, name);
    EXPECT_EQ(rel_diff(field, file_values), 0.0) << name;
    EXPECT_TRUE(field == file_values) << name << " differs in some bit";
  }
}

TEST(DriverAndLibrary, StaticH2TakesTheSameIterations)
{
  const std::string dir = temp_dir(), out = dir + "/h2.h5", file = std::string(HSSBEM_MESHES) + "/examples/sphere_pressure.json";
  run_driver_with({{"-problem", file}, {"-o", out}, {"-bem_mat_type", "h2"}, {"-mat_h2_leaf_size", "32"}});
  const auto lib = library_static(file, {{"bem_mat_type", value("bem_mat_type", "h2")}, {"mat_h2_leaf_size", value("mat_h2_leaf_size", 32)}});
  const ResultData r = lib->result();
  const long long its = read_int_attribute(out, "/", "iterations");
  std::printf("H2: %lld GMRES iterations through the driver, %lld through the library\n", its, r.attributes_int.at("iterations"));
  EXPECT_GE(its, 2); // a Krylov solve, not a direct one
  EXPECT_EQ(r.attributes_int.at("iterations"), its);
  EXPECT_EQ(rel_diff(flat(r.displacement), read_dataset(out, "/fields/displacement")), 0.0);
}

TEST(DriverAndLibrary, ContactSceneOnTheH2ReferenceIsTheCommandLines)
{
  const double delta = 0.02;
  const SphereContact c(false, delta, 0);
  const std::string dir = temp_dir(), out = dir + "/contact.h5";
  write_text(dir + "/contact.json", c.problem_json(mesh_file("sphere_l0.msh"), delta, 0));
  run_driver_with({{"-problem", dir + "/contact.json"}, {"-o", out}, {"-bem_mat_type", "h2"}, {"-mat_h2_leaf_size", "16"}});
  ContactSceneReference ref;
  ref.type = OperatorType::H2;
  ref.h2.leaf_size = 16;
  ContactScene scene(c.mesh, Material{1000.0, 0.3}, c.held, {Obstacle::plane("table", {0, 0, -1}, {0, 0, 1})}, {}, {}, option_default::bem_feature_angle, ref);
  EXPECT_EQ(scene.session().mat_type(), "h2");
  scene.set_values(c.values);
  const ContactFrameReport &rep = scene.solve();
  EXPECT_GT(rep.active_vertices, 0);
  EXPECT_GT(rep.corrections, 0); // the H² reference's columns were corrected, as on the command line
  const double du = rel_diff(flat(scene.displacement()), read_dataset(out, "/fields/displacement")), dp = rel_diff(scene.pressure(), read_dataset(out, "/contact/pressure"));
  std::printf("contact on the H2 reference: library against command line, displacement %.2e, pressure %.2e\n", du, dp);
  EXPECT_LE(du, 1e-12);
  EXPECT_LE(dp, 1e-12);
  EXPECT_EQ(read_int_attribute(out, "/contact", "active_vertices"), rep.active_vertices);
}

TEST(DriverAndLibrary, ContactSceneWithAReferencePerBodyIsTheCommandLines)
{
  const double delta = 0.04, gap = 0.01;
  const SphereContact c(true, delta, gap);
  const std::string dir = temp_dir(), out = dir + "/bodies.h5";
  write_off(dir + "/spheres.off", c.mesh);
  write_text(dir + "/bodies.json", c.problem_json(dir + "/spheres.off", delta, gap));
  run_driver_with({{"-problem", dir + "/bodies.json"}, {"-o", out}, {"-bem_mat_type", "dense"}});
  ContactSettings settings;
  settings.bodies = true;
  ContactSceneReference ref;
  ref.type = OperatorType::Dense;
  ContactScene scene(c.mesh, Material{1000.0, 0.3}, c.held, {}, settings, {}, option_default::bem_feature_angle, ref);
  const auto *composite = dynamic_cast<const CompositeReference *>(&scene.session().reference());
  ASSERT_NE(composite, nullptr);
  EXPECT_EQ(composite->num_bodies(), 2);
  scene.set_values(c.values);
  const ContactFrameReport &rep = scene.solve();
  EXPECT_GT(rep.active_vertices, 0);
  const double du = rel_diff(flat(scene.displacement()), read_dataset(out, "/fields/displacement")), dp = rel_diff(scene.pressure(), read_dataset(out, "/contact/pressure"));
  const std::vector<double> f0 = read_dataset(out, "/contact/forces/body_0");
  std::printf("contact of two bodies, a reference each: library against command line, displacement %.2e, pressure %.2e; body 0 pushed with %.4e\n", du, dp, f0[2]);
  EXPECT_LE(du, 1e-12);
  EXPECT_LE(dp, 1e-12);
  EXPECT_LE(rel_diff({scene.body_forces()[0][2]}, {f0[2]}), 1e-12);
}

TEST(DriverAndLibrary, SceneFramesAreTheCommandLines)
{
  // The sphere clamped on its south cap, a patch pushed on its side (one component) and moved in
  // two frames: frame by frame the library's Scene against the driver's result file.
  const std::string dir = temp_dir(), out = dir + "/scene.h5";
  const std::string patch0 = R"({"where": {"sphere": {"center": [1, 0, 0.2], "radius": 0.4}}, "displacement": [-0.04, null, null]})";
  const std::string patch1 = R"({"where": {"sphere": {"center": [0.98, 0.2, 0.2], "radius": 0.4}}, "displacement": [-0.05, null, null]})";
  write_text(dir + "/scene.json", R"({"mesh": ")" + mesh_file("sphere_l0.msh") + R"(", "material": {"E": 1000.0, "nu": 0.3},
 "boundary": [{"where": {"region": "south"}, "displacement": [0, 0, 0]}], "frames": [{"boundary": [)" + patch0 + R"(]}, {"boundary": [)" + patch1 + R"(]}]})");
  run_driver_with({{"-problem", dir + "/scene.json"}, {"-o", out}});
  const ProblemSetup s = setup_problem(dir + "/scene.json", ProblemOverrides{});
  ASSERT_EQ(s.disc->num_sharp_vertices(), 0); // one dof node per vertex: the Scene API's per-vertex conditions are the file's
  const auto per_vertex = [&](const NodeConditions &nc) {
    Scene::Pattern p(s.mesh->vertices.size());
    std::vector<Vec3> v(s.mesh->vertices.size());
    for (int i = 0; i < s.disc->num_nodes(); ++i) p[s.disc->node(i).vertex] = nc.displacement_prescribed[i], v[s.disc->node(i).vertex] = nc.value[i];
    return std::make_pair(p, v);
  };
  Scene scene(*s.mesh, s.material, per_vertex(apply_rules(s.spec.rules, *s.disc, s.spec.file)).first);
  for (std::size_t f = 0; f < 2; ++f) {
    const auto [pattern, values] = per_vertex(frame_conditions(s.spec, f, *s.disc));
    scene.set_pattern(pattern);
    scene.set_values(values);
    scene.solve();
    const double du = rel_diff(flat(scene.displacement()), read_dataset(out, "/frames/" + std::to_string(f) + "/displacement"));
    std::printf("scene frame %zu: library against command line %.2e\n", f, du);
    EXPECT_LE(du, 1e-12);
  }
}

TEST(ContactSessionPrecomputation, AdoptedWhereTheFingerprintMatchesRefusedWhereItDoesNot)
{
  // The seam a saved precomputation will use: a second session of the same problem adopts the
  // first one's reference and columns and gives the same frame without building them again; a
  // session with other options refuses it, naming what differs.
  const double delta = 0.02;
  const SphereContact c(false, delta, 0);
  auto problem = std::make_shared<SessionProblem>(std::make_shared<ProblemSetup>(setup_in_memory(c.mesh, Material{1000.0, 0.3})), QuadratureOptions{});
  const auto job = [&] {
    ContactJob j;
    j.base.displacement_prescribed.resize(problem->disc().num_nodes());
    j.base.value.assign(problem->disc().num_nodes(), Vec3{0, 0, 0});
    for (int i = 0; i < problem->disc().num_nodes(); ++i) {
      const int v = problem->disc().node(i).vertex;
      j.base.displacement_prescribed[i] = c.held[v], j.base.value[i] = c.values[v];
    }
    j.obstacles = {Obstacle::plane("table", {0, 0, -1}, {0, 0, 1})};
    return j;
  };
  MachineLimits limits;
  PetscCallAbort(PETSC_COMM_WORLD, HssbemMachineLimits(PETSC_COMM_SELF, &limits));
  SessionOptions dense;
  dense.operator_type = OperatorType::Dense;
  ContactSession first(problem, job(), dense, limits);
  first.set_up();
  const ContactFrameReport rep = first.step(selection_of(first.job().base), {Pose{}});
  ASSERT_GT(rep.active_vertices, 0);
  const std::vector<Vec3> u = first.solution().u;
  ContactSession second(problem, job(), dense, limits);
  second.adopt(first.precomputation());
  second.set_up();
  EXPECT_EQ(&second.reference(), &first.reference()); // not built again
  second.step(selection_of(second.job().base), {Pose{}});
  EXPECT_TRUE(second.solution().u == u);
  SessionOptions other = dense;
  other.contact_h2_rtol = 1e-9;
  ContactSession third(problem, job(), other, limits);
  try {
    third.adopt(first.precomputation());
    FAIL() << "a precomputation made with other options was adopted";
  } catch (const std::invalid_argument &e) {
    EXPECT_NE(std::string(e.what()).find("the options differ"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("-contact_h2_rtol 1e-10 in the file, 1e-09 in the problem"), std::string::npos) << e.what(); // the first option that differs
  }
}
