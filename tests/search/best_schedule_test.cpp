#include "search/best_schedule.h"

#include <gtest/gtest.h>

#include <chrono>
#include <random>
#include <thread>

#include "graph/peel.h"
#include "graph/schedule.h"
#include "search/late_bound.h"
#include "tests/graph/test_trees.h"

namespace raycell {
namespace {

using namespace testing;
using namespace testing::cells;

BestScheduleOptions Small() {
  BestScheduleOptions o;
  o.chains = 2;
  o.local.max_windows = 40;
  o.threads = 1;
  return o;
}

// Paths C A D B and A C A: Peel 6; the beam finds A C A D B, whose 5 entries meet the bound,
// so nothing else runs and the schedule is optimal.
TEST(BestScheduleTest, StopsWhenTheBoundIsMet) {
  const CellTree t = FromPaths({{C, A, D, B}, {A, C, A}});
  const BestScheduleResult r = BestSchedule(t);
  EXPECT_EQ(r.schedule, (Schedule{A, C, A, D, B}));
  EXPECT_EQ(r.length, 5u);
  EXPECT_EQ(r.method, "beam(256)");
  EXPECT_EQ(r.peel_length, 6u);
  EXPECT_EQ(r.beam_length, 5u);
  EXPECT_EQ(r.local_length, 0u);
  EXPECT_EQ(r.bound, 5u);
  EXPECT_EQ(r.lower, 5u);
  EXPECT_TRUE(r.optimal);
  EXPECT_EQ(r.windows, 0u);
  EXPECT_EQ(r.exact_status, "not run");
  EXPECT_EQ(r.ToString(), "5 (beam(256); Peel 6, beam 5, bound 5, lower 5, optimal)");
}

// A given lower bound equal to Peel's length: Peel's schedule is optimal, nothing else runs.
TEST(BestScheduleTest, GivenLowerBoundStopsAtPeel) {
  const CellTree t = FromPaths({{A, B}, {B, A}});  // bound 2, Peel 3 = optimum
  BestScheduleOptions o;
  o.lower_bound = 3;
  const BestScheduleResult r = BestSchedule(t, o);
  EXPECT_EQ(r.method, "peel");
  EXPECT_EQ(r.length, 3u);
  EXPECT_EQ(r.beam_length, 0u);
  EXPECT_TRUE(r.optimal);
}

// Rotations of A B C D: bound 4, optimum 7 (2n - 1, tests/search/optimum_test.cpp); the beam
// and local search cannot prove it, the exact search does.
TEST(BestScheduleTest, ExactSearchProvesTheOptimum) {
  const CellTree t = FromPaths({{A, B, C, D}, {B, C, D, A}, {C, D, A, B}, {D, A, B, C}});
  ASSERT_EQ(BruteForceOptimum(t), 7u);
  const BestScheduleResult r = BestSchedule(t, Small());
  EXPECT_EQ(r.length, 7u);
  EXPECT_TRUE(r.optimal);
  EXPECT_EQ(r.lower, 7u);
  EXPECT_EQ(r.exact_status.substr(0, 9), "optimal 7");
  EXPECT_EQ(r.exact_status.find(" s)"), std::string::npos);  // no wall time
  BestScheduleOptions no_exact = Small();
  no_exact.exact_states = 0;
  const BestScheduleResult n = BestSchedule(t, no_exact);
  EXPECT_EQ(n.length, 7u);
  EXPECT_FALSE(n.optimal);
  EXPECT_EQ(n.lower, 4u);
}

TEST(BestScheduleTest, EmptyTreeIsOptimalAtLengthZero) {
  const BestScheduleResult r = BestSchedule(FromPaths({}));
  EXPECT_EQ(r.length, 0u);
  EXPECT_TRUE(r.optimal);
}

// Random small trees: feasible, between the optimum and Peel; an answer called optimal is
// the optimum; the lower bound never passes it.
TEST(BestSchedulePropertyTest, BetweenOptimumAndPeel) {
  std::mt19937 rng(31337);
  int below_peel = 0, optimal = 0, tried = 0;
  for (int i = 0; i < 1000; ++i) {
    const CellTree t = RandomTree(rng, 2 + rng() % 5, 1 + rng() % 8);
    if (t.node_count() > 22) continue;
    ++tried;
    SCOPED_TRACE(t.ToString());
    BestScheduleOptions o = Small();
    o.exact_states = i % 2 ? 50000 : 0;
    const BestScheduleResult r = BestSchedule(t, o);
    const std::size_t best = BruteForceOptimum(t), peel = Peel(t).schedule.size();
    EXPECT_TRUE(IsFeasible(t, r.schedule));
    EXPECT_EQ(r.length, r.schedule.size());
    EXPECT_LE(r.length, peel);
    EXPECT_GE(r.length, best);
    EXPECT_LE(r.lower, best);
    if (r.optimal) {
      EXPECT_EQ(r.length, best);
    }
    if (o.exact_states) {
      EXPECT_TRUE(r.optimal);  // small trees: the exact search finishes
    }
    below_peel += r.length < peel;
    optimal += r.optimal;
  }
  EXPECT_GT(tried, 700);
  EXPECT_GT(below_peel, 30);
  EXPECT_GT(optimal, 300);
}

TEST(BestSchedulePropertyTest, SameResultForAnyThreadCount) {
  std::mt19937 rng(99);
  for (int i = 0; i < 20; ++i) {
    const CellTree t = RandomTree(rng, 8, 60);
    BestScheduleOptions o;
    o.chains = 3;
    o.local.max_windows = 60;
    o.local.min_window = 4;
    o.local.max_window = o.local.exact_window = 8;
    o.local.large_min = 9;  // large windows (odd chains) shorter than the default, for speed
    o.local.large_max = 12;
    o.exact_states = 0;
    o.seed = 1 + i;
    o.threads = 1;
    const BestScheduleResult one = BestSchedule(t, o);
    for (std::size_t threads : {2, 3}) {
      o.threads = threads;
      const BestScheduleResult r = BestSchedule(t, o);
      EXPECT_EQ(r.schedule, one.schedule);
      EXPECT_EQ(r.windows, one.windows);
      EXPECT_EQ(r.work, one.work);
    }
    EXPECT_TRUE(IsFeasible(t, one.schedule));
  }
}

// A lower bound published by another thread while the search runs (search/late_bound.h) gives
// what the same bound given up front gives: the schedule, its method, the lower end and the
// exact search's answer, whenever it arrives (before the search, a few microseconds or
// milliseconds into it). The bound is the brute-force optimum, so that the searches meet it
// and would stop: most of the trees are small enough for the exact search, which waits for it.
TEST(BestSchedulePropertyTest, ALateLowerBoundGivesTheSameResult) {
  std::mt19937 rng(17);
  int stopped = 0;
  for (int i = 0; i < 120; ++i) {
    const CellTree t = RandomTree(rng, 2 + rng() % 4, 1 + rng() % 8, 5);
    BestScheduleOptions o = Small();
    o.seed = 1 + i;
    o.exact_max_nodes = i % 3 == 0 ? 0 : 1000;  // a third without the exact search
    o.lower_bound = BruteForceOptimum(t);
    const BestScheduleResult given = BestSchedule(t, o);
    stopped += given.windows == 0;
    for (int delay_us : {-1, 0, 50, 2000}) {
      SCOPED_TRACE("tree " + std::to_string(i) + ", published after " + std::to_string(delay_us) +
                   " us: " + t.ToString());
      BestScheduleOptions late_o = o;
      const std::uint64_t value = o.lower_bound;
      late_o.lower_bound = 0;
      LateBound late;
      late_o.late_lower_bound = &late;
      if (delay_us < 0) late.Publish(value);  // known from the start
      std::thread publisher([&] {
        if (delay_us < 0) return;
        std::this_thread::sleep_for(std::chrono::microseconds(delay_us));
        late.Publish(value);
      });
      const BestScheduleResult r = BestSchedule(t, late_o);
      publisher.join();
      EXPECT_EQ(r.schedule, given.schedule);
      EXPECT_EQ(r.method, given.method);
      EXPECT_EQ(r.lower, given.lower);
      EXPECT_EQ(r.optimal, given.optimal);
      EXPECT_EQ(r.exact_status, given.exact_status);
    }
    if (HasFailure()) return;
  }
  EXPECT_GT(stopped, 20);  // the given bound stopped the search before its local search
}

// The chains' portfolio: large windows in the odd chains only (chain 0 has none, chain 1
// some); without vary_windows every chain has o.local's.
TEST(BestScheduleTest, OnlyOddChainsHaveLargeWindows) {
  std::mt19937 rng(31);
  const CellTree t = RandomTree(rng, 8, 80);
  BestScheduleOptions o;
  o.local.max_windows = 100;
  o.local.large_min = 6;
  o.local.large_max = 10;
  o.exact_states = 0;
  o.threads = 1;
  o.chains = 1;
  const BestScheduleResult even = BestSchedule(t, o);
  ASSERT_EQ(even.windows, 100u);  // the search did not stop at the bound
  EXPECT_EQ(even.large_windows, 0u);
  o.chains = 2;
  const BestScheduleResult both = BestSchedule(t, o);
  ASSERT_EQ(both.windows, 200u);
  EXPECT_GT(both.large_windows, 20u);
  EXPECT_LT(both.large_windows, 80u);
  o.chains = 1;
  o.vary_windows = false;
  EXPECT_GT(BestSchedule(t, o).large_windows, 20u);
  o.local.large_every = 0;
  EXPECT_EQ(BestSchedule(t, o).large_windows, 0u);
}

// Large trees and many cells: everything stays within its limits and the result is
// feasible and no longer than Peel's (a tree of ~20000 nodes over 512 cells, one of ~3000
// nodes over 4096 cells; random paths, so nearly every visit is a node).
TEST(BestScheduleTest, LargeTreesAndManyCells) {
  std::mt19937 rng(4096);
  for (const auto& [cells, rays] : {std::pair<std::uint32_t, int>{512, 6000}, {4096, 900}}) {
    const CellTree t = RandomTree(rng, cells, rays);
    BestScheduleOptions o;
    o.chains = 2;
    o.local.max_windows = 20;
    o.beam_width = 16;
    o.beam_max_node_visits = 10'000'000;
    const BestScheduleResult r = BestSchedule(t, o);
    EXPECT_TRUE(IsFeasible(t, r.schedule));
    EXPECT_LE(r.length, Peel(t).schedule.size());
    EXPECT_GE(r.length, Bound(t));
    EXPECT_EQ(r.exact_status, "not run");  // more than exact_max_nodes
    EXPECT_GT(t.node_count(), 2500u);
  }
}

}  // namespace
}  // namespace raycell
