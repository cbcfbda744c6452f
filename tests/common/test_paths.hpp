#pragma once
/// Where the tests find the shipped meshes (meshes/), their own data (tests/data/) and the
/// fuzzers' corpora (tests/fuzz/). The directories are compiled into one small object
/// (test_paths.cpp, configured by tests/CMakeLists.txt), not into every test's code: a test's
/// object then does not depend on where the tree was checked out, so a compiler cache serves it
/// to any clone (CI).

namespace hssbem_test {
const char *meshes_dir(); ///< the source tree's meshes/
const char *data_dir();   ///< the source tree's tests/data/
const char *fuzz_dir();   ///< the source tree's tests/fuzz/
} // namespace hssbem_test

#define HSSBEM_MESHES (::hssbem_test::meshes_dir())
#define HSSBEM_TEST_DATA (::hssbem_test::data_dir())
#define HSSBEM_FUZZ_DIR (::hssbem_test::fuzz_dir())
