/// \file test_size_limits.cpp
/// The size check: which problems each operator path refuses, and that the refusal names the
/// size and a path that can take it; -bem_mat_type auto's choice.
#include "hssbem/app/options.hpp"
#include "hssbem/core/size_limits.hpp"

#include <gtest/gtest.h>

using namespace hssbem;

namespace {

MachineLimits machine(double gib, int ranks = 1, int per_node = 1)
{
  MachineLimits m;
  m.node_memory_bytes = gib * 1073741824.0;
  m.ranks             = ranks;
  m.ranks_per_node    = per_node;
  m.index_max         = 2147483647;
  return m;
}

TEST(SizeLimits, DenseBeyondTheIndexWidthIsRefusedNamingH2)
{
  // 47 000 unknowns on one rank: 2.2e9 entries, more than a 32-bit PetscInt indexes (and the
  // memory would not suffice either on 24 GiB; with 1 TiB only the index width refuses).
  const std::string why = size_refusal(OperatorType::Dense, 47001, SizeOptions{}, machine(1024));
  EXPECT_NE(why.find("47001 unknowns"), std::string::npos) << why;
  EXPECT_NE(why.find("32-bit PetscInt"), std::string::npos) << why;
  EXPECT_NE(why.find("use -bem_mat_type h2"), std::string::npos) << why;
  // Split over 4 ranks the blocks fit the index width.
  EXPECT_EQ(size_refusal(OperatorType::Dense, 47001, SizeOptions{}, machine(1024, 4, 1)), "");
}

TEST(SizeLimits, DenseBeyondMemoryIsRefused)
{
  EXPECT_EQ(size_refusal(OperatorType::Dense, 30000, SizeOptions{}, machine(24)), ""); // 14.4 GB
  const std::string why = size_refusal(OperatorType::Dense, 42000, SizeOptions{}, machine(24)); // 28 GB
  EXPECT_NE(why.find("needs about 28.2 GB per node"), std::string::npos) << why;
  EXPECT_NE(why.find("use -bem_mat_type h2"), std::string::npos) << why;
  // Two ranks on one node share its memory: no help; on two nodes each holds half.
  EXPECT_NE(size_refusal(OperatorType::Dense, 42000, SizeOptions{}, machine(24, 2, 2)), "");
  EXPECT_EQ(size_refusal(OperatorType::Dense, 42000, SizeOptions{}, machine(24, 2, 1)), "");
}

TEST(SizeLimits, H2SuggestsSinglePrecisionThenJacobiThenALooserToleranceThenNothing)
{
  const SizeOptions dbl{false, 1e-5, true}, single{true, 1e-5, true}, jacobi{true, 1e-5, false};
  // Double precision with PC h2: 150k fits 24 GiB (13.1 GB); 350k (29.9 GB) does in single (23.4 GB).
  EXPECT_EQ(size_refusal(OperatorType::H2, 150000, dbl, machine(24)), "");
  const std::string s1 = size_refusal(OperatorType::H2, 350000, dbl, machine(24));
  EXPECT_NE(s1.find("use -mat_h2_single_precision"), std::string::npos) << s1;
  EXPECT_EQ(size_refusal(OperatorType::H2, 350000, single, machine(24)), "");
  // 600k in single precision with PC h2 (39.8 GB): Jacobi leaves out the factorization (13.4 GB).
  const std::string s2 = size_refusal(OperatorType::H2, 600000, single, machine(24));
  EXPECT_NE(s2.find("use -pc_type jacobi"), std::string::npos) << s2;
  EXPECT_EQ(size_refusal(OperatorType::H2, 600000, jacobi, machine(24)), "");
  // One million with Jacobi at 1e-5 fits (21.6 GB); 1.4 million (29.6 GB) at 1e-4 (21.7 GB).
  EXPECT_EQ(size_refusal(OperatorType::H2, 1000000, jacobi, machine(24)), "");
  const std::string s3 = size_refusal(OperatorType::H2, 1400000, jacobi, machine(24));
  EXPECT_NE(s3.find("needs about 29.6 GB per node"), std::string::npos) << s3;
  EXPECT_NE(s3.find("use -mat_h2_rel_tol 1e-4"), std::string::npos) << s3;
  EXPECT_EQ(size_refusal(OperatorType::H2, 1400000, SizeOptions{true, 1e-4, false}, machine(24)), "");
  // From double precision with PC h2, every step is named at once.
  const std::string s4 = size_refusal(OperatorType::H2, 1400000, dbl, machine(24));
  EXPECT_NE(s4.find("use -mat_h2_single_precision -pc_type jacobi -mat_h2_rel_tol 1e-4"), std::string::npos) << s4;
  const std::string none = size_refusal(OperatorType::H2, 2000000, jacobi, machine(24));
  EXPECT_NE(none.find("no operator path fits"), std::string::npos) << none;
  // The estimate falls with the tolerance and rises with the factorization.
  EXPECT_LT(estimated_bytes(OperatorType::H2, 100000, SizeOptions{true, 1e-4, false}), estimated_bytes(OperatorType::H2, 100000, jacobi));
  EXPECT_LT(estimated_bytes(OperatorType::H2, 100000, jacobi), estimated_bytes(OperatorType::H2, 100000, single));
}

TEST(SizeLimits, H2AndHssSplitOverTheRanksNodes)
{
  // 2 000 000 unknowns in single precision (41 GB) do not fit one 24 GiB node; the distributed
  // H² matrix spread over 8 nodes does, but not 8 ranks on one node.
  const SizeOptions jacobi{true, 1e-5, false};
  EXPECT_NE(size_refusal(OperatorType::H2, 2000000, jacobi, machine(24)), "");
  EXPECT_EQ(size_refusal(OperatorType::H2, 2000000, jacobi, machine(24, 8, 1)), "");
  EXPECT_NE(size_refusal(OperatorType::H2, 2000000, jacobi, machine(24, 8, 8)), "");
  // HSS at 60 000 unknowns (30 GB) likewise: one node is too small, 8 nodes are not, and the
  // node of rank 0 holds a quarter of a share more (the top above the parts).
  const double hss = estimated_bytes(OperatorType::Hss, 60000, SizeOptions{});
  EXPECT_GT(hss, 24 * 1073741824.0);
  EXPECT_NE(size_refusal(OperatorType::Hss, 60000, SizeOptions{}, machine(24)), "");
  EXPECT_NE(size_refusal(OperatorType::Hss, 60000, SizeOptions{}, machine(24, 8, 8)), "");
  EXPECT_EQ(size_refusal(OperatorType::Hss, 60000, SizeOptions{}, machine(24, 8, 1)), "");
  EXPECT_EQ(size_refusal(OperatorType::Hss, 60000, SizeOptions{}, machine(hss / 2 / 1073741824.0 * 1.3, 2, 1)), "");
  EXPECT_NE(size_refusal(OperatorType::Hss, 60000, SizeOptions{}, machine(hss / 2 / 1073741824.0 * 1.2, 2, 1)), ""); // rank 0's top does not fit
}

TEST(SizeLimits, HssGrowsFasterThanH2)
{
  EXPECT_GT(estimated_bytes(OperatorType::Hss, 100000, SizeOptions{}), estimated_bytes(OperatorType::H2, 100000, SizeOptions{}));
  EXPECT_NE(size_refusal(OperatorType::Hss, 100000, SizeOptions{}, machine(24)).find("use -bem_mat_type h2"), std::string::npos);
}

TEST(AutoOperator, DenseBelowTheCrossoverH2AboveAndWhereDenseDoesNotFit)
{
  EXPECT_EQ(choose_operator(3000, machine(24)), OperatorType::Dense);
  EXPECT_EQ(choose_operator(k_auto_dense_max_unknowns - 3, machine(24)), OperatorType::Dense);
  EXPECT_EQ(choose_operator(k_auto_dense_max_unknowns, machine(24)), OperatorType::H2);
  EXPECT_EQ(choose_operator(60000, machine(24)), OperatorType::H2);
  EXPECT_EQ(choose_operator(3000, machine(0.1)), OperatorType::H2); // dense needs 0.144 GB
}

} // namespace
