#include "search/optimum.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <random>
#include <set>
#include <sstream>

#include "graph/peel.h"
#include "graph/schedule.h"
#include "tests/cell_list.h"
#include "tests/graph/test_trees.h"

namespace raycell {
namespace {

using namespace testing;
using namespace testing::cells;

void ExpectOptimal(const CellTree& t, std::uint64_t length) {
  const OptimumResult r = ExactOptimum(t);
  ASSERT_EQ(r.status, OptimumResult::kOptimal) << r.ToString();
  EXPECT_EQ(r.length, length) << r.ToString();
  EXPECT_EQ(r.schedule.size(), length) << r.ToString();
  EXPECT_TRUE(IsFeasible(t, r.schedule)) << r.ToString();
}

// ------------------------------------------------------------------ hand-made trees

// A B and B A: bound 2, but no schedule of two entries covers both paths; A B A does.
TEST(OptimumTest, TwoCrossedPaths) {
  const CellTree t = FromPaths({{A, B}, {B, A}});
  EXPECT_EQ(Bound(t), 2u);
  EXPECT_EQ(Peel(t).schedule.size(), 3u);
  ExpectOptimal(t, 3);
  EXPECT_EQ(BruteForceOptimum(t), 3u);
}

TEST(OptimumTest, ChainIsTheBound) {
  const CellTree t = FromPaths({{A, B, C, A}});
  ExpectOptimal(t, 4);
  EXPECT_EQ(ExactOptimum(t).schedule, (Schedule{A, B, C, A}));
}

TEST(OptimumTest, StarIsTheCellCount) {
  std::vector<Schedule> paths;
  for (CellId c : CellRange(10)) paths.push_back({c});
  const CellTree t = FromPaths(paths);
  EXPECT_EQ(Bound(t), 10u);
  ExpectOptimal(t, 10);
}

TEST(OptimumTest, EmptyTreeHasOptimumZero) {
  const CellTree t = FromPaths({});
  ExpectOptimal(t, 0);
}

// Paths C A D B and A C A: nodes C1 -> A1 -> D1 -> B1 and A2 -> C2 -> A3; maxGen A 2, B C D
// 1: bound 5. Peel: completion A (A3), completion B, completion D, then no cell is ready
// (A2 and C1 are not leaves) and A and C have one leaf each: split A removes A1, then
// completion C (C1, C2), completion A (A2). Schedule A C A D B A, 6 entries: the split took
// A1 on its own. The optimum A C A D B (the only schedule of length 5) takes A1 with A3.
TEST(OptimumTest, ShorterThanPeelWhenPeelMustSplit) {
  const CellTree t = FromPaths({{C, A, D, B}, {A, C, A}});
  EXPECT_EQ(Bound(t), 5u);
  EXPECT_EQ(Peel(t).schedule, (Schedule{A, C, A, D, B, A}));
  const OptimumResult r = ExactOptimum(t);
  ASSERT_EQ(r.status, OptimumResult::kOptimal);
  EXPECT_EQ(r.length, 5u);
  EXPECT_LT(r.length, Peel(t).schedule.size());
  EXPECT_EQ(r.schedule, (Schedule{A, C, A, D, B}));
  EXPECT_EQ(BruteForceOptimum(t), 5u);
  EXPECT_GT(r.states_expanded, 0u);
  EXPECT_EQ(r.reason, "shorter than Peel's; bound 5, Peel 6");
}

// Rotations of A B C D E: the shortest common supersequence is A B C D E A B C D (2n - 1),
// bound 5.
TEST(OptimumTest, RotationsNeedTwoNMinusOne) {
  const CellTree t = Rotations(5);
  EXPECT_EQ(Bound(t), 5u);
  ExpectOptimal(t, 9);
  EXPECT_EQ(BruteForceOptimum(t), 9u);
}

TEST(OptimumTest, ToStringNamesStatusLengthAndSchedule) {
  const OptimumResult r = ExactOptimum(FromPaths({{A, B, C, A}}));
  EXPECT_EQ(r.ToString().substr(0, 29), "optimal 4 (schedule 0 1 2 0; ");
  EXPECT_STREQ(ToString(OptimumResult::kTooLarge), "too large");
}

// ------------------------------------------------------------------------ limits

TEST(OptimumLimitsTest, StateLimitGivesUnknown) {
  const CellTree t = Rotations(5);
  OptimumLimits limits;
  limits.max_states = 10;
  const OptimumResult r = ExactOptimum(t, limits);
  EXPECT_EQ(r.status, OptimumResult::kUnknown) << r.ToString();
  EXPECT_NE(r.reason.find("max_states = 10"), std::string::npos) << r.reason;
  EXPECT_EQ(r.states_expanded, 10u);
  EXPECT_EQ(r.length, 0u);
  EXPECT_TRUE(r.schedule.empty());
  // Without the limit the answer is known.
  EXPECT_EQ(ExactOptimum(t).status, OptimumResult::kOptimal);
}

TEST(OptimumLimitsTest, TimeAndMemoryLimitsGiveUnknown) {
  const CellTree t = Rotations(5);
  OptimumLimits time;
  time.max_seconds = 0;
  OptimumResult r = ExactOptimum(t, time);
  EXPECT_EQ(r.status, OptimumResult::kUnknown);
  EXPECT_NE(r.reason.find("max_seconds"), std::string::npos) << r.reason;
  EXPECT_TRUE(r.schedule.empty());
  OptimumLimits memory;
  memory.max_bytes = 1;
  r = ExactOptimum(t, memory);
  EXPECT_EQ(r.status, OptimumResult::kUnknown);
  EXPECT_NE(r.reason.find("max_bytes"), std::string::npos) << r.reason;
  EXPECT_TRUE(r.schedule.empty());
}

TEST(OptimumLimitsTest, TooManyNodesGivesTooLarge) {
  const CellTree t = FromPaths({{A, B, C, A}});  // 4 nodes, optimum trivially 4
  OptimumLimits limits;
  limits.max_nodes = 3;
  const OptimumResult r = ExactOptimum(t, limits);
  EXPECT_EQ(r.status, OptimumResult::kTooLarge);
  EXPECT_EQ(r.reason, "tree has 4 nodes, more than max_nodes = 3");
  EXPECT_EQ(r.length, 0u);
  EXPECT_TRUE(r.schedule.empty());
  limits.max_nodes = 4;
  EXPECT_EQ(ExactOptimum(t, limits).status, OptimumResult::kOptimal);
}

// ------------------------------------------------------------------------ properties

// `count` random trees of 2..5 cells and at most 25 nodes.
template <typename Fn>
void ForSmallRandomTrees(int count, Fn fn) {
  std::mt19937 rng(19940622);
  for (int i = 0; i < count;) {
    const std::uint32_t cells = 2 + rng() % 4;
    const int rays = 1 + static_cast<int>(rng() % 8);
    const CellTree t = RandomTree(rng, cells, rays);
    if (t.node_count() > 25) continue;
    ++i;
    SCOPED_TRACE(t.ToString());
    fn(t);
    if (::testing::Test::HasFatalFailure()) return;
  }
}

TEST(OptimumPropertyTest, BetweenBoundAndPeelFeasibleAndEqualToBruteForce) {
  int below_peel = 0;
  ForSmallRandomTrees(3000, [&](const CellTree& t) {
    const OptimumResult r = ExactOptimum(t);
    ASSERT_EQ(r.status, OptimumResult::kOptimal) << r.ToString();
    const std::size_t peel = Peel(t).schedule.size();
    EXPECT_LE(Bound(t), r.length);
    EXPECT_LE(r.length, peel);
    EXPECT_EQ(r.schedule.size(), r.length);
    EXPECT_TRUE(IsFeasible(t, r.schedule)) << r.ToString();
    EXPECT_EQ(r.length, BruteForceOptimum(t)) << r.ToString();
    below_peel += r.length < peel ? 1 : 0;
  });
  // The seeded trees include cases where the search beats Peel, so that path is exercised.
  EXPECT_GT(below_peel, 0);
}

TEST(OptimumPropertyTest, SameTreeGivesTheSameScheduleAndStateCount) {
  ForSmallRandomTrees(300, [](const CellTree& t) {
    const OptimumResult a = ExactOptimum(t), b = ExactOptimum(t);
    EXPECT_EQ(a.schedule, b.schedule);
    EXPECT_EQ(a.states_expanded, b.states_expanded);
  });
}

// ------------------------------------------------------------------- strengthened search

// The optimum as incumbent: nothing shorter exists, the incumbent is returned as optimal.
TEST(OptimumIncumbentTest, OptimalIncumbentIsConfirmed) {
  const CellTree t = FromPaths({{C, A, D, B}, {A, C, A}});
  OptimumOptions o;
  o.incumbent = {A, C, A, D, B};
  o.lower_bound = 0;
  const OptimumResult r = ExactOptimum(t, o);
  ASSERT_EQ(r.status, OptimumResult::kOptimal);
  EXPECT_EQ(r.schedule, o.incumbent);
  EXPECT_EQ(r.reason, "the incumbent's length equals the bound 5");
  // Rotations: bound 5, optimum 9; an incumbent of 9 is confirmed by a search.
  const CellTree rot = Rotations(5);
  o.incumbent = ExactOptimum(rot).schedule;
  ASSERT_EQ(o.incumbent.size(), 9u);
  const OptimumResult q = ExactOptimum(rot, o);
  ASSERT_EQ(q.status, OptimumResult::kOptimal);
  EXPECT_EQ(q.schedule, o.incumbent);
  EXPECT_GT(q.states_expanded, 0u);
  EXPECT_EQ(q.reason, "no schedule is shorter than the incumbent's; bound 5, incumbent 9");
}

// A longer incumbent: the search finds the optimum below it.
TEST(OptimumIncumbentTest, LongerIncumbentIsImproved) {
  const CellTree t = Rotations(4);  // optimum 7
  OptimumOptions o;
  o.incumbent = testing::CellList{0, 1, 2, 3, 0, 1, 2, 3};
  const OptimumResult r = ExactOptimum(t, o);
  ASSERT_EQ(r.status, OptimumResult::kOptimal);
  EXPECT_EQ(r.length, 7u);
  EXPECT_EQ(r.reason, "shorter than the incumbent's; bound 4, incumbent 8");
  EXPECT_TRUE(IsFeasible(t, r.schedule));
}

// A given lower bound that the incumbent meets: optimal without a search.
TEST(OptimumIncumbentTest, LowerBoundMetNeedsNoSearch) {
  const CellTree t = Rotations(4);
  OptimumOptions o;
  o.incumbent = testing::CellList{0, 1, 2, 3, 0, 1, 2};
  o.lower_bound = 7;
  const OptimumResult r = ExactOptimum(t, o);
  ASSERT_EQ(r.status, OptimumResult::kOptimal);
  EXPECT_EQ(r.states_expanded, 0u);
  EXPECT_EQ(r.reason, "the incumbent's length equals the lower bound 7");
}

// Stopped by the state limit: a bracket [lower, upper] that holds the optimum, never a guess.
TEST(OptimumIncumbentTest, StoppedSearchGivesABracket) {
  const CellTree t = Rotations(6);  // bound 6, optimum 11
  OptimumOptions o;
  o.limits.max_states = 50;
  o.pair_heuristic = false;
  const OptimumResult r = ExactOptimum(t, o);
  ASSERT_EQ(r.status, OptimumResult::kUnknown);
  EXPECT_GE(r.lower, 6u);
  EXPECT_LE(r.lower, 11u);
  EXPECT_GT(r.lower, 6u);  // the search proved more than the bound
  EXPECT_EQ(r.upper, Peel(t).schedule.size());
  EXPECT_TRUE(r.schedule.empty());
  EXPECT_NE(r.ToString().find("unknown in [" + std::to_string(r.lower) + ", "), std::string::npos);
}

// The extra bound is used: a consistent one changes nothing but is called; one that
// overestimates (a broken bound) prunes the optimum away, which shows it is used.
TEST(OptimumIncumbentTest, ExtraBoundIsUsed) {
  const CellTree t = Rotations(4);
  int calls = 0;
  OptimumOptions o;
  o.extra_bound = [&](const CellForest& f, const Word* bits) {
    ++calls;
    for (CellForest::Index n = 0; n < f.size(); ++n) {
      if (!TestBit(bits, n)) return 1u;
    }
    return 0u;
  };
  EXPECT_EQ(ExactOptimum(t, o).length, 7u);
  EXPECT_GT(calls, 0);
  o.extra_bound = [](const CellForest&, const Word*) { return 100u; };
  EXPECT_EQ(ExactOptimum(t, o).length, Peel(t).schedule.size());  // 8: wrong, as expected
}

// The pair heuristic keeps the search exact (equal to brute force) on random trees, with
// and without it.
TEST(OptimumPropertyTest, PairHeuristicIsExact) {
  int fewer = 0, more = 0;
  ForSmallRandomTrees(1500, [&](const CellTree& t) {
    OptimumOptions with, without;
    without.pair_heuristic = false;
    const OptimumResult a = ExactOptimum(t, with), b = ExactOptimum(t, without);
    ASSERT_EQ(a.status, OptimumResult::kOptimal);
    ASSERT_EQ(b.status, OptimumResult::kOptimal);
    const std::size_t best = BruteForceOptimum(t);
    EXPECT_EQ(a.length, best);
    EXPECT_EQ(b.length, best);
    fewer += a.states_expanded < b.states_expanded;
    more += a.states_expanded > b.states_expanded;
  });
  EXPECT_GT(fewer, 10 * more);
}

// The figure for the strengthened search: random trees of 6-9 cells and 40-120 nodes, each
// searched with 3000 states at most; the pair heuristic proves the optimum on many more.
// Each proved optimum is checked against a search without limits.
TEST(OptimumPropertyTest, PairHeuristicProvesMoreWithinTheStateLimit) {
  std::mt19937 rng(8128);
  int old_proved = 0, new_proved = 0, trees = 0;
  while (trees < 30) {
    const CellTree t = RandomTree(rng, 6 + rng() % 4, 10 + rng() % 12, 7);
    if (t.node_count() < 40 || t.node_count() > 120) continue;
    ++trees;
    OptimumOptions o;
    o.limits.max_states = 3000;
    const OptimumResult strong = ExactOptimum(t, o);
    o.pair_heuristic = false;
    const OptimumResult weak = ExactOptimum(t, o);
    OptimumOptions unlimited;
    unlimited.limits.max_states = 10'000'000;
    unlimited.limits.max_seconds = 1e9;
    const OptimumResult truth = ExactOptimum(t, unlimited);
    ASSERT_EQ(truth.status, OptimumResult::kOptimal);
    for (const OptimumResult* r : {&strong, &weak}) {
      if (r->status == OptimumResult::kOptimal) {
        EXPECT_EQ(r->length, truth.length);
      } else {
        EXPECT_LE(r->lower, truth.length);
        EXPECT_GE(r->upper, truth.length);
      }
    }
    new_proved += strong.status == OptimumResult::kOptimal;
    old_proved += weak.status == OptimumResult::kOptimal;
  }
  std::printf("proved within 3000 states: %d of %d trees with pairs, %d without\n", new_proved,
              trees, old_proved);
  EXPECT_GT(new_proved, old_proved);
}

}  // namespace
}  // namespace raycell
