// The MPI implementation of Ranks (src/ranks_mpi.cpp), run under `mpirun -np N` (CTest label
// "mpi"; built only with -DPOLRIG_MPI=ON). Every rank runs every test; a failure on any rank
// fails the job.
#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "polrig/ranks.h"

namespace polrig {
namespace {

const Ranks* g_ranks = nullptr;

std::vector<std::byte> bytes_of(const std::string& s) {
  const auto* b = reinterpret_cast<const std::byte*>(s.data());
  return {b, b + s.size()};
}
std::string text_of(const std::vector<std::byte>& b) {
  return {reinterpret_cast<const char*>(b.data()), b.size()};
}

TEST(MpiRanks, RunsAsTheLaunchersRanks) {
  const Launch launch = launch_from_environment();
  ASSERT_TRUE(launch.by_mpi_launcher) << "run this test under mpirun";
  EXPECT_EQ(g_ranks->rank(), launch.rank);
  EXPECT_EQ(g_ranks->size(), launch.processes);
  EXPECT_GE(g_ranks->size(), 2) << "run with -np 2 or more";
}

TEST(MpiRanks, GatherConcatenatesInRankOrderOnRank0Only) {
  // Rank r sends r + 1 copies of the letter 'a' + r (rank 1 sends nothing when asked), so sizes
  // differ and the order shows.
  for (bool empty_rank_1 : {false, true}) {
    const int r = g_ranks->rank();
    const std::string mine = empty_rank_1 && r == 1 ? "" : std::string(static_cast<std::size_t>(r + 1), static_cast<char>('a' + r));
    const std::string all = text_of(g_ranks->gather(bytes_of(mine)));
    if (r != 0) {
      EXPECT_EQ(all, "");
      continue;
    }
    std::string expected;
    for (int k = 0; k < g_ranks->size(); ++k)
      if (!(empty_rank_1 && k == 1)) expected += std::string(static_cast<std::size_t>(k + 1), static_cast<char>('a' + k));
    EXPECT_EQ(all, expected);
  }
}

TEST(MpiRanks, BroadcastGivesEveryRankRank0sBytes) {
  std::vector<std::byte> b = bytes_of(g_ranks->is_root() ? "from rank 0, a longer text" : "x");
  g_ranks->broadcast(b);
  EXPECT_EQ(text_of(b), "from rank 0, a longer text");
  std::vector<std::byte> none = bytes_of(g_ranks->is_root() ? "" : "not empty");
  g_ranks->broadcast(none);
  EXPECT_TRUE(none.empty());
}

TEST(MpiRanks, FirstFailureIsTheLowestFailingRanksMessageOnEveryRank) {
  const int r = g_ranks->rank();
  const int n = g_ranks->size();
  EXPECT_EQ(g_ranks->first_failure(std::nullopt), std::nullopt);
  // Every rank but 0 fails: rank 1's message wins.
  const auto failing = r > 0 ? std::optional<std::string>("rank " + std::to_string(r)) : std::nullopt;
  EXPECT_EQ(g_ranks->first_failure(failing), std::optional<std::string>("rank 1"));
  // The last rank alone fails, with an empty message: still a failure.
  const auto last = r == n - 1 ? std::optional<std::string>("") : std::nullopt;
  EXPECT_EQ(g_ranks->first_failure(last), std::optional<std::string>(""));
  // Every rank fails: rank 0's message.
  EXPECT_EQ(g_ranks->first_failure("failed on " + std::to_string(r)), std::optional<std::string>("failed on 0"));
}

}  // namespace
}  // namespace polrig

int main(int argc, char** argv) {
  std::unique_ptr<polrig::Ranks> job = polrig::join_mpi_job(argc, argv);
  polrig::g_ranks = job ? job.get() : &polrig::this_process_only();
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
