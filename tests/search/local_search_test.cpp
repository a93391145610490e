#include "search/local_search.h"

#include <gtest/gtest.h>

#include <random>

#include "base/check.h"
#include "graph/peel.h"
#include "graph/schedule.h"
#include "tests/graph/test_trees.h"

namespace raycell {
namespace {

using namespace testing;
using namespace testing::cells;

LocalSearchResult Improve(const CellTree& t, const Schedule& s, const LocalSearchOptions& o) {
  return ImproveSchedule(CellForest::FromTree(t), s, o);
}

// Path A B run by A A B B: the second A and the second B process nothing and are deleted
// before any window is tried.
TEST(LocalSearchTest, DeletesEntriesNoNodeNeeds) {
  LocalSearchOptions o;
  o.max_windows = 0;
  const LocalSearchResult r = Improve(FromPaths({{A, B}}), {A, A, B, B}, o);
  EXPECT_EQ(r.schedule, (Schedule{A, B}));
  EXPECT_EQ(r.deletions, 2u);
  EXPECT_EQ(r.windows, 0u);
}

// Path A B run by A A B B again, with 2 re-timings allowed: the one at the start and the one
// after the first deletion; the second idle entry stays, and no window is tried.
TEST(LocalSearchTest, MaxRetimesStopsTheDeletionsAndTheWindows) {
  LocalSearchOptions o;
  o.max_retimes = 2;
  const LocalSearchResult r = Improve(FromPaths({{A, B}}), {A, A, B, B}, o);
  EXPECT_EQ(r.schedule, (Schedule{A, B, B}));
  EXPECT_EQ(r.deletions, 1u);
  EXPECT_EQ(r.retimes, 2u);
  EXPECT_EQ(r.windows, 0u);
}

// One re-timing is the start's own: the search can neither delete an entry nor try a window
// after it, so it returns its start, even where deletions (A A B B) or a window (the next
// test's B C A B A, 4 entries at best) would shorten it. PlanEffort runs no local search then
// (scheduling/best_scheduler.h).
TEST(LocalSearchTest, OneRetimeReturnsTheStart) {
  LocalSearchOptions o;
  o.max_retimes = 1;
  o.min_window = o.max_window = o.exact_window = 5;
  for (const auto& [tree, start] :
       {std::pair{FromPaths({{A, B}}), Schedule{A, A, B, B}},
        std::pair{FromPaths({{C, B, A}, {B, A, B}}), Schedule{B, C, A, B, A}}}) {
    const LocalSearchResult r = Improve(tree, start, o);
    EXPECT_EQ(r.schedule, start);
    EXPECT_EQ(r.retimes, 1u);
    EXPECT_EQ(r.windows + r.deletions, 0u);
  }
}

// Paths C B A and B A B (nodes C1 B1 A1, B2 A2 B3) run by B C A B A: every entry processes
// a node no other entry can (B: B2; C: C1; A: A2; B: B1 and B3; A: A1), so nothing can be
// deleted, yet C B A B (C1; B1 B2; A1 A2; B3) has 4 entries, the bound (B twice, A and C
// once). The window over the whole schedule, solved exactly, finds a schedule of 4.
TEST(LocalSearchTest, WindowFindsWhatDeletionCannot) {
  const CellTree t = FromPaths({{C, B, A}, {B, A, B}});
  const Schedule start{B, C, A, B, A};
  for (std::size_t p = 0; p < start.size(); ++p) {
    Schedule without = start;
    without.erase(without.begin() + p);
    ASSERT_FALSE(IsFeasible(t, without)) << p;
  }
  ASSERT_TRUE(IsFeasible(t, {C, B, A, B}));
  LocalSearchOptions o;
  o.min_window = o.max_window = o.exact_window = 5;
  o.large_every = 0;
  o.max_windows = 1;
  const LocalSearchResult r = Improve(t, start, o);
  EXPECT_EQ(r.schedule.size(), 4u);
  EXPECT_TRUE(IsFeasible(t, r.schedule));
  EXPECT_EQ(r.improvements, 1u);
  EXPECT_EQ(r.deletions, 0u);
}

TEST(LocalSearchTest, StopsAtTheLowerBound) {
  const CellTree t = FromPaths({{A, B}, {B, A}});
  LocalSearchOptions o;
  o.lower_bound = 3;
  const LocalSearchResult r = Improve(t, {A, B, A}, o);
  EXPECT_EQ(r.windows, 0u);
  EXPECT_EQ(r.schedule, (Schedule{A, B, A}));
}

TEST(LocalSearchTest, InconsistentWindowsAreAnInputError) {
  LocalSearchOptions o;
  o.min_window = 12;
  o.max_window = 10;
  EXPECT_THROW(Improve(FromPaths({{A, B}}), {A, B}, o), InputError);
  o.min_window = 0;
  EXPECT_THROW(Improve(FromPaths({{A, B}}), {A, B}, o), InputError);
  o = LocalSearchOptions();
  o.large_min = 31;
  o.large_max = 30;
  EXPECT_THROW(Improve(FromPaths({{A, B}}), {A, B}, o), InputError);
  o.large_min = 0;
  EXPECT_THROW(Improve(FromPaths({{A, B}}), {A, B}, o), InputError);
  o.large_every = 0;  // no large windows: their lengths are not used
  EXPECT_NO_THROW(Improve(FromPaths({{A, B}}), {A, B}, o));
}

// The instance of WindowFindsWhatDeletionCannot, with windows of one entry (which cannot
// shorten B C A B A: no entry can be deleted): a large window over the whole schedule, given
// to the beam search, finds C B A B.
TEST(LocalSearchTest, LargeWindowsReachFurther) {
  const CellTree t = FromPaths({{C, B, A}, {B, A, B}});
  const Schedule start{B, C, A, B, A};
  LocalSearchOptions o;
  o.min_window = o.max_window = o.exact_window = 1;
  o.kick_after = 0;
  o.max_windows = 50;
  o.large_every = 0;
  const LocalSearchResult short_only = Improve(t, start, o);
  ASSERT_EQ(short_only.schedule.size(), 5u);
  EXPECT_EQ(short_only.large_windows, 0u);
  o.large_every = 1;
  o.large_min = o.large_max = 5;
  o.max_windows = 1;
  const LocalSearchResult r = Improve(t, start, o);
  EXPECT_EQ(r.schedule.size(), 4u);
  EXPECT_TRUE(IsFeasible(t, r.schedule));
  EXPECT_EQ(r.windows, 1u);
  EXPECT_EQ(r.large_windows, 1u);
}

// One window in large_every is large, drawn at random: about half of them for 2.
TEST(LocalSearchPropertyTest, LargeWindowShare) {
  std::mt19937 rng(5);
  const CellTree t = RandomTree(rng, 6, 40);
  LocalSearchOptions o;
  o.max_windows = 400;
  o.kick_after = 10;
  o.large_every = 2;
  o.large_min = 6;
  o.large_max = 9;
  const LocalSearchResult r = Improve(t, Peel(t).schedule, o);
  ASSERT_EQ(r.windows, 400u);
  EXPECT_GT(r.large_windows, 160u);
  EXPECT_LT(r.large_windows, 240u);
  EXPECT_TRUE(IsFeasible(t, r.schedule));
}

TEST(LocalSearchTest, ToStringCountsEntriesWindowsAndMoves) {
  LocalSearchOptions o;
  o.max_windows = 0;
  EXPECT_EQ(Improve(FromPaths({{A, B}}), {A, A, B, B}, o).ToString(),
            "2 entries after 0 windows (0 large; 0 shorter, 0 plateau moves, 2 deletions, 0 "
            "kicks)");
}

// Windows as long as the schedule, solved exactly: the local search is then an exact search
// and must reach the optimum from Peel's schedule.
TEST(LocalSearchPropertyTest, WholeWindowIsExact) {
  std::mt19937 rng(424242);
  int below_peel = 0;
  const int tried = ForSmallRandomTrees(rng, 1200, [&](const CellTree& t) {
    const Schedule peel = Peel(t).schedule;
    LocalSearchOptions o;
    o.min_window = o.max_window = o.exact_window = 64;
    o.large_every = 0;  // large windows go to the beam search, which is not exact
    o.exact_states = 1'000'000;
    o.max_windows = 1;
    const LocalSearchResult r = Improve(t, peel, o);
    EXPECT_TRUE(IsFeasible(t, r.schedule));
    EXPECT_EQ(r.schedule.size(), BruteForceOptimum(t));
    below_peel += r.schedule.size() < peel.size();
  });
  EXPECT_GT(tried, 800);
  EXPECT_GT(below_peel, 20);
}

// Default windows on random trees, from Peel and from padded schedules: feasible, between the
// optimum and the input, deterministic.
TEST(LocalSearchPropertyTest, FeasibleNeverLongerDeterministic) {
  std::mt19937 rng(77);
  int improved = 0;
  for (int i = 0; i < 600; ++i) {
    const CellTree t = RandomTree(rng, 2 + rng() % 5, 1 + rng() % 8);
    if (t.node_count() > 22) continue;
    SCOPED_TRACE(t.ToString());
    Schedule start = Peel(t).schedule;
    for (int k = rng() % 4; k > 0; --k) {
      start.insert(start.begin() + rng() % (start.size() + 1), CellId(rng() % t.cell_count()));
    }
    LocalSearchOptions o;
    o.max_windows = 30;
    o.kick_after = 5;
    o.seed = 1 + i;
    const LocalSearchResult a = Improve(t, start, o), b = Improve(t, start, o);
    EXPECT_TRUE(IsFeasible(t, a.schedule));
    EXPECT_LE(a.schedule.size(), start.size());
    EXPECT_GE(a.schedule.size(), BruteForceOptimum(t));
    EXPECT_EQ(a.schedule, b.schedule);
    EXPECT_EQ(a.work, b.work);
    improved += a.schedule.size() < start.size();
  }
  EXPECT_GT(improved, 100);
}

TEST(LocalSearchPropertyTest, KicksKeepTheBest) {
  std::mt19937 rng(8);
  const CellTree t = RandomTree(rng, 6, 30);
  const Schedule peel = Peel(t).schedule;
  LocalSearchOptions o;
  o.max_windows = 200;
  o.kick_after = 1;
  o.kick_size = 5;
  const LocalSearchResult r = Improve(t, peel, o);
  EXPECT_GT(r.kicks, 100u);
  EXPECT_TRUE(IsFeasible(t, r.schedule));
  EXPECT_LE(r.schedule.size(), peel.size());
}

// A B A is optimal for A B and B A; one window that cannot improve it, then a kick of 20
// fetches: the kicked walk is longer, the best (the input) is returned.
TEST(LocalSearchTest, KickedWalkIsNotReturned) {
  const CellTree t = FromPaths({{A, B}, {B, A}});
  LocalSearchOptions o;
  o.max_windows = 1;
  o.kick_after = 1;
  o.kick_size = 20;
  const LocalSearchResult r = Improve(t, {A, B, A}, o);
  EXPECT_EQ(r.kicks, 1u);
  EXPECT_EQ(r.schedule, (Schedule{A, B, A}));
}

}  // namespace
}  // namespace raycell
