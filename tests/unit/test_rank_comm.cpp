// The agreement (core/rank_comm.hpp) as one rank of several sees it, through a communicator whose
// other ranks' outcomes are scripted; and the 32-bit guards of messages and of the spread top's
// local arrays with injected sizes (nothing of that size is allocated).
#include "hssbem/core/cluster_exchange.hpp"
#include "hssbem/core/rank_comm.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include <stdexcept>
#include <string>

using namespace hssbem;

namespace {

/// Rank 0 of two; rank 1's outcome in the next agreement is `other` (0 done, 1 soft, 2 failed; in
/// the agreements after it, 0), its message `other_message`.
class ScriptedComm : public SerialComm {
public:
  mutable int other = 0;
  std::string other_message;
  int rank() const override { return 0; }
  int size() const override { return 2; }
  double max(double v) const override
  {
    if (std::signbit(v)) return std::max(v, !other_message.empty() ? -1.0 : -2.0); // lowest_message's query: -(rank) of a soft failure, -(size) else
    const int o = other;
    other = 0;
    return std::max(v, static_cast<double>(o));
  }
  std::vector<int> allgather(const std::vector<int> &mine, std::vector<int> &counts) const override
  {
    std::vector<int> all = mine;
    if (mine.empty()) all.assign(other_message.begin(), other_message.end());
    counts = {static_cast<int>(mine.size()), static_cast<int>(all.size() - mine.size())};
    return all;
  }
};

struct Soft : std::runtime_error {
  using std::runtime_error::runtime_error;
};

TEST(Agreement, ReturnsTheResultWhenNoRankFails)
{
  ScriptedComm comm;
  EXPECT_EQ(collectively(comm, [] { return 42; }), 42);
  int ran = 0;
  collectively(comm, [&] { ++ran; });
  EXPECT_EQ(ran, 1);
}

TEST(Agreement, AnotherRanksFailureThrowsPeerFaultHere)
{
  ScriptedComm comm;
  comm.other = 2;
  EXPECT_THROW(collectively(comm, [] { return 1; }), PeerFault);
  comm.other = 1; // a soft failure elsewhere counts as a failure where none is expected
  EXPECT_THROW(collectively(comm, [] {}), PeerFault);
}

TEST(Agreement, OwnFailureIsRethrown)
{
  ScriptedComm comm;
  comm.other = 1;
  EXPECT_THROW(collectively<Soft>(comm, [] { throw std::length_error("mine"); }), std::length_error); // a hard failure beats a soft one
}

TEST(Agreement, SoftFailureAnywhereIsTheLowestRanksOnEveryRank)
{
  ScriptedComm comm;
  comm.other = 1;
  comm.other_message = "broke down on rank 1";
  try {
    collectively<Soft>(comm, [] {});
    FAIL() << "no Soft thrown";
  } catch (const Soft &e) {
    EXPECT_STREQ(e.what(), "broke down on rank 1");
  }
  comm.other_message.clear();
  try {
    collectively<Soft>(comm, [] { throw Soft("broke down here"); });
    FAIL() << "no Soft thrown";
  } catch (const Soft &e) {
    EXPECT_STREQ(e.what(), "broke down here");
  }
  comm.other = 2; // and any other failure beats it: this rank gives up without its breakdown
  EXPECT_THROW(collectively<Soft>(comm, [] { throw Soft("broke down here"); }), PeerFault);
}

TEST(Agreement, MakesCollectiveObjectsAfterAgreeingOnTheirStorage)
{
  ScriptedComm comm;
  const auto s = make_shared_collectively<std::string>(comm, 3, 'x');
  EXPECT_EQ(*s, "xxx");
  const auto u = make_unique_collectively<std::vector<int>>(comm, 2, 7);
  EXPECT_EQ(u->size(), 2u);
  comm.other = 2; // another rank could not allocate: nothing is built here either
  EXPECT_THROW(make_unique_collectively<std::string>(comm, 3, 'x'), PeerFault);
}

TEST(SizeGuards, MessagesBeyond32BitCountsAreRefusedByName)
{
  EXPECT_EQ(message_count(2147483647u, "a"), 2147483647);
  try {
    message_count(2147483648u, "rank 1's rows of the dense top");
    FAIL() << "no error";
  } catch (const std::length_error &e) {
    EXPECT_NE(std::string(e.what()).find("rank 1's rows of the dense top: 2.15e+09 values"), std::string::npos) << e.what();
  }
}

TEST(SizeGuards, SpreadTopBeyondScaLapackLocalIndexing)
{
  // On 2 ranks in blocks of 128 columns, rank 0 holds 32 768 columns of a 65 536-unknown top:
  // 2^31 entries, one beyond a 32-bit index; one unknown fewer fits.
  EXPECT_NO_THROW(check_spread_size(65535, 128, 2));
  EXPECT_THROW(check_spread_size(65536, 128, 2), std::length_error);
  EXPECT_NO_THROW(check_spread_size(92160, 128, 4)); // 4 ranks: 23 040 columns on rank 0, 2.12e9 entries
  EXPECT_THROW(check_spread_size(100000, 128, 4), std::length_error);
  EXPECT_THROW(check_spread_size(46341, 128, 1), std::length_error); // one rank: n² > 2^31 - 1
}

} // namespace
