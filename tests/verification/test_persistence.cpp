// A contact's precomputation saved and loaded (session/precomputation_file.hpp, io/saved_file.hpp):
// the frames after a load are the cold run's to the bit (one body, and two bodies on a composite
// reference); a file made for another problem is refused naming what differs, one test per
// difference (mesh, material, pattern, candidates, options, ranks, version, format); truncated
// and altered files are refused, never read.
#include "solve_helpers.hpp"

#include "hssbem/io/saved_file.hpp"
#include "hssbem/session/contact_scene.hpp"
#include "hssbem/session/precomputation_file.hpp"
#include "hssbem/session/scene.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <unistd.h>

using namespace hssbem;
using namespace hssbem::test;

namespace {

constexpr double E = 1000, nu = 0.3, delta = 0.01;

/// A contact problem made in memory: the shipped cube pushed down by δ onto a table (rollers on
/// x0 and y0), or (two) two stacked cubes, the lower one on u_z = 0, the upper one pushed down.
struct Case {
  std::shared_ptr<const SessionProblem> problem;
  ContactJob job;
  SessionOptions options;

  explicit Case(bool two = false, Material material = {E, nu}, Vec3 shift = {0, 0, 0})
  {
    SurfaceMesh mesh = two ? stacked_cubes(0.0) : read_mesh(mesh_file("cube_l0.msh"));
    std::vector<std::string> notices;
    validate_and_orient(mesh, notices);
    mesh.vertices[0] = mesh.vertices[0] + shift; // a mesh of the same sizes, another vertex
    problem = std::make_shared<SessionProblem>(std::make_shared<ProblemSetup>(setup_in_memory(mesh, material)), QuadratureOptions{});
    const Discretization &disc = problem->disc();
    const int nn = disc.num_nodes();
    job.base.displacement_prescribed.assign(nn, {false, false, false});
    job.base.value.assign(nn, Vec3{0, 0, 0});
    const double top = two ? 2 : 1;
    for (int i = 0; i < nn; ++i) {
      const Vec3 x = disc.node_position(i), n = disc.node(i).normal;
      auto &known = job.base.displacement_prescribed[i];
      if (two && x[2] < 1e-12 && n[2] < -0.9) known[2] = true;
      if (x[2] > top - 1e-12 && n[2] > 0.9) known[2] = true, job.base.value[i][2] = -delta;
      if (x[0] < 1e-12) known[0] = true;
      if (x[1] < 1e-12) known[1] = true;
    }
    if (two) job.settings.bodies = true;
    else job.obstacles = {Obstacle::plane("table", {0, 0, 0}, {0, 0, 1})};
    options.operator_type = OperatorType::Dense;
  }
  std::unique_ptr<ContactSession> session() const
  {
    MachineLimits limits;
    limits.node_memory_bytes = 4e9; // the dense reference of 450 or 900 unknowns fits any machine
    return std::make_unique<ContactSession>(problem, job, options, limits);
  }
  /// Frame f: the table raised by f δ / 5 (one body), or the top pushed (1 + f / 2) δ (two).
  void step(ContactSession &s, int f) const
  {
    SystemSelection values = selection_of(job.base);
    for (Vec3 &v : values.known) v = (job.settings.bodies ? 1 + 0.5 * f : 1.0) * v;
    s.step(values, std::vector<Pose>(job.obstacles.size(), Pose::translation({0, 0, 0.2 * delta * f})));
  }
};

/// A file name of its own in the working directory (removed at the end).
struct TempFile {
  std::string path;
  explicit TempFile(const std::string &tag) : path("persistence_" + tag + "_" + std::to_string(::getpid()) + ".pre") {}
  ~TempFile() { std::remove(path.c_str()); }
};

std::string bytes_of(const std::string &path)
{
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void write_bytes(const std::string &path, const std::string &bytes) { std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size())); }

template <class T> bool same_bits(const std::vector<T> &a, const std::vector<T> &b) { return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0; }

/// Every frame's displacement, traction and pressure of the cold session and of a session on
/// its precomputation loaded from `file`, compared bit for bit; the frames must touch.
void expect_frames_identical(const Case &c, ContactSession &cold, const std::string &file, int frames)
{
  auto warm = c.session();
  warm->adopt(load_precomputation(*warm, file));
  for (int f = 0; f < frames; ++f) {
    c.step(cold, f);
    c.step(*warm, f);
    const ContactSolution &a = cold.solution(), &b = warm->solution();
    EXPECT_GT(*std::max_element(a.pressure.begin(), a.pressure.end()), 0.0) << "frame " << f << " touches"; // no test by doing nothing
    EXPECT_TRUE(same_bits(a.u, b.u)) << "frame " << f;
    EXPECT_TRUE(same_bits(a.t, b.t)) << "frame " << f;
    EXPECT_TRUE(same_bits(a.pressure, b.pressure)) << "frame " << f;
    EXPECT_EQ(cold.report().iterations, warm->report().iterations) << "frame " << f;
  }
}

/// The message of loading `file` for case c (empty: it loaded).
std::string load_error(const Case &c, const std::string &file)
{
  auto s = c.session();
  try {
    s->adopt(load_precomputation(*s, file));
  } catch (const SavedFileError &e) {
    return e.what();
  }
  return "";
}

/// A set-up session of case c saved to `file`, its fingerprint first changed by `alter`.
template <class F> void save_altered(const Case &c, const std::string &file, F alter)
{
  auto s = c.session();
  s->set_up();
  alter(s->precomputation()->fingerprint);
  save_precomputation(*s, file);
}

} // namespace

TEST(Persistence, FramesAfterLoadAreTheColdOnesBitwise)
{
  const Case c;
  auto cold = c.session();
  cold->set_up();
  const TempFile file("one");
  save_precomputation(*cold, file.path);
  expect_frames_identical(c, *cold, file.path, 4);
}

TEST(Persistence, ColumnsComputedByFramesAreSavedToo)
{
  const Case c;
  auto cold = c.session();
  for (int f = 0; f < 3; ++f) c.step(*cold, f); // columns added by the frames
  const std::size_t held = cold->precomputation()->columns->size();
  ASSERT_GT(held, 0u);
  const TempFile file("later");
  save_precomputation(*cold, file.path);
  auto warm = c.session();
  warm->adopt(load_precomputation(*warm, file.path));
  warm->set_up();
  EXPECT_EQ(warm->precomputation()->columns->size(), held);
  auto again = c.session();
  again->set_up();
  expect_frames_identical(c, *again, file.path, 3);
}

TEST(Persistence, TwoBodiesOnACompositeReference)
{
  const Case c(true);
  auto cold = c.session();
  cold->set_up();
  ASSERT_EQ(cold->on_h2().size(), 2u);
  const TempFile file("two");
  save_precomputation(*cold, file.path);
  expect_frames_identical(c, *cold, file.path, 3);
}

TEST(Persistence, AnotherMeshIsRefused)
{
  const TempFile file("mesh");
  save_altered(Case(), file.path, [](Fingerprint &) {});
  EXPECT_NE(load_error(Case(false, {E, nu}, {0, 0, 1e-9}), file.path).find("the mesh differs: the same sizes, other coordinates"), std::string::npos);
  EXPECT_NE(load_error(Case(true), file.path).find("the mesh differs: 98 vertices and 192 triangles in the file, 196 vertices"), std::string::npos);
  EXPECT_EQ(load_error(Case(), file.path), "");
}

TEST(Persistence, AnotherMaterialIsRefused)
{
  const TempFile file("material");
  save_altered(Case(), file.path, [](Fingerprint &) {});
  EXPECT_NE(load_error(Case(false, {E, 0.31}), file.path).find("the material differs: E 1000, nu 0.3 in the file, E 1000, nu 0.31 in the problem"), std::string::npos)
      << load_error(Case(false, {E, 0.31}), file.path);
}

TEST(Persistence, AnotherPatternIsRefusedButOtherValuesLoad)
{
  const TempFile file("pattern");
  save_altered(Case(), file.path, [](Fingerprint &) {});
  Case other;
  other.job.base.displacement_prescribed[0][2] = !other.job.base.displacement_prescribed[0][2];
  EXPECT_NE(load_error(other, file.path).find("the pattern of prescribed components differs"), std::string::npos);
  Case values; // the same pattern, other values: loads
  for (Vec3 &v : values.job.base.value) v = 2.0 * v;
  EXPECT_EQ(load_error(values, file.path), "");
}

TEST(Persistence, OtherOptionsAreRefused)
{
  const TempFile file("options");
  save_altered(Case(), file.path, [](Fingerprint &) {});
  Case other;
  other.options.contact.reach = 0.2;
  EXPECT_NE(load_error(other, file.path).find("the options differ: -contact_reach 0 in the file, 0.2 in the problem"), std::string::npos) << load_error(other, file.path);
  Case frames; // the frames' solver's own options do not shape the precomputation
  frames.options.contact.tol = 1e-9, frames.options.contact.max_it = 7;
  EXPECT_EQ(load_error(frames, file.path), "");
}

TEST(Persistence, AnotherCandidateSetIsRefused)
{
  Case c; // frames known ahead: the dense reference keeps the columns of K₀′ the candidates need
  c.job.frames = {c.job.base};
  c.job.placements = {std::vector<Pose>(1)};
  const TempFile file("candidates");
  save_altered(c, file.path, [](Fingerprint &) {});
  Case fewer = c;
  fewer.job.settings.candidate.assign(fewer.problem->mesh().num_vertices(), 0);
  for (int v = 0; v < fewer.problem->mesh().num_vertices(); ++v) fewer.job.settings.candidate[v] = fewer.problem->mesh().vertices[v][0] < 0.5;
  const std::string why = load_error(fewer, file.path);
  EXPECT_NE(why.find("the candidate set differs: "), std::string::npos) << why;
  EXPECT_EQ(load_error(c, file.path), "");
}

TEST(Persistence, ContactSceneSavesAndLoads)
{
  SurfaceMesh mesh = read_mesh(mesh_file("cube_l0.msh"));
  std::vector<std::string> notices;
  validate_and_orient(mesh, notices);
  ContactScene::Pattern held(mesh.vertices.size(), {false, false, false});
  std::vector<Vec3> values(mesh.vertices.size(), Vec3{0, 0, 0});
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    const Vec3 &x = mesh.vertices[v];
    if (x[2] > 1 - 1e-12) held[v][2] = true, values[v][2] = -delta;
    if (x[0] < 1e-12) held[v][0] = true;
    if (x[1] < 1e-12) held[v][1] = true;
  }
  ContactSceneReference ref;
  ref.type = OperatorType::Dense;
  const std::vector<Obstacle> table{Obstacle::plane("table", {0, 0, 0}, {0, 0, 1})};
  ContactScene cold(mesh, Material{E, nu}, held, table, {}, {}, option_default::bem_feature_angle, ref);
  const TempFile file("scene");
  cold.save(file.path);
  ref.load = file.path;
  ContactScene warm(mesh, Material{E, nu}, held, table, {}, {}, option_default::bem_feature_angle, ref);
  for (ContactScene *s : {&cold, &warm}) s->set_values(values), s->set_obstacle_offset("table", {0, 0, 0.002}), s->solve();
  EXPECT_FALSE(cold.active_vertices().empty());
  EXPECT_TRUE(same_bits(cold.displacement(), warm.displacement()));
  EXPECT_TRUE(same_bits(cold.pressure(), warm.pressure()));
  EXPECT_THROW( // another material: refused
      ContactScene(mesh, Material{E, 0.4}, held, table, {}, {}, option_default::bem_feature_angle, ref), SavedFileError);
}

TEST(Persistence, AnotherRankCountIsRefused)
{
  const TempFile file("ranks");
  save_altered(Case(), file.path, [](Fingerprint &f) { f.ranks = 2; });
  EXPECT_NE(load_error(Case(), file.path).find("the number of ranks differs: 2 in the file, 1 in the problem"), std::string::npos);
}

TEST(Persistence, AnotherVersionIsRefused)
{
  const TempFile file("version");
  save_altered(Case(), file.path, [](Fingerprint &f) { f.version = "0.0.1"; });
  EXPECT_NE(load_error(Case(), file.path).find("it was made by hssbem 0.0.1, this is hssbem"), std::string::npos);
}

TEST(Persistence, AnotherFormatOrKindIsRefused)
{
  const TempFile file("format");
  {
    SavedFileWriter w(file.path, {}, "contact precomputation", kPrecomputationFormat + 1);
    w.commit();
  }
  EXPECT_NE(load_error(Case(), file.path).find("its format is version 3; this hssbem reads version 2"), std::string::npos);
  {
    SavedFileWriter w(file.path, {}, "scene precomputation", kPrecomputationFormat);
    w.commit();
  }
  EXPECT_NE(load_error(Case(), file.path).find("it holds a scene precomputation, not a contact precomputation"), std::string::npos);
}

TEST(Persistence, TruncatedFilesAreRefused)
{
  const TempFile file("whole"), cut("cut");
  save_altered(Case(), file.path, [](Fingerprint &) {});
  const std::string bytes = bytes_of(file.path);
  for (std::size_t keep : {std::size_t{0}, std::size_t{100}, std::size_t{512}, bytes.size() / 2, bytes.size() - 1}) {
    write_bytes(cut.path, bytes.substr(0, keep));
    const std::string why = load_error(Case(), cut.path);
    EXPECT_TRUE(why.find("truncated") != std::string::npos || why.find("no hssbem header") != std::string::npos) << keep << " bytes: " << why;
  }
  write_bytes(cut.path, bytes + "x");
  EXPECT_NE(load_error(Case(), cut.path).find("truncated or extended"), std::string::npos);
}

TEST(Persistence, AlteredFilesAreRefused)
{
  const TempFile file("whole2"), bad("flip");
  save_altered(Case(), file.path, [](Fingerprint &) {});
  const std::string bytes = bytes_of(file.path);
  ASSERT_EQ(load_error(Case(), file.path), "");
  int refused = 0, tried = 0;
  for (std::size_t at = 0; at < bytes.size(); at += at < 600 ? 7 : bytes.size() / 300 + 1) { // the header densely, the rest spread
    std::string b = bytes;
    b[at] = static_cast<char>(b[at] ^ (1 << (at % 8)));
    write_bytes(bad.path, b);
    ++tried;
    refused += !load_error(Case(), bad.path).empty();
  }
  EXPECT_EQ(refused, tried);
  EXPECT_GT(tried, 300);
}

// --- a scene without contact (SceneSession, the library's Scene) ------------------------------

namespace {

/// The shipped cube clamped at its base (z = 0), its top's vertices the candidates; frame f
/// presses the top's vertices with x ≤ 0.25 (f + 1) down by δ (switched: u prescribed).
struct SceneCase {
  SurfaceMesh mesh;
  Scene::Pattern clamped;
  std::vector<char> top;
  SceneOptions options;

  SceneCase()
  {
    mesh = read_mesh(mesh_file("cube_l0.msh"));
    std::vector<std::string> notices;
    validate_and_orient(mesh, notices);
    clamped.assign(mesh.vertices.size(), {false, false, false});
    top.assign(mesh.vertices.size(), 0);
    for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
      if (mesh.vertices[v][2] < 1e-12) clamped[v] = {true, true, true};
      top[v] = mesh.vertices[v][2] > 1 - 1e-12;
    }
    options.strategy = SceneStrategy::Update; // auto's choice follows measured times: one strategy for both runs
  }
  std::unique_ptr<Scene> scene(const Material &m = {E, nu}, const std::string &load = {}) const
  {
    return std::make_unique<Scene>(mesh, m, clamped, options, nullptr, option_default::bem_feature_angle, top, load);
  }
  SceneStrategy frame(Scene &s, int f) const
  {
    Scene::Pattern p = clamped;
    std::vector<Vec3> values(mesh.vertices.size(), Vec3{0, 0, 0});
    for (std::size_t v = 0; v < mesh.vertices.size(); ++v)
      if (top[v] && mesh.vertices[v][0] <= 0.25 * (f + 1) + 1e-12) p[v][2] = true, values[v][2] = -delta;
    s.set_pattern(p);
    s.set_values(values);
    return s.solve().strategy;
  }
};

std::string scene_load_error(const SceneCase &c, const Material &m, const std::string &file)
{
  try {
    c.scene(m, file);
  } catch (const SavedFileError &e) {
    return e.what();
  }
  return "";
}

} // namespace

TEST(Persistence, SceneFramesAfterLoadAreTheColdOnesBitwise)
{
  const SceneCase c;
  auto cold = c.scene();
  const TempFile file("plain_scene");
  cold->save(file.path);
  auto warm = c.scene({E, nu}, file.path);
  for (int f = 0; f < 3; ++f) {
    EXPECT_EQ(c.frame(*cold, f), SceneStrategy::Update);
    c.frame(*warm, f);
    double most = 0;
    for (const Vec3 &u : cold->displacement()) most = std::max(most, -u[2]);
    EXPECT_GT(most, 0.99 * delta) << "frame " << f << " presses the top"; // no test by doing nothing
    EXPECT_TRUE(same_bits(cold->displacement(), warm->displacement())) << "frame " << f;
    EXPECT_TRUE(same_bits(cold->traction(), warm->traction())) << "frame " << f;
  }
}

TEST(Persistence, SceneMismatchesAreRefused)
{
  const SceneCase c;
  const TempFile file("plain_scene2"), contact("contact_for_scene");
  c.scene()->save(file.path);
  EXPECT_NE(scene_load_error(c, {E, 0.31}, file.path).find("the material differs: E 1000, nu 0.3 in the file, E 1000, nu 0.31 in the problem"), std::string::npos);
  SceneCase fewer = c; // another candidate set
  for (std::size_t v = 0; v < fewer.top.size(); ++v) fewer.top[v] = fewer.top[v] && fewer.mesh.vertices[v][0] < 0.5;
  EXPECT_NE(scene_load_error(fewer, {E, nu}, file.path).find("the candidate set differs"), std::string::npos) << scene_load_error(fewer, {E, nu}, file.path);
  SceneCase held = c; // another reference pattern
  held.clamped[0] = {!held.clamped[0][0], held.clamped[0][1], held.clamped[0][2]};
  EXPECT_NE(scene_load_error(held, {E, nu}, file.path).find("the pattern of prescribed components differs"), std::string::npos) << scene_load_error(held, {E, nu}, file.path);
  save_altered(Case(), contact.path, [](Fingerprint &) {}); // a contact's file is no scene's
  EXPECT_NE(scene_load_error(c, {E, nu}, contact.path).find("it holds a contact precomputation, not a scene precomputation"), std::string::npos);
  EXPECT_EQ(scene_load_error(c, {E, nu}, file.path), "");
}
