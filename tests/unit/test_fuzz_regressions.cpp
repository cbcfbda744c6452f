/// \file test_fuzz_regressions.cpp
/// Replays every input kept in tests/fuzz/regressions/<harness>/ (crashes the fuzzers found,
/// fixed), the committed corpora (tests/fuzz/corpus/<harness>/) and the shipped meshes and
/// examples through the fuzzers' entry points (tests/fuzz/fuzz_targets.hpp): each may fail only
/// with the reader's own error.
#include "fuzz_targets.hpp"
#include "test_paths.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path &p)
{
  std::ifstream      in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Runs `entry` on every file of `dir` (if it exists); returns how many.
int replay(const fs::path &dir, void (*entry)(const std::string &))
{
  int n = 0;
  if (!fs::is_directory(dir)) return 0;
  for (const auto &f : fs::directory_iterator(dir)) {
    if (!f.is_regular_file()) continue;
    SCOPED_TRACE(f.path().string());
    EXPECT_NO_THROW(entry(slurp(f.path())));
    ++n;
  }
  return n;
}

const fs::path regressions = fs::path(HSSBEM_FUZZ_DIR) / "regressions";
const fs::path corpus      = fs::path(HSSBEM_FUZZ_DIR) / "corpus";

/// The committed corpora hold a few hundred inputs each (tests/fuzz/run_fuzzers.sh --grow):
/// fewer would mean a corpus lost.
constexpr int k_min_corpus = 100;

TEST(FuzzRegressions, MeshInputs)
{
  using namespace hssbem::fuzz;
  replay(regressions / "msh", fuzz_msh);
  replay(regressions / "stl", fuzz_stl);
  replay(regressions / "off", fuzz_off);
  replay(regressions / "obj", fuzz_obj);
  EXPECT_GE(replay(HSSBEM_MESHES, fuzz_msh), 10); // the shipped meshes, as seeds are
}

TEST(FuzzRegressions, Corpora)
{
  using namespace hssbem::fuzz;
  EXPECT_GE(replay(corpus / "msh", fuzz_msh), k_min_corpus);
  EXPECT_GE(replay(corpus / "stl", fuzz_stl), k_min_corpus);
  EXPECT_GE(replay(corpus / "off", fuzz_off), k_min_corpus);
  EXPECT_GE(replay(corpus / "obj", fuzz_obj), k_min_corpus);
  EXPECT_GE(replay(corpus / "problem", fuzz_problem), k_min_corpus);
}

TEST(FuzzRegressions, SavedInputs)
{
  using namespace hssbem::fuzz;
  replay(regressions / "saved", fuzz_saved);
  replay(corpus / "saved", fuzz_saved);
  const fs::path seeds = fs::temp_directory_path() / ("hssbem_saved_seeds." + std::to_string(::getpid()));
  ASSERT_EQ(std::system(("/usr/bin/python3 " + (fs::path(HSSBEM_FUZZ_DIR) / "make_seeds.py").string() + " " + seeds.string() + " > /dev/null").c_str()), 0);
  EXPECT_GE(replay(seeds / "saved", fuzz_saved), 6);
  fs::remove_all(seeds);
}

TEST(FuzzRegressions, PackedInputs)
{
  using namespace hssbem::fuzz;
  replay(regressions / "packed", fuzz_packed);
  replay(corpus / "packed", fuzz_packed);
}

TEST(FuzzRegressions, PackedStreamsRoundTripAndRefuseDamage)
{
  hssbem::PackedArrays a;
  hssbem::PackWriter w(a);
  hssbem::DenseMatrix M(2, 3);
  M(1, 2) = 7.5;
  w.put(3), w.put(std::vector<int>{4, 5}), w.put(std::vector<float>{1.5f}), w.put(M);
  {
    hssbem::PackReader r(a);
    std::vector<int> v;
    std::vector<float> f;
    hssbem::DenseMatrix back;
    EXPECT_EQ(r.get_int(0, 10, "value"), 3);
    r.get(v), r.get(f), r.get(back);
    EXPECT_EQ(v, (std::vector<int>{4, 5}));
    EXPECT_EQ(f, (std::vector<float>{1.5f}));
    EXPECT_EQ(back.m, 2);
    EXPECT_EQ(back.a, M.a);
    EXPECT_TRUE(r.done());
  }
  // a stream that ends early, a negative length, a length past the end, a value out of range,
  // entries that do not fit a matrix's sizes: refused (std::invalid_argument), never read
  const auto refused = [](hssbem::PackedArrays p, int step) {
    hssbem::PackReader r(p);
    std::vector<double> d;
    hssbem::DenseMatrix m;
    if (step == 0) EXPECT_THROW(r.get(d), std::invalid_argument);
    if (step == 1) EXPECT_THROW(r.get_int(0, 1, "value"), std::invalid_argument);
    if (step == 2) EXPECT_THROW(r.get(m), std::invalid_argument);
  };
  refused({{}, {}, {}}, 0);
  refused({{}, {}, {-1}}, 0);
  refused({{1.0}, {}, {2}}, 0);
  refused({{}, {}, {5}}, 1);
  refused({{1.0, 2.0}, {}, {2, 2, 2}}, 2);
}

TEST(FuzzRegressions, ProblemInputs)
{
  using namespace hssbem::fuzz;
  replay(regressions / "problem", fuzz_problem);
  EXPECT_GE(replay(fs::path(HSSBEM_MESHES) / "examples", fuzz_problem), 5);
}

} // namespace
