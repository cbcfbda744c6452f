/// \file test_output.cpp
/// Result writer: every dataset and attribute read back through the HDF5 C API, the XDMF
/// sidecar, atomic replacement and the clean-up after errors; the same for FrameWriter's frames.
#include "hssbem/core/fault.hpp"
#include "hssbem/io/hdf5_output.hpp"
#include "hssbem/io/temp_files.hpp"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace hssbem;

namespace {

/// A distinct value for every (field, row, component), so a transposed or shifted array fails.
double value(int field, std::size_t row, std::size_t k)
{
  return field * 100.0 + static_cast<double>(row) * 10.0 + static_cast<double>(k) + 0.25;
}

std::vector<Vec3> vectors(int field, std::size_t n)
{
  std::vector<Vec3> v(n);
  for (std::size_t i = 0; i < n; ++i)
    v[i] = {value(field, i, 0), value(field, i, 1), value(field, i, 2)};
  return v;
}

/// A tetrahedron with every field filled.
ResultData tetrahedron()
{
  ResultData d;
  d.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  d.triangles = {{{0, 2, 1}}, {{0, 1, 3}}, {{0, 3, 2}}, {{1, 2, 3}}};
  d.triangle_region = {7, 8, 9, 11};
  d.sharp_vertex = {1, 0, 0, 1};
  d.displacement = vectors(1, 4);
  d.traction = vectors(2, 4);
  d.traction_corner.resize(4);
  for (std::size_t t = 0; t < 4; ++t)
    for (std::size_t c = 0; c < 3; ++c)
      d.traction_corner[t][c] = {value(3, t * 3 + c, 0), value(3, t * 3 + c, 1),
                                 value(3, t * 3 + c, 2)};
  d.displacement_prescribed = {{{true, false, true}}, {{false, false, false}},
                               {{true, true, true}}, {{false, true, false}}};
  d.reactions = {{"base", {1.5, -2.5, 3.5}}, {"top", {-4.5, 5.5, -6.5}}};
  d.interior_points = vectors(4, 2);
  d.interior_displacement = vectors(5, 2);
  d.attributes_real = {{"E", 210e9}, {"nu", 0.3}};
  d.attributes_int = {{"iterations", 42}, {"ranks", 4}};
  d.attributes_str = {{"solver", "gmres"}, {"version", "0.1.0"}};
  d.timings = {{"assembly", 1.25}, {"solve", 0.5}};
  return d;
}

/// Owns an open HDF5 identifier in the reading code.
struct Id {
  hid_t id;
  herr_t (*close)(hid_t);
  ~Id()
  {
    if (id >= 0)
      close(id);
  }
};

/// A dataset read back: shape, stored type and values converted to `T`.
template <class T> struct Read {
  std::vector<hsize_t> dims;
  H5T_class_t type_class = H5T_NO_CLASS;
  std::size_t type_size = 0;
  std::vector<T> values;
};

template <class T> Read<T> read_dataset(hid_t file, const std::string &name, hid_t mem_type)
{
  Read<T> r;
  Id set{H5Dopen2(file, name.c_str(), H5P_DEFAULT), H5Dclose};
  EXPECT_GE(set.id, 0) << name;
  if (set.id < 0)
    return r;
  Id space{H5Dget_space(set.id), H5Sclose};
  r.dims.resize(static_cast<std::size_t>(H5Sget_simple_extent_ndims(space.id)));
  H5Sget_simple_extent_dims(space.id, r.dims.data(), nullptr);
  Id type{H5Dget_type(set.id), H5Tclose};
  r.type_class = H5Tget_class(type.id);
  r.type_size = H5Tget_size(type.id);
  r.values.resize(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space.id)));
  EXPECT_GE(H5Dread(set.id, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, r.values.data()), 0);
  return r;
}

bool exists(hid_t file, const std::string &name)
{
  return H5Lexists(file, name.c_str(), H5P_DEFAULT) > 0;
}

template <class T> T read_attribute(hid_t owner, const std::string &name, hid_t mem_type)
{
  T v{};
  Id attr{H5Aopen(owner, name.c_str(), H5P_DEFAULT), H5Aclose};
  EXPECT_GE(attr.id, 0) << name;
  if (attr.id >= 0) {
    EXPECT_GE(H5Aread(attr.id, mem_type, &v), 0) << name;
  }
  return v;
}

std::string read_string_attribute(hid_t owner, const std::string &name)
{
  Id attr{H5Aopen(owner, name.c_str(), H5P_DEFAULT), H5Aclose};
  EXPECT_GE(attr.id, 0) << name;
  Id type{H5Aget_type(attr.id), H5Tclose};
  EXPECT_EQ(H5Tget_class(type.id), H5T_STRING);
  EXPECT_TRUE(H5Tis_variable_str(type.id) > 0);
  char *text = nullptr;
  EXPECT_GE(H5Aread(attr.id, type.id, &text), 0);
  std::string out = text ? text : "";
  H5free_memory(text);
  return out;
}

std::vector<double> flat(const std::vector<Vec3> &v)
{
  std::vector<double> out;
  for (const Vec3 &x : v)
    out.insert(out.end(), x.begin(), x.end());
  return out;
}

std::string slurp(const fs::path &p)
{
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::size_t occurrences(const std::string &text, const std::string &what)
{
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1))
    ++n;
  return n;
}

class OutputTest : public ::testing::Test {
protected:
  void SetUp() override
  {
    const fs::path base = std::getenv("TMPDIR") ? std::getenv("TMPDIR") : "/tmp";
    std::string pattern = (base / "hssbem-output-XXXXXX").string();
    ASSERT_NE(::mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
    h5_ = (dir_ / "out.h5").string();
    xdmf_ = (dir_ / "out.xdmf").string();
  }
  void TearDown() override
  {
    ::chmod(dir_.c_str(), 0700);
    fs::remove_all(dir_);
  }
  /// Names in the test directory, sorted, so that leftovers show in a failure message.
  std::vector<std::string> listing() const
  {
    std::vector<std::string> names;
    for (const auto &entry : fs::directory_iterator(dir_))
      names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }
  /// The temporary file of `file` (`<file>.tmp.<host>.<pid>.<random>`); empty if there is none.
  std::string temp_of(const std::string &file) const
  {
    const std::string head = fs::path(file).filename().string() + ".tmp.";
    for (const std::string &name : listing())
      if (name.rfind(head, 0) == 0) return (dir_ / name).string();
    return "";
  }
  /// Names in the test directory with the random part of temporary names cut off.
  std::vector<std::string> stems() const
  {
    std::vector<std::string> names = listing();
    for (std::string &n : names)
      if (n.find(".tmp.") != std::string::npos || n.find(".bak.") != std::string::npos) n = n.substr(0, n.rfind('.'));
    return names;
  }
  /// A name with this process's host and id: what exclusive_name() makes with `suffix`.
  static std::string planted_name(const std::string &final_path, const std::string &kind, const std::string &suffix)
  {
    const detail::TemporarySuffixForTests fixed([suffix] { return suffix; });
    return exclusive_name(final_path, kind);
  }
  /// `<host>.<pid>` of this process as the temporary names hold it.
  static std::string host_and_pid()
  {
    const std::string n = planted_name("f", "k", "s"); // f.k.<host>.<pid>.s
    return n.substr(4, n.size() - 6);
  }

  fs::path dir_;
  std::string h5_, xdmf_;
};

using Strings = std::vector<std::string>;

TEST_F(OutputTest, MeshDatasetsHaveShapeTypeAndValues)
{
  const ResultData d = tetrahedron();
  write_result(h5_, d);
  Id file{H5Fopen(h5_.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
  ASSERT_GE(file.id, 0);

  const auto v = read_dataset<double>(file.id, "/mesh/vertices", H5T_NATIVE_DOUBLE);
  EXPECT_EQ(v.dims, (std::vector<hsize_t>{4, 3}));
  EXPECT_EQ(v.type_class, H5T_FLOAT);
  EXPECT_EQ(v.type_size, 8u);
  EXPECT_EQ(v.values, flat(d.vertices));

  const auto t = read_dataset<int>(file.id, "/mesh/triangles", H5T_NATIVE_INT);
  EXPECT_EQ(t.dims, (std::vector<hsize_t>{4, 3}));
  EXPECT_EQ(t.type_class, H5T_INTEGER);
  EXPECT_EQ(t.type_size, 4u);
  EXPECT_EQ(t.values, (std::vector<int>{0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3}));

  const auto r = read_dataset<int>(file.id, "/mesh/triangle_region", H5T_NATIVE_INT);
  EXPECT_EQ(r.dims, (std::vector<hsize_t>{4}));
  EXPECT_EQ(r.type_size, 4u);
  EXPECT_EQ(r.values, d.triangle_region);

  const auto s = read_dataset<int>(file.id, "/mesh/sharp_vertex", H5T_NATIVE_INT);
  EXPECT_EQ(s.dims, (std::vector<hsize_t>{4}));
  EXPECT_EQ(s.type_class, H5T_INTEGER);
  EXPECT_EQ(s.type_size, 1u);
  EXPECT_EQ(s.values, d.sharp_vertex);
}

TEST_F(OutputTest, FieldAndBoundaryDatasetsHaveShapeTypeAndValues)
{
  const ResultData d = tetrahedron();
  write_result(h5_, d);
  Id file{H5Fopen(h5_.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
  ASSERT_GE(file.id, 0);

  const auto u = read_dataset<double>(file.id, "/fields/displacement", H5T_NATIVE_DOUBLE);
  EXPECT_EQ(u.dims, (std::vector<hsize_t>{4, 3}));
  EXPECT_EQ(u.type_size, 8u);
  EXPECT_EQ(u.values, flat(d.displacement));

  const auto p = read_dataset<double>(file.id, "/fields/traction", H5T_NATIVE_DOUBLE);
  EXPECT_EQ(p.dims, (std::vector<hsize_t>{4, 3}));
  EXPECT_EQ(p.values, flat(d.traction));

  const auto pc = read_dataset<double>(file.id, "/fields/traction_corner", H5T_NATIVE_DOUBLE);
  EXPECT_EQ(pc.dims, (std::vector<hsize_t>{4, 3, 3}));
  ASSERT_EQ(pc.values.size(), 36u);
  for (std::size_t t = 0; t < 4; ++t)
    for (std::size_t c = 0; c < 3; ++c)
      for (std::size_t k = 0; k < 3; ++k)
        EXPECT_EQ(pc.values[(t * 3 + c) * 3 + k], d.traction_corner[t][c][k]) << t << c << k;

  const auto m = read_dataset<int>(file.id, "/bc/displacement_prescribed", H5T_NATIVE_INT);
  EXPECT_EQ(m.dims, (std::vector<hsize_t>{4, 3}));
  EXPECT_EQ(m.type_class, H5T_INTEGER);
  EXPECT_EQ(m.type_size, 1u);
  EXPECT_EQ(m.values, (std::vector<int>{1, 0, 1, 0, 0, 0, 1, 1, 1, 0, 1, 0}));
}

TEST_F(OutputTest, ReactionsAndInteriorDatasets)
{
  const ResultData d = tetrahedron();
  write_result(h5_, d);
  Id file{H5Fopen(h5_.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
  ASSERT_GE(file.id, 0);

  for (const auto &[region, force] : d.reactions) {
    const auto r = read_dataset<double>(file.id, "/reactions/" + region, H5T_NATIVE_DOUBLE);
    EXPECT_EQ(r.dims, (std::vector<hsize_t>{3})) << region;
    EXPECT_EQ(r.type_size, 8u);
    EXPECT_EQ(r.values, (std::vector<double>(force.begin(), force.end()))) << region;
  }
  Id reactions{H5Gopen2(file.id, "/reactions", H5P_DEFAULT), H5Gclose};
  H5G_info_t info{};
  ASSERT_GE(H5Gget_info(reactions.id, &info), 0);
  EXPECT_EQ(info.nlinks, 2u);

  const auto x = read_dataset<double>(file.id, "/interior/points", H5T_NATIVE_DOUBLE);
  EXPECT_EQ(x.dims, (std::vector<hsize_t>{2, 3}));
  EXPECT_EQ(x.values, flat(d.interior_points));
  const auto u = read_dataset<double>(file.id, "/interior/displacement", H5T_NATIVE_DOUBLE);
  EXPECT_EQ(u.dims, (std::vector<hsize_t>{2, 3}));
  EXPECT_EQ(u.values, flat(d.interior_displacement));
}

TEST_F(OutputTest, RootAttributesAndTimings)
{
  const ResultData d = tetrahedron();
  write_result(h5_, d);
  Id file{H5Fopen(h5_.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
  ASSERT_GE(file.id, 0);

  for (const auto &[name, v] : d.attributes_real)
    EXPECT_EQ(read_attribute<double>(file.id, name, H5T_NATIVE_DOUBLE), v) << name;
  for (const auto &[name, v] : d.attributes_int)
    EXPECT_EQ(read_attribute<long long>(file.id, name, H5T_NATIVE_LLONG), v) << name;
  for (const auto &[name, v] : d.attributes_str)
    EXPECT_EQ(read_string_attribute(file.id, name), v) << name;
  Id iterations{H5Aopen(file.id, "iterations", H5P_DEFAULT), H5Aclose};
  Id int_type{H5Aget_type(iterations.id), H5Tclose};
  EXPECT_EQ(H5Tget_size(int_type.id), 8u);

  Id timings{H5Gopen2(file.id, "/timings", H5P_DEFAULT), H5Gclose};
  ASSERT_GE(timings.id, 0);
  for (const auto &[phase, seconds] : d.timings)
    EXPECT_EQ(read_attribute<double>(timings.id, phase, H5T_NATIVE_DOUBLE), seconds) << phase;
  H5O_info_t info{};
  ASSERT_GE(H5Oget_info2(timings.id, &info, H5O_INFO_NUM_ATTRS), 0);
  EXPECT_EQ(info.num_attrs, 2u);
  ASSERT_GE(H5Oget_info2(file.id, &info, H5O_INFO_NUM_ATTRS), 0);
  EXPECT_EQ(info.num_attrs, 6u);
}

TEST_F(OutputTest, EmptyOptionalArraysAreSkipped)
{
  ResultData d = tetrahedron();
  d.traction.clear();
  d.traction_corner.clear();
  d.displacement_prescribed.clear();
  d.interior_points.clear();
  d.interior_displacement.clear();
  write_result(h5_, d);
  Id file{H5Fopen(h5_.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
  ASSERT_GE(file.id, 0);
  EXPECT_TRUE(exists(file.id, "/fields/displacement"));
  EXPECT_FALSE(exists(file.id, "/fields/traction"));
  EXPECT_FALSE(exists(file.id, "/fields/traction_corner"));
  EXPECT_FALSE(exists(file.id, "/bc/displacement_prescribed"));
  EXPECT_FALSE(exists(file.id, "/interior"));
  const std::string xdmf = slurp(xdmf_);
  EXPECT_EQ(xdmf.find("/fields/traction"), std::string::npos) << xdmf;
  EXPECT_EQ(xdmf.find("displacement_prescribed"), std::string::npos) << xdmf;
}

TEST_F(OutputTest, XdmfSidecarPointsIntoTheH5ByBasename)
{
  write_result(h5_, tetrahedron());
  ASSERT_TRUE(fs::exists(xdmf_));
  const std::string x = slurp(xdmf_);
  EXPECT_EQ(x.rfind("<?xml", 0), 0u);
  EXPECT_NE(x.find(R"(<Xdmf Version="3.0")"), std::string::npos);
  EXPECT_NE(x.find(R"(<Grid Name="hssbem" GridType="Uniform">)"), std::string::npos);
  EXPECT_NE(x.find(R"(<Topology TopologyType="Triangle" NumberOfElements="4">)"),
            std::string::npos);
  EXPECT_NE(x.find(R"(<Geometry GeometryType="XYZ">)"), std::string::npos);
  for (const char *set : {"/mesh/triangles", "/mesh/vertices", "/fields/displacement",
                          "/fields/traction", "/bc/displacement_prescribed",
                          "/mesh/triangle_region"})
    EXPECT_NE(x.find(std::string(">out.h5:") + set + "</DataItem>"), std::string::npos) << set;
  EXPECT_EQ(x.find(dir_.string()), std::string::npos) << "reference must be relative";
  EXPECT_EQ(occurrences(x, R"(Dimensions="4 3")"), 5u) << x;
  EXPECT_NE(x.find(R"(<Attribute Name="triangle_region" AttributeType="Scalar" Center="Cell">)"),
            std::string::npos);
  EXPECT_NE(x.find(R"(<Attribute Name="displacement" AttributeType="Vector" Center="Node">)"),
            std::string::npos);
  EXPECT_EQ(occurrences(x, "<Attribute "), occurrences(x, "</Attribute>"));
  EXPECT_EQ(occurrences(x, "<DataItem "), occurrences(x, "</DataItem>"));
  EXPECT_NE(x.find("</Xdmf>"), std::string::npos);
}

TEST_F(OutputTest, XdmfNameReplacesAnyExtension)
{
  const std::string bare = (dir_ / "result").string();
  write_result(bare, tetrahedron());
  EXPECT_EQ(listing(), (Strings{"result", "result.xdmf"}));
  EXPECT_NE(slurp(dir_ / "result.xdmf").find(">result:/mesh/vertices<"), std::string::npos);
}

TEST_F(OutputTest, NoTemporaryFileRemains)
{
  write_result(h5_, tetrahedron());
  EXPECT_EQ(listing(), (Strings{"out.h5", "out.xdmf"}));
}

TEST_F(OutputTest, OverwritesAnExistingResult)
{
  write_result(h5_, tetrahedron());
  ResultData d = tetrahedron();
  d.displacement = vectors(9, 4);
  d.traction.clear();
  write_result(h5_, d);
  EXPECT_EQ(listing(), (Strings{"out.h5", "out.xdmf"}));
  Id file{H5Fopen(h5_.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
  ASSERT_GE(file.id, 0);
  EXPECT_EQ(read_dataset<double>(file.id, "/fields/displacement", H5T_NATIVE_DOUBLE).values,
            flat(d.displacement));
  EXPECT_FALSE(exists(file.id, "/fields/traction"));
  EXPECT_EQ(slurp(xdmf_).find("/fields/traction"), std::string::npos);
}

TEST_F(OutputTest, CheckOutputPathAcceptsAWritableDirectory)
{
  EXPECT_NO_THROW(check_output_path(h5_));
  EXPECT_TRUE(listing().empty()) << "the check must not create anything";
}

TEST_F(OutputTest, CheckOutputPathRejectsAMissingDirectory)
{
  const std::string path = (dir_ / "missing" / "out.h5").string();
  try {
    check_output_path(path);
    FAIL() << "no exception";
  } catch (const OutputError &e) {
    EXPECT_EQ(std::string(e.what()).rfind("cannot write output '" + path + "': ", 0), 0u)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos) << e.what();
  }
}

TEST_F(OutputTest, CheckOutputPathRejectsDirectories)
{
  EXPECT_THROW(check_output_path(dir_.string()), OutputError);
  EXPECT_THROW(check_output_path(dir_.string() + "/"), OutputError);
  fs::create_directory(dir_ / "out.xdmf");
  EXPECT_THROW(check_output_path(h5_), OutputError) << "the sidecar's name is a directory";
  EXPECT_THROW(check_output_path(""), OutputError);
  EXPECT_THROW(check_output_path(xdmf_), OutputError) << "would collide with its sidecar";
}

TEST_F(OutputTest, CheckOutputPathRejectsAFileAsParent)
{
  std::ofstream(dir_ / "plain") << "x";
  EXPECT_THROW(check_output_path((dir_ / "plain" / "out.h5").string()), OutputError);
}

TEST_F(OutputTest, CheckOutputPathRejectsAColonInTheFileName)
{
  EXPECT_THROW(check_output_path((dir_ / "run:1.h5").string()), OutputError);
  fs::create_directory(dir_ / "a:b");
  EXPECT_NO_THROW(check_output_path((dir_ / "a:b" / "out.h5").string()))
      << "the sidecar names only the basename, so a colon in the directory is harmless";
}

TEST_F(OutputTest, WriteIntoAMissingDirectoryThrowsAndLeavesNothing)
{
  EXPECT_THROW(write_result((dir_ / "missing" / "out.h5").string(), tetrahedron()), OutputError);
  EXPECT_TRUE(listing().empty());
}

TEST_F(OutputTest, WriteIntoAReadOnlyDirectoryThrowsAndLeavesNothing)
{
  if (::geteuid() == 0)
    GTEST_SKIP() << "root can write into a read-only directory";
  ASSERT_EQ(::chmod(dir_.c_str(), 0500), 0);
  EXPECT_THROW(write_result(h5_, tetrahedron()), OutputError);
  ::chmod(dir_.c_str(), 0700);
  EXPECT_TRUE(listing().empty());
}

TEST_F(OutputTest, PlantedEntriesOnTheTemporaryNamesAreSkippedAndKept)
{
  // Before: the temporary name was <final>.tmp.<pid>, opened without O_EXCL: a symlink planted
  // there had its target overwritten. Now every name is created exclusively and a taken one
  // is skipped for the next random one, whatever is on it (a symlink, a directory, a file).
  const std::string victim = (dir_ / "victim").string();
  std::ofstream(victim) << "precious";
  fs::create_symlink(victim, planted_name(h5_, "tmp", "s0"));
  fs::create_directory(planted_name(xdmf_, "tmp", "s1"));
  fs::create_symlink(victim, planted_name(h5_, "bak", "s2"));
  std::ofstream(planted_name(xdmf_, "bak", "s3")) << "someone's";
  const std::size_t before = listing().size();
  for (int round = 0; round < 2; ++round) { // the second round keeps a predecessor under .bak
    int                                   next = 0;
    const detail::TemporarySuffixForTests sequence([&next] { return "s" + std::to_string(next++ % 4); });
    write_result(h5_, tetrahedron());
  }
  EXPECT_EQ(slurp(victim), "precious");
  EXPECT_EQ(listing().size(), before + 2) << "the planted entries stay, the result appears";
  EXPECT_TRUE(fs::is_symlink(planted_name(h5_, "tmp", "s0")));
  EXPECT_TRUE(fs::is_directory(planted_name(xdmf_, "tmp", "s1")));
  Id file{H5Fopen(h5_.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
  EXPECT_GE(file.id, 0);
}

TEST_F(OutputTest, EveryTemporaryNameTakenIsAnErrorThatTouchesNothing)
{
  const std::string victim = (dir_ / "victim").string();
  std::ofstream(victim) << "precious";
  fs::create_symlink(victim, planted_name(h5_, "tmp", "same"));
  const detail::TemporarySuffixForTests same([] { return std::string("same"); });
  try {
    write_result(h5_, tetrahedron());
    FAIL() << "no exception";
  } catch (const OutputError &e) {
    EXPECT_NE(std::string(e.what()).find("cannot create a temporary file beside '" + h5_ + "'"), std::string::npos) << e.what();
  }
  EXPECT_EQ(slurp(victim), "precious");
  EXPECT_EQ(listing().size(), 2u);
}

TEST_F(OutputTest, StaleTemporariesOfDeadProcessesAreSwept)
{
  // Before: a run killed during the write left <final>.tmp.<pid> for ever.
  pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ASSERT_GT(child, 0);
  ::waitpid(child, nullptr, 0); // dead now
  const std::string own  = planted_name(h5_, "tmp", "abc"); // a live process's (this one's)
  const std::string host = host_and_pid().substr(0, host_and_pid().rfind('.'));
  const std::string dead = "." + host + "." + std::to_string(child) + ".abc";
  for (const std::string &name : {h5_ + ".tmp" + dead, xdmf_ + ".tmp" + dead, h5_ + ".bak" + dead, own, h5_ + ".tmp.elsewhere." + std::to_string(child) + ".abc",
                                  (dir_ / "other.h5.tmp").string() + dead})
    std::ofstream(name) << "partial";
  write_result(h5_, tetrahedron());
  const std::string keep_other = "other.h5.tmp" + dead, keep_elsewhere = "out.h5.tmp.elsewhere." + std::to_string(child) + ".abc";
  Strings expected{keep_other, "out.h5", keep_elsewhere, fs::path(own).filename().string(), "out.xdmf"};
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(listing(), expected);
}

TEST_F(OutputTest, AnOutputThatIsAnInputIsRefused)
{
  const std::string mesh = (dir_ / "mesh.off").string(), problem = (dir_ / "p.json").string();
  std::ofstream(mesh) << "OFF";
  std::ofstream(problem) << "{}";
  const std::vector<std::string> inputs{problem, mesh};
  EXPECT_NO_THROW(check_output_path(h5_, inputs));
  EXPECT_THROW(check_output_path(mesh, inputs), OutputError);
  EXPECT_THROW(check_output_path((dir_ / "." / "p.json").string(), inputs), OutputError);
  fs::create_hard_link(mesh, dir_ / "same.h5");
  EXPECT_THROW(check_output_path((dir_ / "same.h5").string(), inputs), OutputError);
  fs::create_symlink(mesh, dir_ / "link.off");
  EXPECT_THROW(check_output_path(mesh, {(dir_ / "link.off").string()}), OutputError) << "the file the link leads to";
  EXPECT_THROW(check_output_path((dir_ / "link.off").string(), {(dir_ / "link.off").string()}), OutputError) << "the link itself";
  std::ofstream(dir_ / "run.xdmf") << "x";
  EXPECT_THROW(check_output_path((dir_ / "run.h5").string(), {(dir_ / "run.xdmf").string()}), OutputError) << "its sidecar";
  ResultData d = tetrahedron();
  d.input_files = inputs;
  EXPECT_THROW(write_result(mesh, d), OutputError);
  EXPECT_EQ(slurp(mesh), "OFF");
}

TEST_F(OutputTest, NonFiniteFieldsAreRefused)
{
  for (double bad : {std::nan(""), HUGE_VAL}) {
    ResultData d = tetrahedron();
    d.traction[2][1] = bad;
    try {
      write_result(h5_, d);
      FAIL() << "no exception";
    } catch (const OutputError &e) {
      EXPECT_NE(std::string(e.what()).find("/fields/traction row 2 holds a non-finite value"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(listing().empty());
  }
}

TEST_F(OutputTest, FailureInsideTheFileRemovesTheTemporaries)
{
  ResultData d = tetrahedron();
  d.attributes_int["nu"] = 3; // clashes with the real attribute "nu"
  try {
    write_result(h5_, d);
    FAIL() << "no exception";
  } catch (const OutputError &e) {
    EXPECT_NE(std::string(e.what()).find("'" + h5_ + "'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("attribute 'nu'"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(listing().empty());
}

TEST_F(OutputTest, FailedWriteKeepsThePreviousResult)
{
  write_result(h5_, tetrahedron());
  const std::string before = slurp(h5_);
  ResultData d = tetrahedron();
  d.attributes_str["E"] = "clash";
  EXPECT_THROW(write_result(h5_, d), OutputError);
  EXPECT_EQ(listing(), (Strings{"out.h5", "out.xdmf"}));
  EXPECT_EQ(slurp(h5_), before);
}

TEST_F(OutputTest, FailureBetweenTheRenamesPutsTheEarlierPairBack)
{
  // The new .h5 is in place when the .xdmf's rename fails: the earlier .h5 must come back, so
  // that the pair on disk is the earlier one, whole.
  write_result(h5_, tetrahedron());
  const std::string h5_before = slurp(h5_), xdmf_before = slurp(xdmf_);
  ResultData d = tetrahedron();
  d.displacement = vectors(9, 4);
  d.interior_points.clear();
  d.interior_displacement.clear();
  arm_fault({"Commit", FaultKind::Error, -1, 0}, 0);
  EXPECT_THROW(write_result(h5_, d), std::runtime_error);
  arm_fault({}, 0);
  EXPECT_EQ(listing(), (Strings{"out.h5", "out.xdmf"}));
  EXPECT_EQ(slurp(h5_), h5_before);
  EXPECT_EQ(slurp(xdmf_), xdmf_before);
  write_result(h5_, d); // and the next write goes through
  EXPECT_NE(slurp(h5_), h5_before);
  EXPECT_EQ(listing(), (Strings{"out.h5", "out.xdmf"}));
}

TEST_F(OutputTest, FailureBetweenTheRenamesLeavesNothingWithoutAPredecessor)
{
  arm_fault({"Commit", FaultKind::Error, -1, 0}, 0);
  EXPECT_THROW(write_result(h5_, tetrahedron()), std::runtime_error);
  arm_fault({}, 0);
  EXPECT_TRUE(listing().empty());
}

TEST_F(OutputTest, FailureBeforeTheCommitKeepsThePreviousResult)
{
  write_result(h5_, tetrahedron());
  const std::string before = slurp(h5_);
  arm_fault({"Write", FaultKind::OutOfMemory, -1, 0}, 0);
  EXPECT_THROW(write_result(h5_, tetrahedron()), std::bad_alloc);
  arm_fault({}, 0);
  EXPECT_EQ(listing(), (Strings{"out.h5", "out.xdmf"}));
  EXPECT_EQ(slurp(h5_), before);
}

TEST_F(OutputTest, InconsistentDataIsRejectedBeforeAnyFileIsCreated)
{
  ResultData short_field = tetrahedron();
  short_field.displacement.pop_back();
  EXPECT_THROW(write_result(h5_, short_field), OutputError);
  ResultData bad_index = tetrahedron();
  bad_index.triangles[2][1] = 4;
  EXPECT_THROW(write_result(h5_, bad_index), OutputError);
  ResultData no_regions = tetrahedron();
  no_regions.triangle_region.clear();
  EXPECT_THROW(write_result(h5_, no_regions), OutputError);
  ResultData nested_name = tetrahedron();
  nested_name.reactions["a/b"] = {0, 0, 0};
  EXPECT_THROW(write_result(h5_, nested_name), OutputError);
  EXPECT_THROW(write_result(h5_, ResultData{}), OutputError);
  EXPECT_TRUE(listing().empty());
}

TEST_F(OutputTest, RestoresHdf5ErrorPrinting)
{
  H5E_auto2_t before = nullptr, after = nullptr;
  void *data_before = nullptr, *data_after = nullptr;
  ASSERT_GE(H5Eget_auto2(H5E_DEFAULT, &before, &data_before), 0);
  ResultData d = tetrahedron();
  d.attributes_int["nu"] = 3;
  EXPECT_THROW(write_result(h5_, d), OutputError);
  ASSERT_GE(H5Eget_auto2(H5E_DEFAULT, &after, &data_after), 0);
  EXPECT_EQ(before, after);
  EXPECT_EQ(data_before, data_after);
}

} // namespace

// ---- FrameWriter: a result written frame by frame ----------------------------------------------

namespace {

/// Frame k of a scene on the tetrahedron: values distinct per frame, field, row and component.
FrameData frame(int k, bool with_mask)
{
  FrameData f;
  f.displacement = vectors(10 + k, 4);
  f.traction = vectors(20 + k, 4);
  if (with_mask)
    f.displacement_prescribed = {{{k % 2 == 0, true, false}}, {{false, false, false}},
                                 {{true, true, true}}, {{false, true, k % 2 == 1}}};
  f.attributes_real = {{"seconds", 0.5 * k + 0.125}};
  f.attributes_int = {{"iterations", 10 + k}, {"switched_unknowns", 3 * k}};
  f.attributes_str = {{"strategy", k == 0 ? "cold" : "warm"}};
  return f;
}

/// A scene of three frames, frame 1 without a displacement_prescribed mask, committed.
void write_scene(const std::string &path)
{
  FrameWriter w(path, tetrahedron());
  for (int k = 0; k < 3; ++k)
    w.append(static_cast<std::size_t>(k), frame(k, k != 1));
  EXPECT_EQ(w.num_frames(), 3u);
  w.commit({{"solve", 2.0}, {"assembly", 9.0}}, {{"num_frames", 3}}, {{"scene_seconds", 4.5}});
}

/// Every start tag has its end tag, in order ("XML-ish": no entities or CDATA are checked).
bool tags_balance(const std::string &x)
{
  std::vector<std::string> open;
  for (std::size_t at = x.find('<'); at != std::string::npos; at = x.find('<', at + 1)) {
    const std::size_t end = x.find('>', at);
    if (end == std::string::npos)
      return false;
    const std::string tag = x.substr(at + 1, end - at - 1);
    if (tag.empty() || tag[0] == '?' || tag[0] == '!' || tag.back() == '/')
      continue;
    const std::string name = tag.substr(tag[0] == '/', tag.find_first_of(" \t\n") - (tag[0] == '/'));
    if (tag[0] != '/')
      open.push_back(name);
    else if (open.empty() || open.back() != name)
      return false;
    else
      open.pop_back();
  }
  return open.empty();
}

} // namespace

TEST_F(OutputTest, FramesAreReadBackWithShapesValuesAndAttributes)
{
  write_scene(h5_);
  EXPECT_EQ(listing(), (Strings{"out.h5", "out.xdmf"}));
  Id file{H5Fopen(h5_.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
  ASSERT_GE(file.id, 0);
  for (int k = 0; k < 3; ++k) {
    const std::string g = "/frames/" + std::to_string(k);
    const FrameData expected = frame(k, k != 1);
    const auto u = read_dataset<double>(file.id, g + "/displacement", H5T_NATIVE_DOUBLE);
    EXPECT_EQ(u.dims, (std::vector<hsize_t>{4, 3})) << g;
    EXPECT_EQ(u.type_class, H5T_FLOAT);
    EXPECT_EQ(u.values, flat(expected.displacement)) << g;
    const auto t = read_dataset<double>(file.id, g + "/traction", H5T_NATIVE_DOUBLE);
    EXPECT_EQ(t.dims, (std::vector<hsize_t>{4, 3})) << g;
    EXPECT_EQ(t.values, flat(expected.traction)) << g;
    ASSERT_EQ(exists(file.id, g + "/displacement_prescribed"), k != 1) << g;
    if (k != 1) {
      const auto m = read_dataset<std::int8_t>(file.id, g + "/displacement_prescribed", H5T_NATIVE_INT8);
      EXPECT_EQ(m.dims, (std::vector<hsize_t>{4, 3}));
      EXPECT_EQ(m.type_size, 1u);
      for (std::size_t r = 0; r < 4; ++r)
        for (std::size_t c = 0; c < 3; ++c)
          EXPECT_EQ(m.values[r * 3 + c], expected.displacement_prescribed[r][c] ? 1 : 0) << g;
    }
    Id group{H5Gopen2(file.id, g.c_str(), H5P_DEFAULT), H5Gclose};
    ASSERT_GE(group.id, 0);
    EXPECT_EQ(read_attribute<double>(group.id, "seconds", H5T_NATIVE_DOUBLE), 0.5 * k + 0.125);
    EXPECT_EQ(read_attribute<long long>(group.id, "iterations", H5T_NATIVE_LLONG), 10 + k);
    EXPECT_EQ(read_attribute<long long>(group.id, "switched_unknowns", H5T_NATIVE_LLONG), 3 * k);
    EXPECT_EQ(read_string_attribute(group.id, "strategy"), k == 0 ? "cold" : "warm");
  }
  EXPECT_FALSE(exists(file.id, "/frames/3"));
  // the base as write_result writes it, and what commit() added
  EXPECT_EQ(read_dataset<double>(file.id, "/fields/displacement", H5T_NATIVE_DOUBLE).values,
            flat(vectors(1, 4)));
  EXPECT_EQ(read_attribute<double>(file.id, "E", H5T_NATIVE_DOUBLE), 210e9);
  EXPECT_EQ(read_attribute<long long>(file.id, "num_frames", H5T_NATIVE_LLONG), 3);
  EXPECT_EQ(read_attribute<double>(file.id, "scene_seconds", H5T_NATIVE_DOUBLE), 4.5);
  Id timings{H5Gopen2(file.id, "/timings", H5P_DEFAULT), H5Gclose};
  ASSERT_GE(timings.id, 0);
  EXPECT_EQ(read_attribute<double>(timings.id, "assembly", H5T_NATIVE_DOUBLE), 9.0); // commit's wins
  EXPECT_EQ(read_attribute<double>(timings.id, "solve", H5T_NATIVE_DOUBLE), 2.0);
}

TEST_F(OutputTest, FramesAreOnlyInTheTemporaryFileBeforeCommit)
{
  FrameWriter w(h5_, tetrahedron());
  const Strings only_temp{"out.h5.tmp." + host_and_pid(), "out.xdmf.tmp." + host_and_pid()};
  EXPECT_EQ(stems(), only_temp);
  const auto before = fs::file_size(temp_of(h5_));
  w.append(0, frame(0, true));
  w.append(1, frame(1, true));
  EXPECT_EQ(stems(), only_temp);
  EXPECT_GT(fs::file_size(temp_of(h5_)), before + 2 * 2 * 4 * 3 * sizeof(double)) << "not flushed";
  w.commit({});
  EXPECT_EQ(listing(), (Strings{"out.h5", "out.xdmf"}));
}

TEST_F(OutputTest, FrameWriterWithoutCommitLeavesNothing)
{
  {
    FrameWriter w(h5_, tetrahedron());
    w.append(0, frame(0, true));
  }
  EXPECT_TRUE(listing().empty());
}

TEST_F(OutputTest, FrameWriterWithoutCommitKeepsThePreviousResult)
{
  write_result(h5_, tetrahedron());
  const std::string h5_before = slurp(h5_), xdmf_before = slurp(xdmf_);
  try {
    FrameWriter w(h5_, tetrahedron());
    w.append(0, frame(0, false));
    throw std::runtime_error("the solve of frame 1 failed");
  } catch (const std::runtime_error &) {
  }
  EXPECT_EQ(listing(), (Strings{"out.h5", "out.xdmf"}));
  EXPECT_EQ(slurp(h5_), h5_before);
  EXPECT_EQ(slurp(xdmf_), xdmf_before);
}

TEST_F(OutputTest, FrameSidecarIsATemporalCollection)
{
  write_scene(h5_);
  const std::string x = slurp(xdmf_);
  EXPECT_TRUE(tags_balance(x)) << x;
  EXPECT_EQ(x.rfind("<?xml", 0), 0u);
  EXPECT_EQ(occurrences(x, R"(GridType="Collection" CollectionType="Temporal")"), 1u) << x;
  EXPECT_EQ(occurrences(x, R"(GridType="Uniform")"), 3u);
  for (int k = 0; k < 3; ++k) {
    const std::string g = "/frames/" + std::to_string(k);
    EXPECT_NE(x.find("<Time Value=\"" + std::to_string(k) + "\"/>"), std::string::npos) << k;
    EXPECT_NE(x.find(">out.h5:" + g + "/displacement</DataItem>"), std::string::npos) << g;
    EXPECT_NE(x.find(">out.h5:" + g + "/traction</DataItem>"), std::string::npos) << g;
    EXPECT_EQ(x.find(">out.h5:" + g + "/displacement_prescribed</DataItem>") != std::string::npos, k != 1) << g;
  }
  EXPECT_EQ(occurrences(x, ">out.h5:/mesh/vertices</DataItem>"), 3u);
  EXPECT_EQ(occurrences(x, ">out.h5:/mesh/triangles</DataItem>"), 3u);
  EXPECT_EQ(x.find("/fields/"), std::string::npos) << "the base grid is left out of the sidecar";
  EXPECT_EQ(x.find(dir_.string()), std::string::npos) << "reference must be relative";
}

TEST_F(OutputTest, FrameWriterWithoutFramesWritesTheBaseSidecar)
{
  FrameWriter w(h5_, tetrahedron());
  w.commit({{"solve", 1.0}});
  const std::string x = slurp(xdmf_);
  EXPECT_TRUE(tags_balance(x)) << x;
  EXPECT_EQ(x.find("Temporal"), std::string::npos);
  EXPECT_NE(x.find(">out.h5:/fields/displacement</DataItem>"), std::string::npos) << x;
}

TEST_F(OutputTest, AppendRefusesAWrongIndexOrSize)
{
  const auto expect_refused = [](const std::function<void()> &f, const std::string &words) {
    try {
      f();
      ADD_FAILURE() << "no OutputError; expected one mentioning " << words;
    } catch (const OutputError &e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  FrameWriter w(h5_, tetrahedron());
  expect_refused([&] { w.append(1, frame(1, true)); }, "frame 1 appended after 0 frames");
  FrameData short_u = frame(0, true);
  short_u.displacement.pop_back();
  expect_refused([&] { w.append(0, short_u); }, "/frames/0/displacement has 3 entries, expected 4");
  FrameData no_t = frame(0, true);
  no_t.traction.clear();
  expect_refused([&] { w.append(0, no_t); }, "/frames/0/traction has 0 entries");
  FrameData long_mask = frame(0, true);
  long_mask.displacement_prescribed.push_back({{true, true, true}});
  expect_refused([&] { w.append(0, long_mask); }, "/frames/0/displacement_prescribed has 5 entries");
  w.append(0, frame(0, true)); // the refusals wrote nothing
  expect_refused([&] { w.append(0, frame(0, true)); }, "frame 0 appended after 1 frames");
  expect_refused([&] { w.append(2, frame(2, true)); }, "frame 2 appended after 1 frames");
  w.append(1, frame(1, true));
  w.commit({});
  expect_refused([&] { w.append(2, frame(2, true)); }, "after commit()");
  Id file{H5Fopen(h5_.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
  ASSERT_GE(file.id, 0);
  EXPECT_TRUE(exists(file.id, "/frames/1/traction"));
  EXPECT_FALSE(exists(file.id, "/frames/2"));
}

TEST_F(OutputTest, FailedFrameCommitRemovesTheTemporariesAndKeepsThePreviousResult)
{
  write_result(h5_, tetrahedron());
  const std::string before = slurp(h5_);
  {
    FrameWriter w(h5_, tetrahedron());
    w.append(0, frame(0, true));
    try {
      w.commit({}, {{"iterations", 3}}); // the base has a root attribute "iterations"
      ADD_FAILURE() << "no exception";
    } catch (const OutputError &e) {
      EXPECT_NE(std::string(e.what()).find("'" + h5_ + "'"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("attribute 'iterations'"), std::string::npos) << e.what();
    }
    EXPECT_THROW(w.append(1, frame(1, true)), OutputError);
  }
  EXPECT_EQ(listing(), (Strings{"out.h5", "out.xdmf"}));
  EXPECT_EQ(slurp(h5_), before);
}

TEST_F(OutputTest, FrameWriterRefusesInconsistentBaseBeforeAnyFileIsCreated)
{
  ResultData short_field = tetrahedron();
  short_field.traction.pop_back();
  EXPECT_THROW(FrameWriter(h5_, short_field), OutputError);
  EXPECT_THROW(FrameWriter((dir_ / "missing" / "out.h5").string(), tetrahedron()), OutputError);
  EXPECT_TRUE(listing().empty());
}

// --- stress: surface fields, interior stress, the interior grid -------------------------------

namespace {

std::vector<Voigt> voigts(int field, std::size_t n)
{
  std::vector<Voigt> v(n);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t k = 0; k < 6; ++k) v[i][k] = value(field, i, k);
  return v;
}

std::vector<double> flat6(const std::vector<Voigt> &v)
{
  std::vector<double> out;
  for (const Voigt &s : v) out.insert(out.end(), s.begin(), s.end());
  return out;
}

/// The tetrahedron with stress fields, interior stress and a 3 x 2 x 2 grid.
ResultData tetrahedron_with_stress()
{
  ResultData d = tetrahedron();
  d.stress.stress = voigts(6, 4);
  d.stress.von_mises = {1, 2, 3, 4};
  d.stress.principal = vectors(7, 4);
  d.stress.corner.resize(4);
  for (std::size_t t = 0; t < 4; ++t) d.stress.corner[t] = {voigts(8, 3)[0], voigts(8, 3)[1], voigts(8, 3)[2]};
  d.interior_stress = voigts(9, 2);
  d.interior_von_mises = {5, 6};
  InteriorGridData &g = d.interior_grid;
  g.origin = {0.1, 0.2, 0.3};
  g.spacing = {0.5, 0.25, 0.125};
  g.points = {3, 2, 2};
  g.displacement = vectors(10, 12);
  g.stress = voigts(11, 12);
  g.von_mises.assign(12, 7.0);
  g.inside = {1, 1, 0, 1, 0, 1, 1, 1, 0, 0, 1, 1};
  return d;
}

} // namespace

TEST_F(OutputTest, StressAndGridDatasets)
{
  const ResultData d = tetrahedron_with_stress();
  write_result(h5_, d);
  Id file{H5Fopen(h5_.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
  ASSERT_GE(file.id, 0);
  const auto s = read_dataset<double>(file.id, "/fields/stress", H5T_NATIVE_DOUBLE);
  EXPECT_EQ(s.dims, (std::vector<hsize_t>{4, 6}));
  EXPECT_EQ(s.values, flat6(d.stress.stress));
  EXPECT_EQ(read_dataset<double>(file.id, "/fields/von_mises", H5T_NATIVE_DOUBLE).values, d.stress.von_mises);
  EXPECT_EQ(read_dataset<double>(file.id, "/fields/principal_stress", H5T_NATIVE_DOUBLE).values, flat(d.stress.principal));
  EXPECT_EQ(read_dataset<double>(file.id, "/fields/stress_corner", H5T_NATIVE_DOUBLE).dims, (std::vector<hsize_t>{4, 3, 6}));
  EXPECT_EQ(read_dataset<double>(file.id, "/interior/stress", H5T_NATIVE_DOUBLE).values, flat6(d.interior_stress));
  EXPECT_EQ(read_dataset<double>(file.id, "/interior/von_mises", H5T_NATIVE_DOUBLE).values, d.interior_von_mises);
  const auto gs = read_dataset<double>(file.id, "/interior/grid/stress", H5T_NATIVE_DOUBLE);
  EXPECT_EQ(gs.dims, (std::vector<hsize_t>{2, 2, 3, 6})); // z, y, x, components
  EXPECT_EQ(gs.values, flat6(d.interior_grid.stress));
  EXPECT_EQ(read_dataset<double>(file.id, "/interior/grid/displacement", H5T_NATIVE_DOUBLE).dims, (std::vector<hsize_t>{2, 2, 3, 3}));
  EXPECT_EQ(read_dataset<double>(file.id, "/interior/grid/y", H5T_NATIVE_DOUBLE).values, (std::vector<double>{0.2, 0.45}));
  const auto inside = read_dataset<int>(file.id, "/interior/grid/inside", H5T_NATIVE_INT);
  EXPECT_EQ(inside.type_size, 1u);
  EXPECT_EQ(inside.values, d.interior_grid.inside);
  Id grid{H5Gopen2(file.id, "/interior/grid", H5P_DEFAULT), H5Gclose};
  EXPECT_EQ(read_attribute<double>(grid.id, "spacing_z", H5T_NATIVE_DOUBLE), 0.125);
  EXPECT_EQ(read_attribute<long long>(grid.id, "points_x", H5T_NATIVE_LLONG), 3);
  const std::string x = slurp(xdmf_);
  EXPECT_NE(x.find(R"(<Grid Name="interior_grid" GridType="Uniform">)"), std::string::npos) << x;
  EXPECT_NE(x.find(R"(<Topology TopologyType="3DRectMesh" Dimensions="2 2 3"/>)"), std::string::npos) << x;
  // The Voigt stress as one 6-component attribute, plain HDF items only (what meshio reads).
  EXPECT_NE(x.find(R"(<Attribute Name="stress" AttributeType="Matrix" Center="Node">)"), std::string::npos) << x;
  EXPECT_NE(x.find(R"(Dimensions="2 2 3 6" NumberType="Float" Precision="8">out.h5:/interior/grid/stress</DataItem>)"), std::string::npos) << x;
  EXPECT_NE(x.find(R"(Dimensions="4 6" NumberType="Float" Precision="8">out.h5:/fields/stress</DataItem>)"), std::string::npos) << x;
  EXPECT_EQ(x.find("HyperSlab"), std::string::npos) << x;
  EXPECT_EQ(occurrences(x, "<DataItem "), occurrences(x, "</DataItem>"));
  EXPECT_EQ(occurrences(x, "<Grid "), occurrences(x, "</Grid>"));
}

TEST_F(OutputTest, InconsistentStressIsRejectedBeforeAnyFileIsCreated)
{
  ResultData a = tetrahedron_with_stress();
  a.stress.von_mises.pop_back();
  EXPECT_THROW(write_result(h5_, a), OutputError);
  ResultData b = tetrahedron_with_stress();
  b.interior_stress.pop_back();
  EXPECT_THROW(write_result(h5_, b), OutputError);
  ResultData c = tetrahedron_with_stress();
  c.interior_grid.inside.pop_back();
  EXPECT_THROW(write_result(h5_, c), OutputError);
  ResultData e = tetrahedron_with_stress();
  e.interior_grid.spacing[1] = 0;
  EXPECT_THROW(write_result(h5_, e), OutputError);
  EXPECT_TRUE(listing().empty());
}

namespace {

/// The tetrahedron with two obstacles: a plane's patch of two triangles and a "tool" mesh.
ResultData tetrahedron_with_obstacles()
{
  ResultData d = tetrahedron();
  d.obstacles.push_back({"table", "plane", {{-1, -1, -1}, {2, -1, -1}, {2, 2, -1}, {-1, 2, -1}}, {{0, 1, 2}, {0, 2, 3}}});
  d.obstacles.push_back({"tool", "mesh", {{0, 0, 2}, {1, 0, 2}, {0, 1, 2}}, {{0, 2, 1}}});
  return d;
}

std::vector<std::vector<Vec3>> moved(const ResultData &d, double dz)
{
  std::vector<std::vector<Vec3>> out;
  for (const ObstacleSurface &o : d.obstacles) {
    out.emplace_back();
    for (const Vec3 &v : o.vertices) out.back().push_back(v + Vec3{0, 0, dz});
  }
  return out;
}

std::string output_error(const std::function<void()> &write)
{
  try {
    write();
  } catch (const OutputError &e) {
    return e.what();
  }
  return "no error";
}

} // namespace

TEST_F(OutputTest, ObstaclesAreWrittenAndShownBesideTheBody)
{
  const ResultData d = tetrahedron_with_obstacles();
  write_result(h5_, d);
  {
    Id file{H5Fopen(h5_.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
    const auto v = read_dataset<double>(file.id, "/obstacles/table/vertices", H5T_NATIVE_DOUBLE);
    EXPECT_EQ(v.dims, (std::vector<hsize_t>{4, 3}));
    EXPECT_EQ(v.values, flat(d.obstacles[0].vertices));
    const auto t = read_dataset<int>(file.id, "/obstacles/tool/triangles", H5T_NATIVE_INT);
    EXPECT_EQ(t.dims, (std::vector<hsize_t>{1, 3}));
    EXPECT_EQ(t.values, (std::vector<int>{0, 2, 1}));
    Id g{H5Gopen2(file.id, "/obstacles/table", H5P_DEFAULT), H5Gclose};
    EXPECT_EQ(read_string_attribute(g.id, "shape"), "plane");
  }
  const std::string x = slurp(xdmf_);
  EXPECT_LT(x.find(R"(<Grid Name="hssbem" GridType="Uniform">)"), x.find(R"(<Grid Name="obstacle table" GridType="Uniform">)")) << x; // the body first
  EXPECT_NE(x.find(R"(<DataItem Format="HDF" Dimensions="2 3" NumberType="Int" Precision="4">out.h5:/obstacles/table/triangles</DataItem>)"), std::string::npos) << x;
  EXPECT_NE(x.find(R"(<DataItem Format="HDF" Dimensions="3 3" NumberType="Float" Precision="8">out.h5:/obstacles/tool/vertices</DataItem>)"), std::string::npos) << x;
  EXPECT_EQ(occurrences(x, "<Grid "), occurrences(x, "</Grid>"));
}

TEST_F(OutputTest, FramesCarryTheObstaclesPlaces)
{
  const ResultData base = tetrahedron_with_obstacles();
  {
    FrameWriter w(h5_, base);
    for (int k = 0; k < 3; ++k) {
      FrameData f = frame(k, false);
      if (k != 1) f.obstacle_vertices = moved(base, 0.1 * k); // frame 1: none given, the base position shown
      w.append(static_cast<std::size_t>(k), f);
    }
    w.commit({});
  }
  Id file{H5Fopen(h5_.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
  EXPECT_EQ(read_dataset<double>(file.id, "/frames/2/obstacles/tool/vertices", H5T_NATIVE_DOUBLE).values, flat(moved(base, 0.2)[1]));
  EXPECT_FALSE(exists(file.id, "/frames/1/obstacles"));
  const std::string x = slurp(xdmf_);
  const auto tool = x.find(R"(<Grid Name="obstacle tool" GridType="Collection" CollectionType="Temporal">)"), frames = x.find(R"(<Grid Name="frames" GridType="Collection")");
  ASSERT_NE(tool, std::string::npos) << x;
  EXPECT_LT(tool, frames); // the body's collection last: the one a reader of one collection takes
  EXPECT_NE(x.find("out.h5:/frames/2/obstacles/tool/vertices"), std::string::npos) << x;
  EXPECT_NE(x.find("out.h5:/frames/0/obstacles/table/vertices"), std::string::npos) << x;
  EXPECT_EQ(occurrences(x, "out.h5:/obstacles/tool/vertices"), 1u) << x; // frame 1 shows the base position
  EXPECT_EQ(occurrences(x, "<Grid "), occurrences(x, "</Grid>"));
}

TEST_F(OutputTest, ObstaclesThatCannotBeWrittenAreRefused)
{
  for (const std::string &name : {std::string("a/b"), std::string("a:b"), std::string("."), std::string(".."), std::string(""), std::string("tab\tle")}) {
    ResultData d = tetrahedron_with_obstacles();
    d.obstacles[1].name = name;
    EXPECT_NE(output_error([&] { write_result(h5_, d); }).find("obstacle name '" + name + "' cannot name the group /obstacles/<name>"), std::string::npos) << name;
  }
  ResultData twice = tetrahedron_with_obstacles();
  twice.obstacles[1].name = "table";
  EXPECT_NE(output_error([&] { write_result(h5_, twice); }).find("two obstacles are named 'table'"), std::string::npos);
  ResultData out_of_range = tetrahedron_with_obstacles();
  out_of_range.obstacles[1].triangles[0][2] = 3;
  EXPECT_NE(output_error([&] { write_result(h5_, out_of_range); }).find("/obstacles/tool/triangles row 0 refers to vertex 3 of 3"), std::string::npos);
  ResultData nan = tetrahedron_with_obstacles();
  nan.obstacles[0].vertices[2][1] = std::nan("");
  EXPECT_NE(output_error([&] { write_result(h5_, nan); }).find("/obstacles/table/vertices row 2 holds a non-finite value"), std::string::npos);
  const ResultData base = tetrahedron_with_obstacles();
  FrameWriter w(h5_, base);
  FrameData f = frame(0, false);
  f.obstacle_vertices = moved(base, 0.1);
  f.obstacle_vertices[1].pop_back();
  EXPECT_NE(output_error([&] { w.append(0, f); }).find("/frames/0/obstacles/tool/vertices has 2 entries, expected 3"), std::string::npos);
  f.obstacle_vertices = moved(base, 0.1);
  f.obstacle_vertices[0][0][0] = HUGE_VAL;
  EXPECT_NE(output_error([&] { w.append(0, f); }).find("/frames/0/obstacles/table/vertices row 0 holds a non-finite value (inf)"), std::string::npos);
  EXPECT_EQ(w.num_frames(), 0u); // refused frames leave the file as it was
}

TEST_F(OutputTest, EveryWrittenFieldIsCheckedFinite)
{
  // The stress on the surface and inside, the grid (where it is inside the body), the contact's
  // fields and forces, and the same in a frame: each names its dataset (and frame); nothing is
  // written. A NaN where the layout means "none" passes: a gap with no obstacle within reach,
  // the grid outside the body.
  const double nan = std::nan("");
  const std::vector<std::pair<std::string, std::function<void(ResultData &)>>> cases{
      {"/fields/stress row 1", [&](ResultData &d) { d.stress.stress[1][3] = nan; }},
      {"/fields/von_mises row 3", [&](ResultData &d) { d.stress.von_mises[3] = HUGE_VAL; }},
      {"/fields/principal_stress row 0", [&](ResultData &d) { d.stress.principal[0][2] = nan; }},
      {"/fields/stress_corner[2] row 1", [&](ResultData &d) { d.stress.corner[2][1][0] = nan; }},
      {"/interior/stress row 1", [&](ResultData &d) { d.interior_stress[1][5] = nan; }},
      {"/interior/von_mises row 0", [&](ResultData &d) { d.interior_von_mises[0] = nan; }},
      {"/interior/grid/displacement row 0", [&](ResultData &d) { d.interior_grid.displacement[0][1] = nan; }},
      {"/interior/grid/stress row 5", [&](ResultData &d) { d.interior_grid.stress[5][0] = nan; }},
      {"/interior/grid/von_mises row 11", [&](ResultData &d) { d.interior_grid.von_mises[11] = nan; }},
      {"/contact/pressure row 2", [&](ResultData &d) { d.contact.pressure[2] = nan; }},
      {"/contact/gap row 1", [&](ResultData &d) { d.contact.gap[1] = -HUGE_VAL; }},
      {"/contact/forces/tool row 0", [&](ResultData &d) { d.contact.forces["tool"][0] = nan; }}};
  auto with_contact = [] {
    ResultData d = tetrahedron_with_stress();
    d.contact.pressure = {0, 1, 2, 0};
    d.contact.gap = {std::nan(""), 0, 0, 0.5};
    d.contact.status = {0, 2, 2, 0};
    d.contact.forces = {{"tool", Vec3{0, 0, 1}}};
    d.interior_grid.displacement[2] = {std::nan(""), std::nan(""), std::nan("")}; // outside (inside[2] = 0)
    d.interior_grid.stress[2][0] = std::nan("");
    return d;
  };
  write_result(h5_, with_contact()); // NaN gaps and NaN outside the grid's body pass
  fs::remove(h5_), fs::remove(xdmf_);
  for (const auto &[dataset, spoil] : cases) {
    ResultData d = with_contact();
    spoil(d);
    const std::string e = output_error([&] { write_result(h5_, d); });
    EXPECT_NE(e.find(dataset + " holds a non-finite value"), std::string::npos) << dataset << ": " << e;
    EXPECT_TRUE(listing().empty()) << dataset;
  }
  FrameWriter w(h5_, tetrahedron());
  FrameData f = frame(0, false);
  f.stress.von_mises = {1, 2, nan, 4};
  EXPECT_NE(output_error([&] { w.append(0, f); }).find("/frames/0/von_mises row 2 holds a non-finite value (nan)"), std::string::npos);
  f = frame(0, false);
  f.contact.pressure = {0, 0, HUGE_VAL, 0}, f.contact.gap.assign(4, 0), f.contact.status.assign(4, 0);
  EXPECT_NE(output_error([&] { w.append(0, f); }).find("/frames/0/contact/pressure row 2 holds a non-finite value (inf)"), std::string::npos);
}
