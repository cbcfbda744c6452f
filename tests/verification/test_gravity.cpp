// Gravity through the particular solution of a uniform body force (bem/body_force.hpp), end to
// end: the problem file's "gravity" and "density", the static session's result (surface fields,
// stress, reactions, interior points) and a scene's frames that turn the gravity vector.
//
// The column [-a/2, a/2]² × [0, H] (H = 3a) under its own weight, carried by the uniform upward
// traction ρ g H on its base, its other faces free: σ_zz = ρ g (z − H), the other stresses zero
// (Timoshenko & Goodier, a prismatic bar hanging or standing under its own weight). A pure-traction
// problem: the project holds it by regularising along the rigid modes (setup_problem).
#include "solve_helpers.hpp"

#include "hssbem/core/option_table.hpp"
#include "hssbem/petsc/system.h"
#include "hssbem/session/scene_session.hpp"
#include "hssbem/session/static_session.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <string>
#include <vector>

using namespace hssbem;
using namespace hssbem::test;

namespace {

constexpr double E = 1000, nu = 0.3, rho = 2, g = 10, H = 3; // ρ g H = 60
constexpr double weight_stress = rho * g * H;

/// A fresh directory for a test's files.
std::string temp_dir()
{
  char tmpl[] = "/tmp/hssbem-gravity-XXXXXX";
  const char *d = mkdtemp(tmpl);
  if (!d) throw std::runtime_error("mkdtemp failed");
  return d;
}

/// The column [-1/2, 1/2]² × [0, 3] with n × n squares on its ends and n × 3n on each side, as a
/// Gmsh 2.2 file with the regions "base" (z = 0), "top" (z = 3) and "side".
void write_column(const std::string &path, int n)
{
  const int count[3] = {n, n, 3 * n};
  std::map<std::array<int, 3>, int> index;
  std::vector<std::array<int, 3>> keys;
  std::vector<std::array<int, 4>> tris; // 1-based nodes, region
  auto vertex = [&](std::array<int, 3> k) {
    const auto it = index.find(k);
    if (it != index.end()) return it->second;
    keys.push_back(k);
    return index[k] = static_cast<int>(keys.size());
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, w = (axis + 2) % 3, region = axis < 2 ? 2 : (side == 0 ? 1 : 3);
      for (int i = 0; i < count[u]; ++i)
        for (int j = 0; j < count[w]; ++j) {
          auto at = [&](int a, int b) {
            std::array<int, 3> k{};
            k[axis] = side * count[axis], k[u] = a, k[w] = b;
            return vertex(k);
          };
          int q[4] = {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)};
          if (side == 0) std::swap(q[1], q[3]); // outward
          tris.push_back({q[0], q[1], q[2], region});
          tris.push_back({q[0], q[2], q[3], region});
        }
    }
  std::ofstream f(path);
  f.precision(17);
  f << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n3\n2 1 \"base\"\n2 2 \"side\"\n2 3 \"top\"\n$EndPhysicalNames\n";
  f << "$Nodes\n" << keys.size() << "\n";
  for (std::size_t v = 0; v < keys.size(); ++v)
    f << v + 1 << " " << double(keys[v][0]) / n - 0.5 << " " << double(keys[v][1]) / n - 0.5 << " " << double(keys[v][2]) / n << "\n";
  f << "$EndNodes\n$Elements\n" << tris.size() << "\n";
  for (std::size_t e = 0; e < tris.size(); ++e) f << e + 1 << " 2 2 " << tris[e][3] << " " << tris[e][3] << " " << tris[e][0] << " " << tris[e][1] << " " << tris[e][2] << "\n";
  f << "$EndElements\n";
}

/// A problem file: the column of n, the material with the density, `rest` (JSON members after
/// the material, each with its leading comma).
std::string column_problem(const std::string &dir, int n, const std::string &rest)
{
  const std::string mesh = dir + "/column_" + std::to_string(n) + ".msh", file = dir + "/column_" + std::to_string(n) + ".json";
  write_column(mesh, n);
  std::ofstream(file) << R"({"mesh": ")" << mesh << R"(", "material": {"E": )" << E << R"(, "nu": )" << nu << R"(, "density": )" << rho << "}" << rest << "}";
  return file;
}

/// The static session of a problem file on the dense path, solved.
std::unique_ptr<StaticSession> solved(const std::string &file)
{
  auto setup = std::make_shared<ProblemSetup>(setup_problem(file, ProblemOverrides{}));
  OptionValues given;
  given["bem_mat_type"] = OptionValue::of(*find_option("bem_mat_type"), std::string("dense"));
  const SessionOptions o = session_options(given);
  auto s = std::make_unique<StaticSession>(PETSC_COMM_WORLD, std::make_shared<SessionProblem>(setup, o.quad), o);
  s->solve();
  return s;
}

/// The largest difference from the column's exact stress (σ_zz = ρ g (z − H), the rest zero) over
/// the points, relative to ρ g H.
double column_stress_error(const std::vector<Vec3> &points, const std::vector<Voigt> &stress)
{
  double e = 0;
  for (std::size_t p = 0; p < points.size(); ++p) {
    const Voigt exact{0, 0, rho * g * (points[p][2] - H), 0, 0, 0};
    for (int k = 0; k < 6; ++k) e = std::max(e, std::abs(stress[p][k] - exact[k]));
  }
  return e / weight_stress;
}

/// The column's exact displacement (up to a rigid motion): u_x = −ν ρ g x (z − H)/E, u_y alike,
/// u_z = ρ g (z²/2 − H z)/E + ν ρ g (x² + y²)/(2E).
Vec3 column_displacement(const Vec3 &x)
{
  const double c = rho * g / E;
  return {-nu * c * x[0] * (x[2] - H), -nu * c * x[1] * (x[2] - H), c * (x[2] * x[2] / 2 - H * x[2]) + nu * c * (x[0] * x[0] + x[1] * x[1]) / 2};
}

/// The relative L2 error of the displacement per vertex (its dof nodes' mean), rigid motion removed.
double column_displacement_error(const ProblemSetup &s, const std::vector<Vec3> &per_vertex)
{
  std::vector<Vec3> got, exact;
  for (int i = 0; i < s.disc->num_nodes(); ++i) {
    got.push_back(per_vertex[s.disc->node(i).vertex]);
    exact.push_back(column_displacement(s.disc->node_position(i)));
  }
  return rel_error_modulo_rigid(*s.disc, got, exact);
}

/// Interior points off the surface by a quarter of the width at least, over the column's height.
std::string column_interior_points()
{
  std::string pts;
  for (double z : {0.4, 0.9, 1.5, 2.1, 2.6})
    for (const auto &xy : {std::array<double, 2>{0, 0}, {0.2, -0.1}, {-0.25, 0.25}})
      pts += std::string(pts.empty() ? "" : ", ") + "[" + std::to_string(xy[0]) + ", " + std::to_string(xy[1]) + ", " + std::to_string(z) + "]";
  return ", \"interior_points\": [" + pts + "]";
}

} // namespace

TEST(Gravity, AColumnUnderItsOwnWeightCarriedOnItsBase)
{
  // Two meshes (4 x 4 x 12 and 8 x 8 x 24 squares, 310 and 1062 dof nodes). Measured (Release):
  // displacement 3.4e-3 → 9.5e-4 (order 1.83); interior stress 1.9e-3 → 4.2e-4 (order 2.17);
  // surface stress 2.9e-2 → 1.5e-2 (order 0.94), its largest error on the base's edges and the
  // row of vertices above them, first order there as the surface stress of the homogeneous part
  // is near sharp edges (σ_p itself is added exactly); on the vertices off the edges 7.2e-3.
  const std::string dir = temp_dir();
  const std::string load = R"(, "gravity": [0, 0, -10], "boundary": [{"where": {"region": "base"}, "traction": [0, 0, 60]}])" + column_interior_points();
  double disp[2], surface[2], off_edges[2], inside[2];
  const int n[2] = {4, 8};
  for (int l = 0; l < 2; ++l) {
    const auto s = solved(column_problem(dir, n[l], load));
    const ResultData r = s->result();
    EXPECT_EQ(r.attributes_int.at("pure_traction"), 1);
    disp[l] = column_displacement_error(s->problem().setup(), r.displacement);
    surface[l] = column_stress_error(r.vertices, r.stress.stress);
    std::vector<Vec3> smooth;
    std::vector<Voigt> smooth_stress;
    for (std::size_t v = 0; v < r.vertices.size(); ++v)
      if (!r.sharp_vertex[v]) smooth.push_back(r.vertices[v]), smooth_stress.push_back(r.stress.stress[v]);
    off_edges[l] = column_stress_error(smooth, smooth_stress);
    inside[l] = column_stress_error(r.interior_points, r.interior_stress);
    // The load: the base carries the weight ρ g V = 60 (a = 1), and so does the whole surface
    // (the reported traction is the whole one: without t_p the base would show 30).
    const Vec3 base = r.reactions.at("base"), total = r.reactions.at("total");
    EXPECT_NEAR(base[2], rho * g * H, 1e-9 * weight_stress);
    EXPECT_NEAR(total[2], rho * g * H, 1e-9 * weight_stress);
    EXPECT_NEAR(std::hypot(total[0], total[1]), 0, 1e-9 * weight_stress);
    PetscPrintf(PETSC_COMM_WORLD, "column, %d x %d x %d squares: displacement %.3e; largest stress error / (rho g H): surface %.3e (off the edges %.3e), interior %.3e\n", n[l], n[l],
                3 * n[l], disp[l], surface[l], off_edges[l], inside[l]);
  }
  const double order_disp = std::log2(disp[0] / disp[1]), order_surface = std::log2(surface[0] / surface[1]), order_inside = std::log2(inside[0] / inside[1]);
  PetscPrintf(PETSC_COMM_WORLD, "column: observed order displacement %.2f, surface stress %.2f, interior stress %.2f\n", order_disp, order_surface, order_inside);
  EXPECT_LE(inside[1], 1.5e-3); // the issue's 1e-2 inside, with margin over the measured 4.2e-4
  EXPECT_GE(order_inside, 1.6);
  EXPECT_LE(disp[1], 3e-3);
  EXPECT_GE(order_disp, 1.5);
  EXPECT_LE(off_edges[1], 2e-2);
  EXPECT_LE(surface[1], 5e-2);
  EXPECT_GE(order_surface, 0.7);
  EXPECT_GT(surface[1], 1e-6); // a discretisation error, not a tautology
}

TEST(Gravity, AClampedColumnsBaseCarriesItsWeight)
{
  // Clamped on its base, free elsewhere, gravity askew: the reaction (computed, not prescribed:
  // the base and, as the clamp reaches every node of the base's edge vertices, the side's nodes
  // along that edge) is the weight ρ g V, by equilibrium. Measured on 2, 4, 8 squares across:
  // relative error 1.3e-2, 6.7e-3, 2.6e-3; here 4 (bound 3x).
  const std::string dir = temp_dir();
  const auto s = solved(column_problem(dir, 4, R"(, "gravity": [3, 0, -10], "boundary": [{"where": {"region": "base"}, "displacement": [0, 0, 0]}])"));
  const ResultData r = s->result();
  EXPECT_EQ(r.attributes_int.at("pure_traction"), 0);
  const Vec3 weight = rho * H * Vec3{3, 0, -10}, total = r.reactions.at("total");
  const double e = norm(total + weight) / norm(weight);
  PetscPrintf(PETSC_COMM_WORLD, "clamped column: reaction (%.4f, %.4f, %.4f), weight (%.1f, %.1f, %.1f), relative error %.2e\n", total[0], total[1], total[2], weight[0], weight[1],
              weight[2], e);
  EXPECT_LE(e, 2e-2);
  EXPECT_NEAR(r.attributes_real.at("density"), rho, 0);
  EXPECT_NEAR(r.attributes_real.at("gravity_x"), 3, 0);
}

TEST(Gravity, APressureRuleCarriesTheColumnAsItsTraction)
{
  // The base's load as a pressure (−p n with n = −z: p = ρ g H) instead of a traction: a pressure
  // node's homogeneous load is p − b·r over each flat triangle, the traction's t̄ − t_p at the
  // nodes; on the flat base both are exact, so the two problems give the same fields (round-off).
  const std::string dir = temp_dir();
  const auto t = solved(column_problem(dir, 4, R"(, "gravity": [0, 0, -10], "boundary": [{"where": {"region": "base"}, "traction": [0, 0, 60]}])"));
  const auto p = solved(column_problem(dir, 4, R"(, "gravity": [0, 0, -10], "boundary": [{"where": {"region": "base"}, "pressure": 60}])"));
  const ResultData rt = t->result(), rp = p->result();
  double d = 0;
  for (std::size_t v = 0; v < rt.vertices.size(); ++v)
    for (int k = 0; k < 6; ++k) d = std::max(d, std::abs(rt.stress.stress[v][k] - rp.stress.stress[v][k]));
  PetscPrintf(PETSC_COMM_WORLD, "column carried by a pressure against a traction: stress differs by %.2e of rho g H\n", d / weight_stress);
  EXPECT_LE(d, 1e-9 * weight_stress);
  EXPECT_NEAR(rp.reactions.at("base")[2], rho * g * H, 1e-9 * weight_stress);
}

TEST(Gravity, AScenesFramesTurnTheGravity)
{
  // The clamped column, the patient turned frame by frame: each frame's fields against a static
  // solve of the same problem with that frame's gravity (the scene's reference LU and W against a
  // dense solve: round-off). The third frame gives no gravity and takes the base's.
  const std::string dir = temp_dir();
  const std::string clamp = R"("boundary": [{"where": {"region": "base"}, "displacement": [0, 0, 0]}])";
  const std::string file = column_problem(dir, 2, ", \"gravity\": [0, 0, -10], " + clamp + R"(, "frames": [{"gravity": [-10, 0, 0]}, {"gravity": [0, 7, -7]}, {"boundary": []}])");
  auto setup = std::make_shared<ProblemSetup>(setup_problem(file, ProblemOverrides{}));
  const SessionOptions o = session_options({});
  MachineLimits limits;
  ASSERT_EQ(HssbemMachineLimits(PETSC_COMM_WORLD, &limits), 0);
  auto problem = std::make_shared<SessionProblem>(setup, o.quad);
  SceneSession scene(problem, scene_reference(*setup), o, limits);
  const char *gravity[3] = {"[-10, 0, 0]", "[0, 7, -7]", "[0, 0, -10]"};
  for (std::size_t f = 0; f < 3; ++f) {
    scene.step(f);
    const FrameData frame = scene.frame_data(kFrameFields);
    const auto s = solved(column_problem(dir, 2, ", \"gravity\": " + std::string(gravity[f]) + ", " + clamp));
    const ResultData r = s->result();
    double du = 0, dsig = 0, umax = 0, smax = 0;
    for (std::size_t v = 0; v < r.vertices.size(); ++v) {
      du = std::max(du, norm(frame.displacement[v] - r.displacement[v])), umax = std::max(umax, norm(r.displacement[v]));
      for (int k = 0; k < 6; ++k) dsig = std::max(dsig, std::abs(frame.stress.stress[v][k] - r.stress.stress[v][k])), smax = std::max(smax, std::abs(r.stress.stress[v][k]));
    }
    PetscPrintf(PETSC_COMM_WORLD, "scene frame %d, gravity %s: displacement %.2e, stress %.2e of the static solve's\n", static_cast<int>(f), gravity[f], du / umax, dsig / smax);
    EXPECT_LE(du, 1e-9 * umax);
    EXPECT_LE(dsig, 1e-9 * smax);
    EXPECT_GT(smax, 0.5 * rho * 10 * H); // the weight's stress is there
    EXPECT_NEAR(frame.attributes_real.at("gravity_x"), f == 0 ? -10 : 0, 0);
  }
}

TEST(Gravity, ABodyImmersedInAFluidOfItsOwnDensityIsHydrostatic)
{
  // The pressure p = b·x on every vertex (a fluid of the body's density around it): the exact
  // stress is σ = −(b·x) I everywhere, in equilibrium with the weight. Its homogeneous part is the
  // constant −(b·x₀) I, a linear displacement that P1 elements carry exactly, so the solve leaves
  // only the quadrature's and the faceting's errors: on the coarsest sphere (pure traction),
  // the surface stress, the interior stress and the displacement against the closed form.
  const Material mat = Material::from_young(E, nu);
  const Vec3 gravity{1, -2, -9}, b = rho * gravity;
  const SurfaceMesh mesh = read_mesh(mesh_file("sphere_l0.msh"));
  std::string p;
  for (const Vec3 &x : mesh.vertices) p += std::string(p.empty() ? "" : ", ") + std::to_string(dot(b, x));
  const std::string dir = temp_dir(), file = dir + "/immersed.json";
  std::ofstream(file) << R"({"mesh": ")" << mesh_file("sphere_l0.msh") << R"(", "material": {"E": )" << E << R"(, "nu": )" << nu << R"(, "density": )" << rho
                      << R"(}, "gravity": [1, -2, -9], "boundary": [{"where": "all", "pressure": [)" << p << R"(]}],
                         "interior_points": [[0, 0, 0], [0.3, -0.2, 0.4], [-0.5, 0.1, -0.2]]})";
  const auto s = solved(file);
  const ResultData r = s->result();
  const auto exact = [&](const Vec3 &x) { const double q = -dot(b, x); return Voigt{q, q, q, 0, 0, 0}; };
  const double scale = norm(b); // |σ| at |x| = 1
  double surface = 0, inside = 0;
  for (std::size_t v = 0; v < r.vertices.size(); ++v)
    for (int k = 0; k < 6; ++k) surface = std::max(surface, std::abs(r.stress.stress[v][k] - exact(r.vertices[v])[k]) / scale);
  for (std::size_t q = 0; q < r.interior_points.size(); ++q)
    for (int k = 0; k < 6; ++k) inside = std::max(inside, std::abs(r.interior_stress[q][k] - exact(r.interior_points[q])[k]) / scale);
  // The displacement: u_p about any origin, up to a rigid motion and the constant stress's linear field.
  const UniformBodyForce up(mat, b, {0, 0, 0});
  std::vector<Vec3> got, want;
  const Discretization &disc = *s->problem().setup().disc;
  for (int i = 0; i < disc.num_nodes(); ++i) got.push_back(r.displacement[disc.node(i).vertex]), want.push_back(up.displacement(disc.node_position(i)));
  const double du = rel_error_modulo_rigid(disc, got, want);
  PetscPrintf(PETSC_COMM_WORLD, "immersed sphere: largest stress error / |b|: surface %.2e, interior %.2e; displacement %.2e\n", surface, inside, du);
  // Measured: surface 2.7e-8, interior 2.0e-7, displacement 1.7e-8 (bounds 10x: quadrature, not
  // discretisation; without the particular solution each would be of order 1).
  EXPECT_LE(surface, 3e-7);
  EXPECT_LE(inside, 2e-6);
  EXPECT_LE(du, 2e-7);
}
