// The fuzzed entry points, shared by the libFuzzer harnesses (fuzz_entry.cpp) and the regression
// test of the main build (test_fuzz_regressions.cpp): each reads one input as a user's file would
// be read, and may only fail with the reader's own error (MeshError, ProblemError). Anything
// else — another exception, a crash, a sanitizer report — is a bug. (Saved precomputations:
// SavedFileError.)
#pragma once

#include "hssbem/core/packed.hpp"
#include "hssbem/io/saved_file.hpp"
#include "hssbem/mesh/mesh.hpp"
#include "hssbem/problem/problem.hpp"

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

namespace hssbem::fuzz {

/// A mesh file as the driver reads it: parse, then validate and orient.
inline void mesh_input(const std::string &bytes, const char *name)
{
  try {
    SurfaceMesh              mesh = parse_mesh(bytes, name);
    std::vector<std::string> notices;
    validate_and_orient(mesh, notices);
  } catch (const MeshError &) {
  }
}

/// A closed tetrahedron with two regions, for the problem file's rules to select from.
inline SurfaceMesh rule_mesh()
{
  SurfaceMesh m;
  m.vertices        = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.triangles       = {{{0, 2, 1}}, {{0, 1, 3}}, {{0, 3, 2}}, {{1, 2, 3}}};
  m.triangle_region = {1, 1, 2, 2};
  m.region_tags     = {{"base", 1}, {"top", 2}};
  return m;
}

/// A problem file: parse, then apply its rules to a small mesh.
inline void problem_input(const std::string &bytes)
{
  try {
    const ProblemSpec spec = parse_problem(bytes, "fuzz.json");
    (void)apply_rules(spec.rules, rule_mesh(), spec.file);
  } catch (const ProblemError &) {
  }
}

/// A saved precomputation as -hssbem_load reads it (the reader takes a path: the bytes go to a
/// file of this process first): the header, length and checksum, then HDF5 and the arrays and
/// attributes a contact's load reads. It may only fail with SavedFileError.
inline void saved_input(const std::string &bytes)
{
  const std::string path = "/tmp/hssbem_fuzz_saved." + std::to_string(::getpid());
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  try {
    const SavedFileReader r(path, "contact precomputation", 2);
    (void)r.text("fingerprint_version");
    (void)r.chars("on_h2");
    (void)r.ints("reference/piv");
    (void)r.doubles("reference/lu");
  } catch (const SavedFileError &) {
  }
  std::remove(path.c_str());
}

/// The packed streams of a saved H2 precomputation (core/packed.hpp, session/h2_file.hpp): the
/// bytes cut in three (integers, floats, doubles), then read as the unpacking reads, each step
/// chosen by the next integer, until the streams end. It may only fail with std::invalid_argument.
inline void packed_input(const std::string &bytes)
{
  PackedArrays a;
  const std::size_t third = bytes.size() / 3;
  a.i.resize(third / sizeof(int)), a.f.resize(third / sizeof(float)), a.d.resize((bytes.size() - 2 * third) / sizeof(double));
  if (!a.i.empty()) std::memcpy(a.i.data(), bytes.data(), a.i.size() * sizeof(int)); // (no memcpy to an empty vector's null data)
  if (!a.f.empty()) std::memcpy(a.f.data(), bytes.data() + third, a.f.size() * sizeof(float));
  if (!a.d.empty()) std::memcpy(a.d.data(), bytes.data() + 2 * third, a.d.size() * sizeof(double));
  PackReader r(a);
  std::vector<int> vi;
  std::vector<float> vf;
  std::vector<double> vd;
  DenseMatrix M;
  try {
    while (!r.done()) { // every step reads at least one integer
      switch (static_cast<unsigned>(r.get_int()) % 6) {
      case 0: (void)r.get_int(-1, 100, "value"); break;
      case 1: (void)r.get_double(); break;
      case 2: r.get(vi); break;
      case 3: r.get(vf); break;
      case 4: r.get(vd); break;
      default: r.get(M); break;
      }
    }
  } catch (const std::invalid_argument &) {
  }
}

inline void fuzz_msh(const std::string &b) { mesh_input(b, "fuzz.msh"); }
inline void fuzz_stl(const std::string &b) { mesh_input(b, "fuzz.stl"); }
inline void fuzz_off(const std::string &b) { mesh_input(b, "fuzz.off"); }
inline void fuzz_obj(const std::string &b) { mesh_input(b, "fuzz.obj"); }
inline void fuzz_problem(const std::string &b) { problem_input(b); }
inline void fuzz_saved(const std::string &b) { saved_input(b); }
inline void fuzz_packed(const std::string &b) { packed_input(b); }

} // namespace hssbem::fuzz
