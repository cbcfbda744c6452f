/// \file test_mesh.cpp
/// Mesh readers (.msh 2.2/4.1, STL, OFF, OBJ) and topology validation / orientation.

#include "hssbem/mesh/mesh.hpp"
#include "test_paths.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>

namespace fs = std::filesystem;
using namespace hssbem;

namespace {

using Tri = std::array<int, 3>;

/// Points and triangles, as the tests write them into files.
struct Shape {
  std::vector<Vec3> points;
  std::vector<Tri> tris;
};

/// Axis-aligned cube with outward triangles: corners 0..3 at z = z0 (counter-clockwise from
/// (x0, y0)), 4..7 above them.
Shape cube(double size = 1.0, Vec3 origin = {0, 0, 0})
{
  Shape s;
  for (int k = 0; k < 8; ++k) {
    const double x = (k % 4 == 1 || k % 4 == 2) ? size : 0.0;
    const double y = (k % 4 >= 2) ? size : 0.0;
    s.points.push_back(origin + Vec3{x, y, k >= 4 ? size : 0.0});
  }
  const int quads[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                           {2, 3, 7, 6}, {0, 4, 7, 3}, {1, 2, 6, 5}};
  for (const auto &q : quads) {
    s.tris.push_back({q[0], q[1], q[2]});
    s.tris.push_back({q[0], q[2], q[3]});
  }
  return s;
}

Shape tetrahedron()
{
  return {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}};
}

/// Appends b to a; `shared` maps vertices of b onto existing vertices of a.
Shape merge(Shape a, const Shape &b, const std::map<int, int> &shared = {})
{
  std::vector<int> map(b.points.size());
  for (std::size_t i = 0; i < b.points.size(); ++i) {
    const auto it = shared.find(static_cast<int>(i));
    if (it != shared.end()) {
      map[i] = it->second;
    } else {
      map[i] = static_cast<int>(a.points.size());
      a.points.push_back(b.points[i]);
    }
  }
  for (const Tri &t : b.tris)
    a.tris.push_back({map[t[0]], map[t[1]], map[t[2]]});
  return a;
}

Shape flipped(Shape s)
{
  for (Tri &t : s.tris)
    std::swap(t[1], t[2]);
  return s;
}

SurfaceMesh to_mesh(const Shape &s, const std::string &source = "test")
{
  SurfaceMesh m;
  m.vertices = s.points;
  m.triangles = s.tris;
  m.triangle_region.assign(s.tris.size(), -1);
  m.source = source;
  return m;
}

double signed_volume(const SurfaceMesh &m, const std::vector<int> &tris)
{
  double v = 0;
  for (int t : tris) {
    const auto &x = m.triangles[t];
    v += dot(m.vertices[x[0]], cross(m.vertices[x[1]], m.vertices[x[2]])) / 6.0;
  }
  return v;
}

std::vector<int> range(int lo, int hi)
{
  std::vector<int> r;
  for (int i = lo; i < hi; ++i)
    r.push_back(i);
  return r;
}

// ------------------------------------------------------------------------------ file writers

std::string point_text(const Vec3 &x)
{
  std::ostringstream s;
  s.precision(17);
  s << x[0] << ' ' << x[1] << ' ' << x[2];
  return s.str();
}

std::string stl_ascii(const Shape &s)
{
  std::string out = "solid test\n";
  for (const Tri &t : s.tris) {
    out += "  facet normal 0 0 0\n    outer loop\n";
    for (int v : t)
      out += "      vertex " + point_text(s.points[v]) + "\n";
    out += "    endloop\n  endfacet\n";
  }
  return out + "endsolid test\n";
}

void put_u32(std::string &out, std::uint32_t v)
{
  for (int i = 0; i < 4; ++i)
    out += static_cast<char>((v >> (8 * i)) & 0xff);
}

std::string stl_binary(const Shape &s, const std::string &header = "binary test")
{
  std::string out = header;
  out.resize(80, ' ');
  put_u32(out, static_cast<std::uint32_t>(s.tris.size()));
  for (const Tri &t : s.tris) {
    std::vector<float> values(3, 0.0f);
    for (int v : t)
      for (double c : s.points[v])
        values.push_back(static_cast<float>(c));
    for (float f : values) {
      std::uint32_t bits = 0;
      std::memcpy(&bits, &f, 4);
      put_u32(out, bits);
    }
    out += std::string(2, '\0');
  }
  return out;
}

/// OFF with the cube written as quads.
std::string off_cube_quads()
{
  const Shape c = cube();
  std::string out = "OFF # a comment\n# vertex count, face count, edge count\n8 6 0\n";
  for (const Vec3 &x : c.points)
    out += point_text(x) + "\n";
  for (std::size_t q = 0; q < 6; ++q) {
    const Tri &a = c.tris[2 * q], &b = c.tris[2 * q + 1];
    out += "4 " + std::to_string(a[0]) + " " + std::to_string(a[1]) + " " + std::to_string(a[2]) +
           " " + std::to_string(b[2]) + "  255 0 0\n";
  }
  return out;
}

std::string off_text(const Shape &s)
{
  std::string out = "OFF\n" + std::to_string(s.points.size()) + " " + std::to_string(s.tris.size()) + " 0\n";
  for (const Vec3 &x : s.points)
    out += point_text(x) + "\n";
  for (const Tri &t : s.tris)
    out += "3 " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) + "\n";
  return out;
}

std::string obj_text(const Shape &s)
{
  std::string out = "# written by test_mesh\no shape\n";
  for (const Vec3 &x : s.points)
    out += "v " + point_text(x) + "\n";
  for (const Tri &t : s.tris)
    out += "f " + std::to_string(t[0] + 1) + " " + std::to_string(t[1] + 1) + " " +
           std::to_string(t[2] + 1) + "\n";
  return out;
}

// The cube in .msh form: node tags are not contiguous and not in file order; vertex i of cube()
// gets tag k_cube_tags[i], so after sorting by tag vertex j of the mesh is cube corner
// k_tag_order[j].
const int k_cube_tags[8] = {40, 7, 13, 1000, 2, 99, 15, 8};
const int k_tag_order[8] = {4, 1, 7, 2, 6, 0, 5, 3}; // corners by ascending tag

std::string tri_nodes(const Tri &t)
{
  return std::to_string(k_cube_tags[t[0]]) + " " + std::to_string(k_cube_tags[t[1]]) + " " +
         std::to_string(k_cube_tags[t[2]]);
}

/// Triangles 0-5 in physical group 1 ("bottom part"), 6-11 in group 2 ("top"); a point, a line
/// and a tetrahedron are mixed in and must be ignored.
std::string msh22_cube()
{
  const Shape c = cube();
  std::string out = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n3\n"
                    "2 1 \"bottom part\"\n2 2 \"top\"\n3 5 \"solid\"\n$EndPhysicalNames\n"
                    "$Comments\nanything at all 1 2 3\n$EndComments\n$Nodes\n8\n";
  for (int i = 7; i >= 0; --i)
    out += std::to_string(k_cube_tags[i]) + " " + point_text(c.points[i]) + "\n";
  out += "$EndNodes\n$Elements\n15\n1 15 2 0 1 40\n2 1 2 0 1 40 7\n";
  for (int t = 0; t < 12; ++t)
    out += std::to_string(t + 3) + " 2 2 " + (t < 6 ? "1" : "2") + " 3 " + tri_nodes(c.tris[t]) + "\n";
  return out + "15 4 2 5 1 40 7 13 2\n$EndElements\n";
}

/// Surface entity 3 carries physical tags 7 and 9 (the first counts), entity 4 none.
std::string msh41_cube()
{
  const Shape c = cube();
  std::string out = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n2 7 \"skin\"\n"
                    "1 3 \"wire\"\n$EndPhysicalNames\n$Entities\n1 0 2 1\n"
                    "1 0 0 0 0 \n3 0 0 0 1 1 1 2 7 9 0 \n4 0 0 0 1 1 1 0 0 \n"
                    "1 0 0 0 1 1 1 1 5 2 3 4 \n$EndEntities\n$Nodes\n2 8 2 1000\n"
                    "1 1 0 3\n";
  for (int i : {0, 1, 2})
    out += std::to_string(k_cube_tags[i]) + "\n";
  for (int i : {0, 1, 2})
    out += point_text(c.points[i]) + "\n";
  out += "2 3 1 5\n"; // parametric: two extra coordinates per node
  for (int i = 3; i < 8; ++i)
    out += std::to_string(k_cube_tags[i]) + "\n";
  for (int i = 3; i < 8; ++i)
    out += point_text(c.points[i]) + " 0.5 0.25\n";
  out += "$EndNodes\n$Elements\n3 13 1 20\n0 1 15 1\n1 40\n2 3 2 6\n";
  for (int t = 0; t < 6; ++t)
    out += std::to_string(t + 2) + " " + tri_nodes(c.tris[t]) + "\n";
  out += "2 4 2 6\n";
  for (int t = 6; t < 12; ++t)
    out += std::to_string(t + 2) + " " + tri_nodes(c.tris[t]) + "\n";
  return out + "$EndElements\n";
}

/// Writes test files into a fresh directory removed at the end of the test.
class MeshFiles : public ::testing::Test {
protected:
  void SetUp() override
  {
    const auto *info = ::testing::UnitTest::GetInstance()->current_test_info();
    m_dir = fs::temp_directory_path() /
            ("hssbem_test_mesh_" + std::string(info->name()) + "_" +
             std::to_string(std::chrono::steady_clock::now().time_since_epoch().count()));
    fs::create_directories(m_dir);
  }
  void TearDown() override { fs::remove_all(m_dir); }

  std::string write(const std::string &name, const std::string &content)
  {
    const std::string path = (m_dir / name).string();
    std::ofstream(path, std::ios::binary) << content;
    return path;
  }

  fs::path m_dir;
};

/// Message of the MeshError thrown by f (fails the test when nothing is thrown).
std::string error_of(const std::function<void()> &f)
{
  try {
    f();
  } catch (const MeshError &e) {
    return e.what();
  }
  ADD_FAILURE() << "no MeshError thrown";
  return {};
}

std::string read_error(const std::string &path)
{
  return error_of([&] { read_mesh(path); });
}

std::string validate_error(const Shape &s)
{
  SurfaceMesh m = to_mesh(s, "shape.obj");
  std::vector<std::string> notices;
  return error_of([&] { validate_and_orient(m, notices); });
}

std::vector<std::string> validate(SurfaceMesh &m)
{
  std::vector<std::string> notices;
  validate_and_orient(m, notices);
  return notices;
}

#define EXPECT_HAS(text, part) EXPECT_NE(std::string(text).find(part), std::string::npos) << (text)

void expect_same_shape(const SurfaceMesh &m, const Shape &s)
{
  ASSERT_EQ(m.num_vertices(), static_cast<int>(s.points.size()));
  ASSERT_EQ(m.num_triangles(), static_cast<int>(s.tris.size()));
  for (std::size_t i = 0; i < s.points.size(); ++i)
    for (std::size_t d = 0; d < 3; ++d)
      EXPECT_NEAR(m.vertices[i][d], s.points[i][d], 1e-6);
  for (std::size_t t = 0; t < s.tris.size(); ++t)
    EXPECT_EQ(m.triangles[t], s.tris[t]) << "triangle " << t;
  EXPECT_EQ(m.triangle_region, std::vector<int>(s.tris.size(), -1));
}

} // namespace

// ------------------------------------------------------------------------------- geometry

TEST(MeshGeometry, NormalAndArea)
{
  const SurfaceMesh m = to_mesh(cube(2.0));
  const Vec3 bottom = m.triangle_normal(0);
  EXPECT_NEAR(bottom[2], -1.0, 1e-15);
  EXPECT_NEAR(norm(bottom), 1.0, 1e-15);
  EXPECT_NEAR(m.triangle_normal(2)[2], 1.0, 1e-15);
  EXPECT_NEAR(m.triangle_normal(11)[0], 1.0, 1e-15);
  for (int t = 0; t < 12; ++t)
    EXPECT_DOUBLE_EQ(m.triangle_area(t), 2.0);
  const SurfaceMesh tet = to_mesh(tetrahedron());
  EXPECT_NEAR(tet.triangle_area(3), std::sqrt(3.0) / 2.0, 1e-15);
  EXPECT_NEAR(tet.triangle_normal(3)[1], 1.0 / std::sqrt(3.0), 1e-15);
}

// ------------------------------------------------------------------------------- dispatch

TEST_F(MeshFiles, DispatchIsCaseInsensitive)
{
  const Shape t = tetrahedron();
  expect_same_shape(read_mesh(write("TET.OBJ", obj_text(t))), t);
  expect_same_shape(read_mesh(write("tet.Off", off_text(t))), t);
  const SurfaceMesh stl = read_mesh(write("tet.StL", stl_ascii(t)));
  ASSERT_EQ(stl.num_vertices(), 4);
  ASSERT_EQ(stl.num_triangles(), 4);
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(stl.vertices[stl.triangles[i][k]], t.points[t.tris[i][k]]);
}

TEST_F(MeshFiles, UnknownExtensionAndMissingFile)
{
  const std::string vtk = write("cube.vtk", "whatever");
  const std::string e = read_error(vtk);
  EXPECT_HAS(e, "cube.vtk");
  EXPECT_HAS(e, ".msh");
  EXPECT_HAS(e, ".stl");
  EXPECT_HAS(e, ".off");
  EXPECT_HAS(e, ".obj");
  const std::string missing = (m_dir / "missing.msh").string();
  EXPECT_HAS(read_error(missing), "cannot open mesh file '" + missing + "'");
  const std::string dir = (m_dir / "folder.stl").string();
  fs::create_directories(dir);
  EXPECT_HAS(read_error(dir), "cannot open mesh file");
}

// ------------------------------------------------------------------------------------ .msh

/// The cube written with non-contiguous node tags: vertices in ascending tag order, triangles
/// renumbered accordingly, the first six triangles in region `lower`, the rest in `upper`.
static void expect_tag_ordered_cube(const SurfaceMesh &m, int lower, int upper)
{
  const Shape c = cube();
  ASSERT_EQ(m.num_vertices(), 8);
  ASSERT_EQ(m.num_triangles(), 12);
  for (int j = 0; j < 8; ++j)
    EXPECT_EQ(m.vertices[j], c.points[k_tag_order[j]]) << "vertex " << j;
  for (int t = 0; t < 12; ++t) {
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(k_tag_order[m.triangles[t][k]], c.tris[t][k]);
    EXPECT_EQ(m.triangle_region[t], t < 6 ? lower : upper);
  }
}

TEST_F(MeshFiles, Msh22TagsRegionsAndNames)
{
  const SurfaceMesh m = read_mesh(write("cube22.msh", msh22_cube()));
  expect_tag_ordered_cube(m, 1, 2);
  EXPECT_EQ(m.region_tags, (std::map<std::string, int>{{"bottom part", 1}, {"top", 2}}));
  EXPECT_HAS(m.source, "cube22.msh");
}

TEST_F(MeshFiles, Msh41TagsRegionsAndNames)
{
  const SurfaceMesh m = read_mesh(write("cube41.msh", msh41_cube()));
  expect_tag_ordered_cube(m, 7, -1);
  EXPECT_EQ(m.region_tags, (std::map<std::string, int>{{"skin", 7}}));
}

TEST(MeshGmsh, BoxWithSphericalCavityBothVersions)
{
  const std::string dir = std::string(HSSBEM_TEST_DATA) + "/meshes/";
  SurfaceMesh v22 = read_mesh(dir + "box_sphere_cavity_v22.msh");
  SurfaceMesh v41 = read_mesh(dir + "box_sphere_cavity_v41.msh");
  EXPECT_EQ(v22.vertices, v41.vertices);
  EXPECT_EQ(v22.triangles, v41.triangles);
  EXPECT_EQ(v22.triangle_region, v41.triangle_region);
  EXPECT_EQ(v41.region_tags, (std::map<std::string, int>{{"outer", 11}, {"cavity", 12}}));
  EXPECT_EQ(std::count(v41.triangle_region.begin(), v41.triangle_region.end(), 12), 26);
  EXPECT_EQ(std::count(v41.triangle_region.begin(), v41.triangle_region.end(), 11), 264);
  // Gmsh already orients the cavity into the cavity: nothing to flip or report.
  EXPECT_TRUE(validate(v41).empty());
  EXPECT_EQ(v41.triangles, v22.triangles);
}

TEST(MeshGmsh, VolumeMeshKeepsOnlyTriangles)
{
  SurfaceMesh m = read_mesh(std::string(HSSBEM_TEST_DATA) + "/meshes/box_sphere_cavity_v41_volume.msh");
  EXPECT_EQ(m.num_triangles(), 290);
  EXPECT_EQ(m.num_vertices(), 151); // interior nodes of the tetrahedra stay, unused
  const auto notices = validate(m);
  ASSERT_EQ(notices.size(), 1u);
  EXPECT_HAS(notices[0], "2 of 151 vertices are used by no triangle");
}

TEST_F(MeshFiles, MshBinaryAndVersion)
{
  const std::string bin =
      write("bin.msh", std::string("$MeshFormat\n4.1 1 8\n\1\0\0\0\n$EndMeshFormat\n", 40));
  EXPECT_HAS(read_error(bin), "binary .msh not supported, save as ASCII");
  EXPECT_HAS(read_error(bin), "bin.msh:2");
  const std::string v3 = write("v3.msh", "$MeshFormat\n3.0 0 8\n$EndMeshFormat\n");
  EXPECT_HAS(read_error(v3), "unsupported .msh version 3.0");
  const std::string v40 = write("v40.msh", "$MeshFormat\n4 0 8\n$EndMeshFormat\n");
  EXPECT_HAS(read_error(v40), "v40.msh:2: unsupported .msh version 4");
  EXPECT_HAS(read_error(write("empty.msh", "")), "no $MeshFormat");
  EXPECT_HAS(read_error(write("nofmt.msh", "$Nodes\n0\n$EndNodes\n")), "nofmt.msh:1");
}

TEST_F(MeshFiles, MshUnknownNodeTag)
{
  // Element 9 is triangle 6, on line 34 (after 27 lines of header, nodes, a point and a line).
  const auto replace_element_9 = [](const std::string &by) {
    std::string text = msh22_cube();
    const std::size_t start = text.find("\n9 2 2 2 3 ") + 1;
    return text.replace(start, text.find('\n', start) - start, by);
  };
  const std::string line_of_9 = ":34:";
  EXPECT_HAS(read_error(write("extra.msh", replace_element_9("9 2 2 2 3 13 1000 8 15"))),
             "extra.msh:34: triangle element: expected 8 values, found 9");
  const std::string e = read_error(write("unknown.msh", replace_element_9("9 2 2 2 3 13 5557 8")));
  EXPECT_HAS(e, "unknown.msh" + line_of_9);
  EXPECT_HAS(e, "unknown node tag 5557");

  std::string t41 = msh41_cube();
  t41.replace(t41.find("\n2 40 "), 6, "\n2 41 ");
  EXPECT_HAS(read_error(write("unknown41.msh", t41)), "unknown node tag 41");
}

TEST_F(MeshFiles, MshTruncatedAndMissingEnd)
{
  const std::string full = msh22_cube();
  const std::string cut = full.substr(0, full.find("13 2 2 2"));
  const std::string e = read_error(write("cut.msh", cut));
  EXPECT_HAS(e, "cut.msh:");
  EXPECT_HAS(e, "truncated");

  std::string no_end = full;
  no_end.erase(no_end.find("$EndNodes\n"), 10);
  const std::string e2 = read_error(write("noend.msh", no_end));
  EXPECT_HAS(e2, "noend.msh:23: expected $EndNodes, found '$Elements'");

  const std::string open_comment = full.substr(0, full.find("$EndComments"));
  EXPECT_HAS(read_error(write("comment.msh", open_comment)), "section $Comments (line 10) has no $EndComments");

  const std::string short_nodes = full.substr(0, full.find("$Nodes\n8\n") + 9) + "1 0 0 0\n$EndNodes\n";
  EXPECT_HAS(read_error(write("short.msh", short_nodes)), "short.msh:16: section $Nodes is truncated");
  EXPECT_HAS(read_error(write("fmt.msh", "$MeshFormat\n2.2 0 8\n")), "section $MeshFormat has no $EndMeshFormat");
}

TEST_F(MeshFiles, MshNonNumericTokens)
{
  std::string text = msh22_cube();
  text.replace(text.find("\n2 0 0 1\n"), 9, "\n2 0 zero 1\n"); // node tag 2 is corner 4
  const std::string e = read_error(write("nan.msh", text));
  EXPECT_HAS(e, "nan.msh:");
  EXPECT_HAS(e, "expected a number, found 'zero'");

  std::string t41 = msh41_cube();
  t41.replace(t41.find("2 3 2 6\n"), 8, "2 3 2 six\n");
  EXPECT_HAS(read_error(write("six.msh", t41)), "expected an integer, found 'six'");
}

// ------------------------------------------------------------------------------------- STL

TEST_F(MeshFiles, StlAsciiMergesVertices)
{
  const Shape c = cube();
  const SurfaceMesh m = read_mesh(write("cube.stl", stl_ascii(c)));
  ASSERT_EQ(m.num_vertices(), 8);
  ASSERT_EQ(m.num_triangles(), 12);
  // Numbered by first appearance: triangle 0 is (0, 3, 2), triangle 1 adds 1, ...
  EXPECT_EQ(m.vertices[1], c.points[3]);
  EXPECT_EQ(m.vertices[3], c.points[1]);
  for (int t = 0; t < 12; ++t)
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(m.vertices[m.triangles[t][k]], c.points[c.tris[t][k]]);
  EXPECT_TRUE(m.region_tags.empty());
  EXPECT_EQ(m.triangle_region, std::vector<int>(12, -1));
}

TEST_F(MeshFiles, StlBinaryMatchesAscii)
{
  const Shape c = cube(0.5, {1.0, -2.0, 0.25}); // exact in float
  const SurfaceMesh ascii = read_mesh(write("a.stl", stl_ascii(c)));
  const SurfaceMesh binary = read_mesh(write("b.stl", stl_binary(c)));
  // A binary header may start with "solid": the exact file size still says binary.
  const SurfaceMesh tricky = read_mesh(write("c.stl", stl_binary(c, "solid pretending")));
  EXPECT_EQ(binary.vertices, ascii.vertices);
  EXPECT_EQ(binary.triangles, ascii.triangles);
  EXPECT_EQ(tricky.triangles, ascii.triangles);
  EXPECT_EQ(binary.num_vertices(), 8);
}

TEST_F(MeshFiles, StlMalformed)
{
  std::string text = stl_ascii(tetrahedron());
  text.replace(text.find("vertex 1 0 0"), 12, "vertex 1 0");
  EXPECT_HAS(read_error(write("short.stl", text)), "short.stl:6: vertex: expected 4 values, found 3");

  text = stl_ascii(tetrahedron());
  text.replace(text.find("vertex 1 0 0"), 12, "vertex 1 0 0\nvertex 2 0 0");
  EXPECT_HAS(read_error(write("four.stl", text)), "four.stl:7: facet with more than 3 vertices");

  text = stl_ascii(tetrahedron());
  EXPECT_HAS(read_error(write("trunc.stl", text.substr(0, text.find("endsolid")))), "missing endsolid");

  const std::string bin = stl_binary(tetrahedron());
  const std::string e = read_error(write("cut.stl", bin.substr(0, bin.size() - 7)));
  EXPECT_HAS(e, "cut.stl");
  EXPECT_HAS(e, "declares 4 triangles");
  EXPECT_HAS(read_error(write("tiny.stl", "abc")), "not an STL file");
}

// ------------------------------------------------------------------------------------- OFF

TEST_F(MeshFiles, OffQuadsAndComments)
{
  const SurfaceMesh m = read_mesh(write("cube.off", off_cube_quads()));
  expect_same_shape(m, cube());
}

TEST_F(MeshFiles, OffMalformed)
{
  std::string text = off_cube_quads();
  text.replace(text.find("4 0 3 2 1"), 9, "4 0 3 2 8");
  EXPECT_HAS(read_error(write("range.off", text)), "range.off:12: face refers to vertex 8, but the file has 8 vertices");
  const std::string tet = off_text(tetrahedron());
  const std::string no_last_face = tet.substr(0, tet.rfind("3 ", tet.size() - 2));
  EXPECT_HAS(read_error(write("trunc.off", no_last_face)), "trunc.off:9: file truncated: 3 of 4 faces read");
  EXPECT_HAS(read_error(write("cut.off", off_cube_quads().substr(0, 150))), "cut.off:14: expected at least 5 values");
  EXPECT_HAS(read_error(write("hdr.off", "PLY\n")), "hdr.off:1: expected the header OFF");
  text = off_cube_quads();
  text.replace(text.find("4 0 3 2 1"), 9, "2 0 3");
  EXPECT_HAS(read_error(write("two.off", text)), "two.off:12: face with 2 vertices");
}

// ------------------------------------------------------------------------------------- OBJ

TEST_F(MeshFiles, ObjNegativeIndicesSlashesAndPolygons)
{
  // Each quad is written right after its corners and refers to them by negative indices;
  // "v/vt/vn" forms, groups, objects, normals and texture lines must be accepted and ignored.
  const Shape c = cube();
  std::string text = "mtllib none.mtl\no cube\ng sides\nvn 0 0 1\nvt 0 0\n";
  for (std::size_t i = 0; i < 8; ++i)
    text += "v " + point_text(c.points[i]) + " 1.0\n";
  text += "f 1/1/1 4/1/1 3/1/1 2/1/1\nf -4//1 -3//1 -2//1 -1//1\ns off\n";
  text += "f 1/1 2/1 6/1 5/1\nf 3 4 8 7\nf 1 5 8 4\nf 2 3 7 6\n";
  const SurfaceMesh m = read_mesh(write("cube.obj", text));
  expect_same_shape(m, cube());

  std::string pentagon = "v 0 0 0\nv 1 0 0\nv 2 1 0\nv 1 2 0\nv 0 1 0\nf -5 -4 -3 -2 -1\n";
  const SurfaceMesh p = read_mesh(write("pent.obj", pentagon));
  EXPECT_EQ(p.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 2, 3}, {0, 3, 4}}));
}

TEST_F(MeshFiles, ObjMalformed)
{
  EXPECT_HAS(read_error(write("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n")),
             "zero.obj:4: face vertex index 0");
  EXPECT_HAS(read_error(write("far.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n")),
             "far.obj:4: face refers to vertex 4, but only 3 vertices are defined so far");
  EXPECT_HAS(read_error(write("neg.obj", "v 0 0 0\nv 1 0 0\n\nv 0 1 0\nf -1 -2 -4\n")),
             "neg.obj:5: face refers to vertex -4");
  EXPECT_HAS(read_error(write("vx.obj", "# c\nv 0 zero 0\n")), "vx.obj:2: expected a number, found 'zero'");
  EXPECT_HAS(read_error(write("two.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n")), "two.obj:3: face (at least 3 vertices)");
  EXPECT_HAS(read_error(write("slash.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 /2 3\n")),
             "slash.obj:4: bad face vertex '/2'");
}

// ------------------------------------------------------------------------------ validation

TEST(MeshValidate, GoodMeshesPassUnchanged)
{
  for (const Shape &s : {cube(), tetrahedron(), cube(3.0, {-1e6, 2e6, 5.0})}) {
    SurfaceMesh m = to_mesh(s);
    EXPECT_TRUE(validate(m).empty());
    EXPECT_EQ(m.triangles, s.tris);
  }
}

TEST(MeshValidate, BasicTriangleFaults)
{
  EXPECT_HAS(validate_error(Shape{{{0, 0, 0}}, {}}), "mesh 'shape.obj': no triangles");
  Shape s = cube();
  s.tris[4][1] = 8;
  EXPECT_HAS(validate_error(s), "triangle 4 (0, 8, 5) references vertex 8, but the mesh has 8 vertices");
  s = cube();
  s.tris[5] = {3, 7, 3};
  EXPECT_HAS(validate_error(s), "triangle 5 (3, 7, 3) has a repeated vertex");
}

TEST(MeshValidate, DegenerateAndDuplicate)
{
  Shape s = cube();
  s.points.push_back({0.5, 0.0, 0.0});
  s.tris.push_back({0, 1, 8});
  EXPECT_HAS(validate_error(s), "degenerate triangle 12 (0, 1, 8)");
  s = cube();
  s.points[1] = {1e-13, 0, 0}; // not exactly zero, but far below 1e-12 x diagonal^2
  EXPECT_HAS(validate_error(s), "degenerate triangle 1 (0, 2, 1)");
  s = cube();
  s.tris.push_back({s.tris[3][0], s.tris[3][2], s.tris[3][1]});
  EXPECT_HAS(validate_error(s), "duplicate triangle: triangles 3 and 12 have the same vertices (4, 6, 7)");
}

TEST(MeshValidate, OpenSurface)
{
  Shape s = cube();
  s.tris.pop_back(); // (1, 6, 5): the first triangle left with an open edge is (4, 5, 6)
  EXPECT_HAS(validate_error(s), "open surface: edge (5, 6) belongs to only one triangle (2)");
}

TEST(MeshValidate, NonManifoldEdgeAndVertex)
{
  // A second cube sharing the vertical edge (2, 6) of the first.
  const Shape edge_pair = merge(cube(), cube(1.0, {1, 1, 0}), {{0, 2}, {4, 6}});
  EXPECT_HAS(validate_error(edge_pair), "non-manifold edge (2, 6) is shared by 4 triangles (7, 10, 17, 20)");
  // A second cube touching the first only at corner 6.
  const Shape vertex_pair = merge(cube(), cube(1.0, {1, 1, 1}), {{0, 6}});
  EXPECT_HAS(validate_error(vertex_pair), "non-manifold vertex 6: its 11 triangles form more than one fan");
}

TEST(MeshValidate, InconsistentOrientation)
{
  Shape s = cube();
  std::swap(s.tris[7][1], s.tris[7][2]);
  const std::string e = validate_error(s);
  EXPECT_HAS(e, "inconsistent orientation: triangles");
  EXPECT_HAS(e, "and 7 both traverse edge");
}

TEST(MeshValidate, FlatComponentEnclosesNoVolume)
{
  // Two different triangulations of one square, glued along its border.
  const Shape flat{{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 3}, {1, 0, 3}, {1, 3, 2}}};
  EXPECT_HAS(validate_error(flat), "component 0 (4 triangles, first triangle 0) encloses no volume");
}

TEST(MeshValidate, InwardCubeIsFlipped)
{
  SurfaceMesh m = to_mesh(flipped(cube(2.0, {5, 5, 5})), "x.msh");
  EXPECT_LT(signed_volume(m, range(0, 12)), 0.0);
  const auto notices = validate(m);
  ASSERT_EQ(notices.size(), 1u);
  EXPECT_EQ(notices[0], "mesh 'x.msh': component 0 (12 triangles) was oriented inward; flipped");
  EXPECT_NEAR(signed_volume(m, range(0, 12)), 8.0, 1e-9);
  EXPECT_TRUE(validate(m).empty()); // idempotent
}

TEST(MeshValidate, CubeInCubeMakesInnerACavity)
{
  // Both written outward: the inner one bounds a cavity and must end up pointing into it.
  SurfaceMesh m = to_mesh(merge(cube(3.0), cube(1.0, {1, 1, 1})), "nested.obj");
  const auto notices = validate(m);
  ASSERT_EQ(notices.size(), 1u);
  EXPECT_EQ(notices[0], "mesh 'nested.obj': component 1 (12 triangles, cavity boundary) was oriented "
                        "inward; flipped");
  EXPECT_NEAR(signed_volume(m, range(0, 12)), 27.0, 1e-9);
  EXPECT_NEAR(signed_volume(m, range(12, 24)), -1.0, 1e-9);

  // Inner first and both inward: two flips, the inner one still ends negative.
  SurfaceMesh r = to_mesh(merge(flipped(cube(1.0, {1, 1, 1})), flipped(cube(3.0))), "rev.obj");
  EXPECT_EQ(validate(r).size(), 1u); // only the outer one was wrong
  EXPECT_NEAR(signed_volume(r, range(0, 12)), -1.0, 1e-9);
  EXPECT_NEAR(signed_volume(r, range(12, 24)), 27.0, 1e-9);
}

TEST(MeshValidate, IslandInsideCavityAndSeparateBodies)
{
  // outer solid, cavity, a solid island in the cavity, and a separate body beside them
  Shape s = merge(merge(cube(5.0), cube(3.0, {1, 1, 1})), cube(1.0, {2, 2, 2}));
  s = merge(s, tetrahedron());
  for (std::size_t i = s.points.size() - 4; i < s.points.size(); ++i)
    s.points[i] = s.points[i] + Vec3{10, 0, 0};
  SurfaceMesh m = to_mesh(s);
  validate(m);
  EXPECT_NEAR(signed_volume(m, range(0, 12)), 125.0, 1e-9);
  EXPECT_NEAR(signed_volume(m, range(12, 24)), -27.0, 1e-9);
  EXPECT_NEAR(signed_volume(m, range(24, 36)), 1.0, 1e-9);
  EXPECT_NEAR(signed_volume(m, range(36, 40)), 1.0 / 6.0, 1e-12);
}

TEST_F(MeshFiles, ValidationNamesTheFileAndReportsUnusedVertices)
{
  Shape s = cube();
  s.points.push_back({9, 9, 9});
  SurfaceMesh m = read_mesh(write("extra.off", off_text(flipped(s))));
  const auto notices = validate(m);
  ASSERT_EQ(notices.size(), 2u);
  EXPECT_HAS(notices[0], "extra.off");
  EXPECT_HAS(notices[0], "flipped");
  EXPECT_HAS(notices[1], "1 of 9 vertices are used by no triangle (first: vertex 8)");

  SurfaceMesh nested = read_mesh(write("nested.stl", stl_binary(merge(cube(4.0), cube(1.0, {1, 1, 1})))));
  const auto flips = validate(nested);
  ASSERT_EQ(flips.size(), 1u);
  EXPECT_HAS(flips[0], "nested.stl': component 1 (12 triangles, cavity boundary) was oriented inward");
  EXPECT_NEAR(signed_volume(nested, range(12, 24)), -1.0, 1e-9);

  Shape open = cube();
  open.tris.pop_back();
  SurfaceMesh o = read_mesh(write("open.stl", stl_ascii(open)));
  const std::string e = error_of([&] { validate(o); });
  EXPECT_HAS(e, "mesh '" + o.source + "': open surface");
  EXPECT_HAS(e, "open.stl");
}

// -------------------------------------------------------------------------------- large mesh

/// Surface of an n x n x n lattice cube, each face split into 2 n^2 outward triangles.
Shape lattice_cube(int n)
{
  Shape s;
  std::map<std::array<int, 3>, int> index;
  auto vertex = [&](std::array<int, 3> p) {
    const auto [it, inserted] = index.emplace(p, static_cast<int>(s.points.size()));
    if (inserted)
      s.points.push_back({double(p[0]), double(p[1]), double(p[2])});
    return it->second;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side <= 1; ++side)
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          int q[4];
          const int di[4] = {0, 1, 1, 0}, dj[4] = {0, 0, 1, 1};
          for (int k = 0; k < 4; ++k) {
            std::array<int, 3> p{};
            p[axis] = side * n;
            p[(axis + 1) % 3] = i + di[k];
            p[(axis + 2) % 3] = j + dj[k];
            q[k] = vertex(p);
          }
          // (axis+1, axis+2) is right-handed about +axis: reverse on the low side
          if (side == 1)
            s.tris.insert(s.tris.end(), {{q[0], q[1], q[2]}, {q[0], q[2], q[3]}});
          else
            s.tris.insert(s.tris.end(), {{q[0], q[2], q[1]}, {q[0], q[3], q[2]}});
        }
  return s;
}

TEST_F(MeshFiles, HundredThousandTriangles)
{
  const Shape s = lattice_cube(91); // 99 372 triangles
  const std::string path = write("big.obj", obj_text(flipped(s)));
  SurfaceMesh m = read_mesh(path); // its time is a benchmark's (no timed unit tests)
  const auto notices = validate(m);
  EXPECT_EQ(m.num_triangles(), 6 * 2 * 91 * 91);
  ASSERT_EQ(notices.size(), 1u);
  EXPECT_NEAR(signed_volume(m, range(0, m.num_triangles())), 91.0 * 91.0 * 91.0, 1e-3);
}
