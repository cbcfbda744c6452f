/// \file test_problem.cpp
/// Problem file parsing, boundary rules, node conditions and material validation.
#include "hssbem/problem/problem.hpp"
#include "hssbem/bem/rigid_modes.hpp"
#include "hssbem/problem/setup.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <stdexcept>
#include <string>

using namespace hssbem;

namespace {

const std::string k_head = R"({"mesh": "m.msh", "material": {"E": 1000, "nu": 0.3}, )";

/// A problem whose "boundary" is the given JSON list.
std::string with_rules(const std::string &rules) { return k_head + "\"boundary\": " + rules + "}"; }

std::vector<BoundaryRule> rules_of(const std::string &rules)
{
  return parse_problem(with_rules(rules), "problem.json").rules;
}

/// Unit cube [0,1]^3, vertex x + 2y + 4z, 12 outward triangles; the bottom face (z = 0) is
/// physical group 1 "base", the rest 2 "body". Optionally one vertex used by no triangle.
SurfaceMesh unit_cube(bool with_unused = false)
{
  SurfaceMesh m;
  for (int v = 0; v < 8; ++v)
    m.vertices.push_back({double(v & 1), double((v >> 1) & 1), double((v >> 2) & 1)});
  for (int a = 0; a < 3; ++a)
    for (int side = 0; side < 2; ++side) {
      // quad (u, v) in axes (a+1, a+2) runs counter-clockwise about +e_a; reverse it at side 0
      std::array<int, 4> q{};
      const int uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      for (int k = 0; k < 4; ++k)
        q[k] = (side << a) | (uv[k][0] << ((a + 1) % 3)) | (uv[k][1] << ((a + 2) % 3));
      if (side == 0)
        std::swap(q[1], q[3]);
      const int tag = (a == 2 && side == 0) ? 1 : 2;
      m.triangles.push_back({q[0], q[1], q[2]});
      m.triangles.push_back({q[0], q[2], q[3]});
      m.triangle_region.insert(m.triangle_region.end(), 2, tag);
    }
  m.region_tags = {{"base", 1}, {"body", 2}};
  if (with_unused)
    m.vertices.push_back({0.5, 0.5, 0.5});
  m.source = "cube";
  return m;
}

/// Runs f, expects a ProblemError whose message contains every word.
void expect_error(const std::function<void()> &f, std::initializer_list<const char *> words)
{
  try {
    f();
    ADD_FAILURE() << "no ProblemError; expected one mentioning " << *words.begin();
  } catch (const ProblemError &e) {
    const std::string msg = e.what();
    for (const char *w : words)
      EXPECT_NE(msg.find(w), std::string::npos) << "'" << w << "' not in: " << msg;
  }
}

void expect_parse_error(const std::string &text, std::initializer_list<const char *> words)
{
  expect_error([&] { parse_problem(text, "problem.json"); }, words);
}

void expect_apply_error(const std::string &rules, std::initializer_list<const char *> words)
{
  const SurfaceMesh mesh = unit_cube(true);
  expect_error([&] { apply_rules(rules_of(rules), mesh, "problem.json"); }, words);
}

VertexConditions apply_text(const std::string &rules, bool with_unused = false)
{
  return apply_rules(rules_of(rules), unit_cube(with_unused), "problem.json");
}

} // namespace

// ---- parsing ---------------------------------------------------------------------------------

TEST(ProblemFile, TopLevelKeysAndPaths)
{
  const std::string text = R"({
    // comments are allowed
    "mesh": "sphere.msh", /* block comments too */
    "material": {"E": 1000.0, "nu": 0.3},
    "boundary": [],
    "interior_points": [[0, 0, 0], [0.5, -1, 2e-3]],
    "output": "out/result.h5"
  })";
  const ProblemSpec spec = parse_problem(text, "/data/case/problem.json");
  EXPECT_EQ(spec.file, "/data/case/problem.json");
  EXPECT_EQ(spec.mesh_path, "/data/case/sphere.msh");
  EXPECT_EQ(*spec.E, 1000.0);
  EXPECT_EQ(*spec.nu, 0.3);
  EXPECT_FALSE(spec.lambda || spec.mu);
  ASSERT_EQ(spec.interior_points.size(), 2u);
  EXPECT_EQ(spec.interior_points[1], (Vec3{0.5, -1, 2e-3}));
  EXPECT_EQ(spec.output, "out/result.h5");
  EXPECT_TRUE(spec.rules.empty());
}

TEST(ProblemFile, InteriorGrid)
{
  const ProblemSpec spec = parse_problem(k_head + R"("interior_points": {"points": [[0.5, 0.5, 0.5]],
      "grid": {"box": [[0, -1, 2], [1, 1, 3]], "cells": [2, 4, 1]}}})", "p.json");
  ASSERT_EQ(spec.interior_points.size(), 1u);
  ASSERT_TRUE(spec.interior_grid);
  const InteriorGrid &g = *spec.interior_grid;
  EXPECT_EQ(g.num_points(), 3 * 5 * 2);
  EXPECT_EQ(g.spacing(), (Vec3{0.5, 0.5, 1.0}));
  const std::vector<Vec3> p = g.points();
  ASSERT_EQ(p.size(), 30u);
  EXPECT_EQ(p[0], (Vec3{0, -1, 2}));
  EXPECT_EQ(p[1], (Vec3{0.5, -1, 2})); // x fastest, then y, then z
  EXPECT_EQ(p[3], (Vec3{0, -0.5, 2}));
  EXPECT_EQ(p[29], (Vec3{1, 1, 3}));
  const ProblemSpec only = parse_problem(k_head + R"("interior_points": {"grid": {"box": [[0, 0, 0], [1, 1, 1]], "cells": [1, 1, 1]}}})", "p.json");
  EXPECT_TRUE(only.interior_points.empty());
  EXPECT_EQ(only.interior_grid->num_points(), 8);
  EXPECT_FALSE(parse_problem(k_head + R"("interior_points": []})", "p.json").interior_grid);
}

TEST(ProblemFile, MalformedGridsAreRefused)
{
  auto grid = [](const std::string &g) { return k_head + R"("interior_points": {"grid": )" + g + "}}"; };
  expect_parse_error(grid(R"({"box": [[0, 0, 0], [1, 1, 1]], "cells": [4, 0, 4]})"), {"interior_points.grid.cells[1]", "between 1 and 100000, got 0"});
  expect_parse_error(grid(R"({"box": [[0, 0, 0], [1, 1, 1]], "cells": [4, -2, 4]})"), {"interior_points.grid.cells[1]", "got -2"});
  expect_parse_error(grid(R"({"box": [[0, 0, 1], [1, 1, 0]], "cells": [4, 4, 4]})"), {"interior_points.grid.box", "upper corner must exceed", "component 2"});
  expect_parse_error(grid(R"({"box": [[0, 0, 0], [0, 1, 1]], "cells": [4, 4, 4]})"), {"interior_points.grid.box", "component 0"});
  expect_parse_error(grid(R"({"box": [[0, 0, 0], [1, 1, 1]], "cells": [4, 4.5, 4]})"), {"cells[1]", "whole number of cells, got 4.5"});
  expect_parse_error(grid(R"({"box": [[0, 0, 0], [1, 1, 1]], "cells": [4, "4", 4]})"), {"cells[1]", "got string"});
  expect_parse_error(grid(R"({"box": [[0, 0, 0], [1, 1, 1]], "cells": 4})"), {"interior_points.grid.cells", "[nx, ny, nz]"});
  expect_parse_error(grid(R"({"box": [[0, 0, 0]], "cells": [4, 4, 4]})"), {"interior_points.grid.box", "[[xlo, ylo, zlo], [xhi, yhi, zhi]]"});
  expect_parse_error(grid(R"({"box": [[0, 0, 0], [1, 1, "a"]], "cells": [4, 4, 4]})"), {"interior_points.grid.box[1][2]"});
  expect_parse_error(grid(R"({"cells": [4, 4, 4]})"), {"interior_points.grid", "\"box\""});
  expect_parse_error(grid(R"({"box": [[0, 0, 0], [1, 1, 1]], "cells": [4, 4, 4], "size": 1})"), {"unknown key 'size'"});
  expect_parse_error(grid(R"({"box": [[0, 0, 0], [1, 1, 1]], "cells": [400, 400, 400]})"), {"interior_points.grid", "64481201 points, more than 50000000"});
  expect_parse_error(grid("[1, 2]"), {"interior_points.grid", "expected an object"});
  expect_parse_error(k_head + R"("interior_points": {}})", {"interior_points", "expected a list of points"});
  expect_parse_error(k_head + R"("interior_points": {"points": []}})", {"interior_points.points", "non-empty list"});
  expect_parse_error(k_head + R"("interior_points": 3})", {"interior_points", "expected an object"});
}

TEST(ProblemFile, MeshPathResolution)
{
  const std::string lame = R"(, "material": {"lambda": 5, "mu": 2}})";
  EXPECT_EQ(parse_problem(R"({"mesh": "m.msh")" + lame, "problem.json").mesh_path, "m.msh");
  EXPECT_EQ(parse_problem(R"({"mesh": "../m.msh")" + lame, "a/b.json").mesh_path, "a/../m.msh");
  EXPECT_EQ(parse_problem(R"({"mesh": "/abs/m.msh")" + lame, "a/b.json").mesh_path, "/abs/m.msh");
  const ProblemSpec spec = parse_problem(R"({"mesh": "m.msh")" + lame, "p.json");
  EXPECT_EQ(*spec.lambda, 5.0);
  EXPECT_EQ(*spec.mu, 2.0);
  EXPECT_FALSE(spec.E || spec.nu);
  EXPECT_TRUE(spec.output.empty());
  EXPECT_TRUE(spec.interior_points.empty());
}

TEST(ProblemFile, Selectors)
{
  const auto rules = rules_of(R"([
    {"where": "all", "traction": [0, 0, 0]},
    {"where": {"region": "clamp"}, "traction": [0, 0, 0]},
    {"where": {"region": 7}, "traction": [0, 0, 0]},
    {"where": {"box": [[-1, -2, 0.9], [1, 2, 3]]}, "traction": [0, 0, 0]},
    {"where": {"sphere": {"center": [0, 0, 1], "radius": 0.3}}, "traction": [0, 0, 0]},
    {"where": {"vertices": [0, 5, 9]}, "traction": [0, 0, 0]}
  ])");
  ASSERT_EQ(rules.size(), 6u);
  EXPECT_EQ(rules[0].where.kind, Selector::Kind::All);
  EXPECT_EQ(rules[1].where.kind, Selector::Kind::Region);
  EXPECT_EQ(rules[1].where.region_name, "clamp");
  EXPECT_EQ(rules[2].where.kind, Selector::Kind::Region);
  EXPECT_TRUE(rules[2].where.region_name.empty());
  EXPECT_EQ(rules[2].where.region_tag, 7);
  EXPECT_EQ(rules[3].where.kind, Selector::Kind::Box);
  EXPECT_EQ(rules[3].where.lo, (Vec3{-1, -2, 0.9}));
  EXPECT_EQ(rules[3].where.hi, (Vec3{1, 2, 3}));
  EXPECT_EQ(rules[4].where.kind, Selector::Kind::Sphere);
  EXPECT_EQ(rules[4].where.center, (Vec3{0, 0, 1}));
  EXPECT_EQ(rules[4].where.radius, 0.3);
  EXPECT_EQ(rules[5].where.kind, Selector::Kind::Vertices);
  EXPECT_EQ(rules[5].where.vertices, (std::vector<int>{0, 5, 9}));
}

TEST(ProblemFile, ValueForms)
{
  const auto rules = rules_of(R"([
    {"where": "all", "displacement": [0, null, -0.05]},
    {"where": "all", "traction": [[1, 0, 0], [null, 1, 0], [0, 0, 1]]},
    {"where": "all", "pressure": 100},
    {"where": "all", "pressure": [1, null, 3.5]}
  ])");
  ASSERT_EQ(rules.size(), 4u);
  EXPECT_EQ(rules[0].kind, BoundaryRule::Kind::Displacement);
  ASSERT_EQ(rules[0].rows.size(), 1u);
  EXPECT_EQ(rules[0].rows[0][0], 0.0);
  EXPECT_TRUE(std::isnan(rules[0].rows[0][1]));
  EXPECT_EQ(rules[0].rows[0][2], -0.05);
  EXPECT_EQ(rules[1].kind, BoundaryRule::Kind::Traction);
  ASSERT_EQ(rules[1].rows.size(), 3u);
  EXPECT_TRUE(std::isnan(rules[1].rows[1][0]));
  EXPECT_EQ(rules[1].rows[2], (Vec3{0, 0, 1}));
  EXPECT_EQ(rules[2].kind, BoundaryRule::Kind::Pressure);
  EXPECT_EQ(rules[2].pressure, std::vector<double>{100});
  ASSERT_EQ(rules[3].pressure.size(), 3u);
  EXPECT_TRUE(std::isnan(rules[3].pressure[1]));
  EXPECT_EQ(rules[3].pressure[2], 3.5);
}

TEST(ProblemFile, ReadFromDisk)
{
  const std::string path = testing::TempDir() + "hssbem_test_problem.json";
  {
    std::ofstream out(path);
    out << R"({"mesh": "cube.msh", "material": {"E": 1, "nu": 0}})";
  }
  const ProblemSpec spec = read_problem(path);
  EXPECT_EQ(spec.file, path);
  EXPECT_EQ(spec.mesh_path, testing::TempDir() + "cube.msh");
  std::remove(path.c_str());
  expect_error([&] { read_problem(path); }, {"cannot open problem file", path.c_str()});
}

// ---- applying rules --------------------------------------------------------------------------

TEST(BoundaryRules, DefaultIsTractionFree)
{
  const VertexConditions vc = apply_text("[]");
  ASSERT_EQ(vc.value.size(), 8u);
  for (int v = 0; v < 8; ++v) {
    EXPECT_EQ(vc.displacement_prescribed[v], (std::array<bool, 3>{false, false, false}));
    EXPECT_EQ(vc.value[v], (Vec3{0, 0, 0}));
    EXPECT_TRUE(std::isnan(vc.pressure[v]));
  }
}

TEST(BoundaryRules, RegionByNameAndTag)
{
  const VertexConditions by_name = apply_text(R"([{"where": {"region": "base"}, "displacement": [0, 0, 0]}])");
  const VertexConditions by_tag = apply_text(R"([{"where": {"region": 1}, "displacement": [0, 0, 0]}])");
  for (int v = 0; v < 8; ++v) {
    const bool base = v < 4; // z = 0
    EXPECT_EQ(by_name.displacement_prescribed[v][2], base) << v;
    EXPECT_EQ(by_tag.displacement_prescribed[v], by_name.displacement_prescribed[v]) << v;
  }
}

TEST(BoundaryRules, BoxAndSphereAreInclusive)
{
  // box face at z = 1 and sphere surface through vertex 7 = (1,1,1) both touch vertices exactly
  const VertexConditions vc = apply_text(R"([
    {"where": {"box": [[0, 0, 1], [1, 1, 1]]}, "displacement": [1, null, null]},
    {"where": {"sphere": {"center": [1, 1, 2], "radius": 1}}, "displacement": [null, 2, null]}
  ])");
  for (int v = 0; v < 8; ++v) {
    EXPECT_EQ(vc.displacement_prescribed[v][0], v >= 4) << v;
    EXPECT_EQ(vc.displacement_prescribed[v][1], v == 7) << v;
  }
  EXPECT_EQ(vc.value[7], (Vec3{1, 2, 0}));
}

TEST(BoundaryRules, GeometricSelectorsSkipUnusedVertices)
{
  const VertexConditions vc = apply_text(R"([
    {"where": {"sphere": {"center": [0.5, 0.5, 0.5], "radius": 10}}, "displacement": [1, 1, 1]}
  ])", true);
  ASSERT_EQ(vc.value.size(), 9u);
  EXPECT_EQ(vc.displacement_prescribed[7][0], true);
  EXPECT_EQ(vc.displacement_prescribed[8][0], false); // the unused centre vertex
}

TEST(BoundaryRules, AllRowsFollowMeshOrderIncludingUnused)
{
  std::string rows;
  for (int v = 0; v < 9; ++v)
    rows += (v ? ", [" : "[") + std::to_string(v) + ", null, " + std::to_string(-v) + "]";
  const VertexConditions vc = apply_text(R"([{"where": "all", "traction": [)" + rows + "]}]", true);
  for (int v = 0; v < 9; ++v) {
    EXPECT_EQ(vc.value[v][0], v);
    EXPECT_EQ(vc.value[v][1], 0.0); // null: traction-free as before
    EXPECT_EQ(vc.value[v][2], -v);
  }
}

TEST(BoundaryRules, VertexRowsFollowAscendingIndex)
{
  const VertexConditions vc = apply_text(R"([
    {"where": {"vertices": [2, 5, 6]}, "displacement": [[1, 1, 1], [2, 2, 2], [3, 3, 3]]},
    {"where": {"vertices": [6, 0]}, "traction": [9, null, null]}
  ])");
  EXPECT_EQ(vc.value[2], (Vec3{1, 1, 1}));
  EXPECT_EQ(vc.value[5], (Vec3{2, 2, 2}));
  EXPECT_EQ(vc.value[6], (Vec3{9, 3, 3}));
  EXPECT_EQ(vc.value[0], (Vec3{9, 0, 0}));
  EXPECT_EQ(vc.displacement_prescribed[6], (std::array<bool, 3>{false, true, true}));
}

TEST(BoundaryRules, LaterRulesWinPerComponentAndNullKeeps)
{
  const VertexConditions vc = apply_text(R"([
    {"where": "all", "displacement": [0, 0, 0]},
    {"where": {"box": [[0, 0, 1], [1, 1, 1]]}, "traction": [null, 5, null]},
    {"where": {"vertices": [7]}, "displacement": [null, null, -0.05]}
  ])");
  // vertex 0 is not on top: all three displacements from rule 0
  EXPECT_EQ(vc.displacement_prescribed[0], (std::array<bool, 3>{true, true, true}));
  // vertex 7: x from rule 0, y from rule 1 (traction), z from rule 2
  EXPECT_EQ(vc.displacement_prescribed[7], (std::array<bool, 3>{true, false, true}));
  EXPECT_EQ(vc.value[7], (Vec3{0, 5, -0.05}));
}

TEST(BoundaryRules, PressureFlagsAndOverride)
{
  const VertexConditions vc = apply_text(R"([
    {"where": "all", "displacement": [1, 1, 1]},
    {"where": {"region": "body"}, "pressure": 100},
    {"where": {"vertices": [4]}, "displacement": [null, null, 0]},
    {"where": {"vertices": [5]}, "displacement": [0, 0, 0]},
    {"where": {"vertices": [6, 7]}, "pressure": [null, 7]}
  ])");
  EXPECT_EQ(vc.from_pressure[4], (std::array<bool, 3>{true, true, false}));
  EXPECT_EQ(vc.displacement_prescribed[4], (std::array<bool, 3>{false, false, true}));
  EXPECT_EQ(vc.pressure[4], 100.0);
  EXPECT_TRUE(std::isnan(vc.pressure[5])); // no component left to pressure
  EXPECT_EQ(vc.pressure[6], 100.0);        // null in the list: kept
  EXPECT_EQ(vc.pressure[7], 7.0);
  EXPECT_EQ(vc.from_pressure[7], (std::array<bool, 3>{true, true, true}));
}

TEST(BoundaryRules, BulkRowsForHundredThousandVertices)
{
  const int nx = 400, ny = 250, n = nx * ny; // flat grid: enough for selection and rows
  SurfaceMesh mesh;
  mesh.vertices.reserve(n);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      mesh.vertices.push_back({double(i), double(j), 0});
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      const int a = j * nx + i;
      mesh.triangles.push_back({a, a + 1, a + nx + 1});
      mesh.triangles.push_back({a, a + nx + 1, a + nx});
    }
  std::string text = k_head + R"("boundary": [{"where": "all", "displacement": [)";
  text.reserve(text.size() + 40 * std::size_t(n));
  for (int v = 0; v < n; ++v)
    text += (v ? ",[" : "[") + std::to_string(v % 7 * 0.001) + (v % 3 ? ",null," : ",0,") +
            std::to_string(-v) + "]";
  text += "]}]}";
  const ProblemSpec spec = parse_problem(text, "bulk.json");
  ASSERT_EQ(spec.rules.at(0).rows.size(), std::size_t(n));
  const VertexConditions vc = apply_rules(spec.rules, mesh, spec.file);
  for (int v : {0, 1, 2, 3, 12345, n - 1}) {
    EXPECT_EQ(vc.displacement_prescribed[v], (std::array<bool, 3>{true, v % 3 == 0, true})) << v;
    EXPECT_NEAR(vc.value[v][0], v % 7 * 0.001, 1e-12);
    EXPECT_EQ(vc.value[v][2], -v);
  }
}

// ---- node conditions -------------------------------------------------------------------------

TEST(NodeConditions, PressureIsMinusPTimesGroupNormal)
{
  const SurfaceMesh mesh = unit_cube();
  const Discretization disc(mesh, 30.0);
  ASSERT_EQ(disc.num_nodes(), 24); // every cube corner has three smooth groups
  const VertexConditions vc = apply_rules(rules_of(R"([
    {"where": "all", "pressure": 100},
    {"where": {"region": "base"}, "displacement": [null, null, 0]}
  ])"), mesh, "problem.json");
  const NodeConditions nc = node_conditions(vc, disc);
  ASSERT_EQ(nc.value.size(), 24u);
  const Vec3 centre{0.5, 0.5, 0.5};
  for (int i = 0; i < disc.num_nodes(); ++i) {
    const DofNode &node = disc.node(i);
    EXPECT_NEAR(norm(node.normal), 1.0, 1e-12);
    EXPECT_GT(dot(node.normal, mesh.vertices[node.vertex] - centre), 0); // outward
    const bool base = node.vertex < 4;
    EXPECT_EQ(nc.displacement_prescribed[i], (std::array<bool, 3>{false, false, base}));
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(nc.value[i][c], (base && c == 2) ? 0.0 : -100.0 * node.normal[c], 1e-12);
  }
  EXPECT_EQ(nc.num_displacement_prescribed(), 4 * 3); // 4 base vertices x 3 nodes, z only
}

// ---- errors ----------------------------------------------------------------------------------

TEST(ProblemErrors, Selection)
{
  expect_apply_error(R"([{"where": "all", "traction": [0, 0, 0]},
    {"where": {"box": [[5, 5, 5], [6, 6, 6]]}, "displacement": [0, 0, 0]}])",
                     {"problem.json: boundary[1]: selects no vertex"});
  expect_apply_error(R"([{"where": {"region": "base"}, "displacement": [[0,0,0],[0,0,0],[0,0,0]]}])",
                     {"boundary[0]", "'displacement' has 3 rows but the selection has 4 vertices"});
  expect_apply_error(R"([{"where": "all", "pressure": [1, 2]}])",
                     {"boundary[0]", "'pressure' has 2 values but the selection has 9 vertices"});
  expect_apply_error(R"([{"where": {"vertices": [1200]}, "traction": [0, 0, 0]}])",
                     {"boundary[0]", "vertex index 1200 out of range (mesh has 9 vertices)"});
  expect_apply_error(R"([{"where": {"region": "clmap"}, "traction": [0, 0, 0]}])",
                     {"boundary[0]", "unknown region 'clmap' (known: base, body)"});
  expect_apply_error(R"([{"where": {"region": 7}, "traction": [0, 0, 0]}])",
                     {"boundary[0]", "unknown region 7"});
  expect_apply_error(R"([{"where": {"vertices": [3, 3]}, "traction": [0, 0, 0]}])",
                     {"boundary[0]", "vertex index 3 listed twice"});
  expect_apply_error(R"([{"where": {"vertices": [3, 1]}, "traction": [[0, 0, 0], [1, 1, 1]]}])",
                     {"boundary[0]", "ascending order", "'traction'"});
}

TEST(ProblemErrors, UnknownKeys)
{
  expect_parse_error(k_head + R"("boundry": []})", {"problem.json: ", "unknown key 'boundry'"});
  expect_parse_error(with_rules(R"([{"where": "all", "displacment": [0, 0, 0]}])"),
                     {"boundary[0]", "unknown key 'displacment'"});
  expect_parse_error(with_rules(R"([{"where": {"regoin": "a"}, "traction": [0, 0, 0]}])"),
                     {"boundary[0].where", "unknown key 'regoin'"});
  expect_parse_error(with_rules(R"([{"where": {"sphere": {"centre": [0,0,0], "radius": 1}},
                     "traction": [0, 0, 0]}])"), {"boundary[0].where.sphere", "unknown key 'centre'"});
  expect_parse_error(R"({"mesh": "m", "material": {"E": 1, "nu": 0.3, "G": 2}})",
                     {"material", "unknown key 'G'"});
  expect_parse_error(R"({"mesh": "m", "material": {"E": 1, "nu": 0.3}, "mesh": "n"})",
                     {"duplicate key 'mesh'"});
}

TEST(ProblemErrors, RuleShape)
{
  expect_parse_error(with_rules(R"([{"where": "all"}])"),
                     {"boundary[0]", "needs one of 'displacement', 'traction', 'pressure'"});
  expect_parse_error(with_rules(R"([{"where": "all", "traction": [0,0,0], "pressure": 1}])"),
                     {"boundary[0]", "more than one of"});
  expect_parse_error(with_rules(R"([{"traction": [0, 0, 0]}])"), {"boundary[0]", "missing 'where'"});
  expect_parse_error(with_rules(R"([{"where": "everything", "traction": [0, 0, 0]}])"),
                     {"boundary[0].where", "unknown selector 'everything'"});
  expect_parse_error(with_rules(R"([{"where": {"box": [[0,0,0],[1,1,1]], "vertices": [1]},
                     "traction": [0, 0, 0]}])"), {"boundary[0].where", "exactly one of"});
}

TEST(ProblemErrors, WrongTypes)
{
  expect_parse_error(R"({"mesh": 5, "material": {"E": 1, "nu": 0.3}})", {"mesh", "non-empty string"});
  expect_parse_error(k_head + R"("boundary": {}})", {"boundary", "list of rules"});
  expect_parse_error(with_rules(R"([{"where": "all", "displacement": "zero"}])"),
                     {"boundary[0].displacement", "expected [x, y, z]"});
  expect_parse_error(with_rules(R"([{"where": "all", "traction": [[0,0,0], [0,"1",0]]}])"),
                     {"boundary[0].traction[1][1]", "expected a number or null, got string"});
  expect_parse_error(with_rules(R"([{"where": "all", "traction": [[0,0,0], [0,0]]}])"),
                     {"boundary[0].traction[1]", "expected 3 components, got 2"});
  expect_parse_error(with_rules(R"([{"where": "all", "pressure": "high"}])"),
                     {"boundary[0].pressure", "expected a number"});
  expect_parse_error(with_rules(R"([{"where": {"vertices": [1.5]}, "traction": [0,0,0]}])"),
                     {"boundary[0].where.vertices[0]", "expected an integer vertex index"});
  expect_parse_error(with_rules(R"([{"where": {"vertices": [-2]}, "traction": [0,0,0]}])"),
                     {"boundary[0].where.vertices[0]", "vertex index -2 is negative"});
  expect_parse_error(with_rules(R"([{"where": {"box": [[0,0,0]]}, "traction": [0,0,0]}])"),
                     {"boundary[0].where.box", "expected [[xlo, ylo, zlo], [xhi, yhi, zhi]]"});
  expect_parse_error(with_rules(R"([{"where": {"box": [[0,0,2],[1,1,1]]}, "traction": [0,0,0]}])"),
                     {"boundary[0].where.box", "lower corner exceeds upper corner"});
  expect_parse_error(with_rules(R"([{"where": {"sphere": {"center": [0,0,0], "radius": -1}},
                     "traction": [0,0,0]}])"), {"sphere.radius", "negative"});
  expect_parse_error(with_rules(R"([{"where": {"region": true}, "traction": [0,0,0]}])"),
                     {"boundary[0].where.region", "region name or a physical tag"});
  expect_parse_error(k_head + R"("interior_points": [0, 0, 0]})",
                     {"interior_points[0]", "expected a 3-vector"});
  expect_parse_error(k_head + R"("interior_points": [[0, null, 0]]})",
                     {"interior_points[0][1]", "expected a number, got null"});
  expect_parse_error("[1, 2]", {"problem.json: expected an object, got array"});
}

TEST(ProblemErrors, MissingAndMaterial)
{
  expect_parse_error(R"({"material": {"E": 1, "nu": 0.3}})", {"problem.json", "missing 'mesh'"});
  expect_parse_error(R"({"mesh": "m"})", {"problem.json", "missing 'material'"});
  expect_parse_error(R"({"mesh": "m", "material": {"E": 1, "nu": 0.3, "mu": 1}})",
                     {"material", "not both"});
  expect_parse_error(R"({"mesh": "m", "material": {"E": 1}})", {"material", "'E' given without 'nu'"});
  expect_parse_error(R"({"mesh": "m", "material": {"mu": 1}})",
                     {"material", "'mu' given without 'lambda'"});
  expect_parse_error(R"({"mesh": "m", "material": {}})", {"material", "expected {\"E\""});
  expect_parse_error(R"({"mesh": "m", "material": {"E": "1", "nu": 0.3}})",
                     {"material.E", "expected a number, got string"});
}

TEST(ProblemErrors, ValuesBeyondWhatTheSolveCarries)
{
  // A pressure of 1e300 gave a NaN residual: values beyond 1e30 are refused naming the rule.
  expect_parse_error(with_rules(R"([{"where": "all", "pressure": 1e300}])"), {"problem.json: boundary[0].pressure: value 1e+300 exceeds 1e+30"});
  expect_parse_error(with_rules(R"([{"where": "all", "traction": [0, -2e31, 0]}])"), {"boundary[0].traction: value -2e+31 exceeds"});
  expect_parse_error(with_rules(R"([{"where": "all", "displacement": [[0, 0, 1e40]]}])"), {"boundary[0].displacement: value 1e+40"});
  EXPECT_NO_THROW(rules_of(R"([{"where": "all", "pressure": 1e30}, {"where": {"box": [[-1e300, -1e300, -1e300], [1e300, 1e300, 1e300]]}, "traction": [0, 0, 0]}])"));
}

TEST(ProblemErrors, MalformedJsonAndNonFinite)
{
  expect_parse_error("{\"mesh\": \"m\",\n \"material\": }", {"problem.json", "malformed JSON", "line 2"});
  expect_parse_error("{\"mesh\": \"m\"", {"malformed JSON", "byte"});
  expect_parse_error(with_rules(R"([{"where": "all", "pressure": 1e999}])"),
                     {"problem.json", "malformed JSON", "1e999", "finite"});
  expect_parse_error(with_rules(R"([{"where": "all", "pressure": NaN}])"), {"malformed JSON"});
}

// ---- frames of a scene -----------------------------------------------------------------------

namespace {

/// Base rules: the base (z = 0) clamped, the top (z = 1) loaded with traction [0, 0, -1].
const std::string k_base_rules = R"([
  {"where": {"region": "base"}, "displacement": [0, 0, 0]},
  {"where": {"box": [[0, 0, 1], [1, 1, 1]]}, "traction": [0, 0, -1]}
])";

/// A problem with the base rules above and the given "frames" value.
ProblemSpec with_frames(const std::string &frames)
{
  return parse_problem(k_head + "\"boundary\": " + k_base_rules + ", \"frames\": " + frames + "}", "problem.json");
}

void expect_frame_error(const std::string &frames, std::initializer_list<const char *> words)
{
  expect_error([&] { with_frames(frames); }, words);
}

/// Runs f on every dof node of vertex v.
template <class F> void for_nodes_of(const Discretization &disc, int v, F f)
{
  for (int i = disc.first_node(v); i < disc.first_node(v) + disc.node_count(v); ++i)
    f(i);
}

} // namespace

TEST(Frames, AbsentKeyIsASingleSolve)
{
  EXPECT_TRUE(parse_problem(with_rules(k_base_rules), "problem.json").frames.empty());
}

TEST(Frames, ParseRulesWithTheBoundaryGrammar)
{
  const ProblemSpec spec = with_frames(R"([
    {"boundary": []},
    {"boundary": [{"where": {"vertices": [4, 5]}, "displacement": [[null, null, -0.01], [null, null, -0.02]]},
                  {"where": "all", "pressure": 3}]},
    {"boundary": [{"where": {"sphere": {"center": [1, 1, 1], "radius": 0.1}}, "traction": [1, null, null]}]}
  ])");
  ASSERT_EQ(spec.rules.size(), 2u);
  ASSERT_EQ(spec.frames.size(), 3u);
  EXPECT_TRUE(spec.frames[0].rules.empty());
  ASSERT_EQ(spec.frames[1].rules.size(), 2u);
  const BoundaryRule &bulk = spec.frames[1].rules[0];
  EXPECT_EQ(bulk.kind, BoundaryRule::Kind::Displacement);
  EXPECT_EQ(bulk.where.kind, Selector::Kind::Vertices);
  ASSERT_EQ(bulk.rows.size(), 2u);
  EXPECT_TRUE(std::isnan(bulk.rows[1][0]));
  EXPECT_EQ(bulk.rows[1][2], -0.02);
  EXPECT_EQ(spec.frames[1].rules[1].kind, BoundaryRule::Kind::Pressure);
  EXPECT_EQ(spec.frames[2].rules.at(0).where.kind, Selector::Kind::Sphere);
  EXPECT_EQ(spec.frames[2].rules.at(0).kind, BoundaryRule::Kind::Traction);
}

TEST(Frames, ParseErrorsNameTheFrame)
{
  expect_frame_error(R"({"boundary": []})", {"problem.json: frames: expected a non-empty list of frames", "got object"});
  expect_frame_error("[]", {"problem.json: frames: expected a non-empty list of frames", "got []"});
  expect_frame_error(R"([{"boundary": []}, [1]])", {"frames[1]: expected an object, got array"});
  expect_frame_error(R"([{"boundary": [], "time": 0.5}])", {"frames[0]: unknown key 'time' (known: boundary, obstacles)"});
  expect_frame_error(R"([{}])", {"frames[0]: missing 'boundary'"});
  expect_frame_error(R"([{"boundary": {}}])", {"frames[0].boundary: expected a list of rules, got object"});
  expect_frame_error(R"([{"boundary": []}, {"boundary": []}, {"boundary": []},
    {"boundary": [{"where": "all", "traction": [0, 0, 0]}, {"where": "everywhere", "traction": [0, 0, 0]}]}])",
                     {"problem.json: frames[3].boundary[1].where: unknown selector 'everywhere'"});
  expect_frame_error(R"([{"boundary": [{"where": "all", "displacment": [0, 0, 0]}]}])",
                     {"frames[0].boundary[0]: unknown key 'displacment'"});
  expect_frame_error(R"([{"boundary": [{"where": "all", "traction": [[0, 0, 0], [0, "1", 0]]}]}])",
                     {"frames[0].boundary[0].traction[1][1]: expected a number or null, got string"});
  expect_frame_error(R"([{"boundary": []}, {"boundary": []}], "frames": [])", {"duplicate key 'frames'"});
}

TEST(Frames, EmptyFrameIsTheBaseProblem)
{
  const SurfaceMesh mesh = unit_cube();
  const Discretization disc(mesh, 30.0);
  const ProblemSpec spec = with_frames(R"([{"boundary": []}])");
  const NodeConditions base = apply_rules(spec.rules, disc, spec.file);
  const NodeConditions frame = frame_conditions(spec, 0, disc);
  EXPECT_EQ(frame.displacement_prescribed, base.displacement_prescribed);
  EXPECT_EQ(frame.value, base.value);
  EXPECT_EQ(frame.num_displacement_prescribed(), 4 * 3 * 3); // 4 base corners x 3 nodes x 3
}

TEST(Frames, FrameRulesFollowTheBaseRules)
{
  const SurfaceMesh mesh = unit_cube();
  const Discretization disc(mesh, 30.0);
  // frame 0 switches the top's z from traction to displacement, per vertex; frame 1 gives
  // vertex 7 an x traction and leaves y and z (nulls) as the base has them
  const ProblemSpec spec = with_frames(R"([
    {"boundary": [{"where": {"vertices": [4, 5, 6, 7]},
                   "displacement": [[null, null, -0.04], [null, null, -0.05], [null, null, -0.06], [null, null, -0.07]]}]},
    {"boundary": [{"where": {"vertices": [7]}, "traction": [2, null, null]}]}
  ])");
  const NodeConditions switched = frame_conditions(spec, 0, disc);
  const NodeConditions nulls = frame_conditions(spec, 1, disc);
  for (int v = 0; v < 8; ++v)
    for_nodes_of(disc, v, [&](int i) {
      const bool base = v < 4;
      EXPECT_EQ(switched.displacement_prescribed[i], (std::array<bool, 3>{base, base, true})) << v;
      EXPECT_DOUBLE_EQ(switched.value[i][2], base ? 0.0 : -0.01 * v) << v;
      EXPECT_EQ(switched.value[i][0], 0.0) << v; // the base's traction-free x
      EXPECT_EQ(nulls.displacement_prescribed[i], (std::array<bool, 3>{base, base, base})) << v;
      EXPECT_EQ(nulls.value[i], base ? (Vec3{0, 0, 0}) : (Vec3{v == 7 ? 2.0 : 0.0, 0, -1})) << v;
    });
  EXPECT_EQ(switched.num_displacement_prescribed(), 4 * 3 * 3 + 4 * 3);
}

TEST(Frames, FrameRuleSelectingNothingNamesTheFrame)
{
  const SurfaceMesh mesh = unit_cube();
  const Discretization disc(mesh, 30.0);
  const ProblemSpec spec = with_frames(R"([
    {"boundary": []},
    {"boundary": [{"where": "all", "traction": [0, 0, 0]},
                  {"where": {"box": [[5, 5, 5], [6, 6, 6]]}, "displacement": [0, 0, 0]}]}
  ])");
  EXPECT_NO_THROW(frame_conditions(spec, 0, disc));
  expect_error([&] { frame_conditions(spec, 1, disc); }, {"problem.json: frames[1].boundary[1]: selects no vertex"});
  EXPECT_THROW(frame_conditions(spec, 2, disc), std::out_of_range);
}

TEST(Frames, BaseRuleErrorsKeepTheirName)
{
  const SurfaceMesh mesh = unit_cube();
  const Discretization disc(mesh, 30.0);
  const ProblemSpec spec = parse_problem(k_head + R"("boundary": [{"where": {"region": "lid"}, "traction": [0, 0, 0]}],
    "frames": [{"boundary": [{"where": {"region": "lid"}, "traction": [0, 0, 0]}]}]})", "problem.json");
  expect_error([&] { frame_conditions(spec, 0, disc); }, {"problem.json: boundary[0]: unknown region 'lid'"});
  expect_error([&] { apply_rules(spec.frames[0].rules, disc, spec.file, "frames[0].boundary"); },
               {"problem.json: frames[0].boundary[0]: unknown region 'lid'"});
}

TEST(Frames, ObstacleTurnsParse)
{
  const std::string contact = R"("contact": {"obstacles": [{"name": "tool", "sphere": {"center": [0, 0, 2], "radius": 0.5}}]}, "frames": )";
  const auto parse = [&](const std::string &frames) { return parse_problem(k_head + "\"boundary\": " + k_base_rules + ", " + contact + frames + "}", "problem.json"); };
  const ProblemSpec spec = parse(R"([{"obstacles": {"tool": {"translate": [0.1, 0, 0], "rotate": {"axis": [0, 1, 0], "angle": 30, "about": [0, 0, 1]}}}},
                                     {"obstacles": {"tool": {"rotate": {"axis": [0, 0, 2], "angle": -90}}}}, {"obstacles": {"tool": {"translate": [0, 0, -0.1]}}}])");
  ASSERT_EQ(spec.frames.size(), 3u);
  EXPECT_EQ(spec.frames[0].obstacles.at(0).second, (Vec3{0.1, 0, 0}));
  const ObstacleTurn &t0 = spec.frames[0].turns.at("tool");
  EXPECT_EQ(t0.axis, (Vec3{0, 1, 0}));
  EXPECT_EQ(t0.angle_deg, 30);
  ASSERT_TRUE(t0.about.has_value());
  EXPECT_EQ(*t0.about, (Vec3{0, 0, 1}));
  EXPECT_EQ(spec.frames[1].obstacles.at(0).second, (Vec3{0, 0, 0})); // rotate alone: no translation
  EXPECT_FALSE(spec.frames[1].turns.at("tool").about.has_value());    // the obstacle's default centre
  EXPECT_TRUE(spec.frames[2].turns.empty());
  const auto error = [&](const std::string &frames, std::initializer_list<const char *> words) { expect_error([&] { parse(frames); }, words); };
  error(R"([{"obstacles": {"tool": {"rotate": {"axis": [0, 0, 0], "angle": 10}}}}])", {"problem.json: frames[0].obstacles.tool.rotate.axis: the rotation axis is zero"});
  error(R"([{"obstacles": {"tool": {"rotate": {"axis": [0, 0, 1]}}}}])", {"frames[0].obstacles.tool.rotate: missing 'axis' or 'angle'"});
  error(R"([{"obstacles": {"tool": {"rotate": {"axis": [0, 0, 1], "angle": "10"}}}}])", {"frames[0].obstacles.tool.rotate.angle: expected a number, got string"});
  error(R"([{"obstacles": {"tool": {"rotate": {"axis": [0, 0, 1], "angle": 10, "centre": [0, 0, 0]}}}}])", {"rotate: unknown key 'centre' (known: axis, angle, about)"});
  error(R"([{"obstacles": {"tool": {}}}])", {"frames[0].obstacles.tool: missing 'translate' or 'rotate'"});
}

// ---- material --------------------------------------------------------------------------------

TEST(Material, YoungValidation)
{
  const Material m = Material::from_young(1000, 0.49);
  EXPECT_EQ(m.E, 1000);
  EXPECT_EQ(m.nu, 0.49);
  EXPECT_NO_THROW(Material::from_young(1, -0.99));
  const auto message = [](double E, double nu) {
    try {
      Material::from_young(E, nu);
    } catch (const std::invalid_argument &e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(message(1, 0.5),
            "invalid material: nu = 0.5 must satisfy -1 < nu < 0.5 (nu = 0.5 is incompressible, not supported)");
  EXPECT_EQ(message(1, -1), "invalid material: nu = -1 must satisfy -1 < nu < 0.5");
  EXPECT_NE(message(0, 0.3).find("E = 0 must be positive"), std::string::npos);
  EXPECT_NE(message(-5, 0.3).find("E = -5"), std::string::npos);
  EXPECT_NE(message(1, NAN).find("nu = nan"), std::string::npos);
  // Moduli the arithmetic carries (E = 1e-300 gave a NaN residual): within 1e-30 .. 1e30.
  EXPECT_NE(message(1e-300, 0.3).find("E = 1e-300 lies outside [1e-30, 1e30]"), std::string::npos);
  EXPECT_NE(message(1e31, 0.3).find("lies outside"), std::string::npos);
  EXPECT_EQ(message(1e-30, 0.3), "accepted");
  EXPECT_EQ(message(1e30, 0.3), "accepted");
}

TEST(Material, LameRoundTrip)
{
  const Material m = Material::from_young(1000, 0.3);
  const Material back = Material::from_lame(m.lambda(), m.mu());
  EXPECT_NEAR(back.E, 1000, 1e-9);
  EXPECT_NEAR(back.nu, 0.3, 1e-14);
  const Material l = Material::from_lame(0, 2); // lambda = 0: nu = 0, E = 2 mu
  EXPECT_EQ(l.nu, 0);
  EXPECT_EQ(l.E, 4);
  EXPECT_THROW(Material::from_lame(1, 0), std::invalid_argument);
  EXPECT_THROW(Material::from_lame(-1, 1), std::invalid_argument); // nu = -1
  EXPECT_THROW(Material::from_lame(1e20, 1), std::invalid_argument); // nu rounds to 0.5
}

// ---- a scene validated whole before its first frame ------------------------------------------

namespace {

/// The unit cube written as an OFF file in the temporary directory; returns its path.
std::string cube_file()
{
  const std::string path = (std::getenv("TMPDIR") ? std::string(std::getenv("TMPDIR")) : std::string("/tmp")) + "/hssbem_test_problem_cube.off";
  const SurfaceMesh m    = unit_cube();
  std::ofstream     f(path);
  f << "OFF\n" << m.num_vertices() << " " << m.num_triangles() << " 0\n";
  for (const Vec3 &x : m.vertices) f << x[0] << " " << x[1] << " " << x[2] << "\n";
  for (const auto &t : m.triangles) f << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
  return path;
}

/// A scene on the cube: 40 frames pushing vertex 7 (the base clamped), frame `bad` replaced.
ProblemSpec forty_frames(int bad, const std::string &bad_frame)
{
  std::string frames = "[";
  for (int i = 0; i < 40; ++i)
    frames += std::string(i ? ", " : "") + (i == bad ? bad_frame : R"({"boundary": [{"where": {"vertices": [7]}, "displacement": [0, 0, -0.01]}]})");
  const std::string base = R"([{"where": {"box": [[0, 0, 0], [1, 1, 0]]}, "displacement": [0, 0, 0]}])"; // the OFF file has no regions
  ProblemSpec       spec = parse_problem(k_head + "\"boundary\": " + base + ", \"frames\": " + frames + "]}", "problem.json");
  spec.mesh_path         = cube_file();
  return spec;
}

} // namespace

TEST(SceneSetup, EveryFrameIsCheckedBeforeTheFirstIsSolved)
{
  // Before: frames[39]'s vertex out of range was found after 39 frames had been solved.
  expect_error([] { setup_problem(forty_frames(39, R"({"boundary": [{"where": {"vertices": [100]}, "displacement": [0, 0, 0]}]})"), {}); },
               {"problem.json: frames[39].boundary[0]", "100"});
  try { // a frame that frees the body: the base's clamp replaced by tractions
    setup_problem(forty_frames(12, R"({"boundary": [{"where": {"box": [[0, 0, 0], [1, 1, 0]]}, "traction": [0, 0, 0]}]})"), {});
    ADD_FAILURE() << "no ConstraintError";
  } catch (const ConstraintError &e) {
    EXPECT_NE(std::string(e.what()).find("frames[12]: the prescribed displacements leave the body free to move"), std::string::npos) << e.what();
  }
  const ProblemSetup s = setup_problem(forty_frames(-1, ""), {});
  EXPECT_EQ(s.spec.frames.size(), 40u);
  EXPECT_EQ(s.input_files, (std::vector<std::string>{"problem.json", cube_file()}));
}
