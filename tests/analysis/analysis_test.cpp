// AnalyzeTree with --bracket: on random small trees, bound <= lower_bound <= the brute-force
// optimum <= best_length <= Peel, the best schedule feasible, the optimum reported only when
// it is the optimum.
#include "analysis/analysis.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "base/check.h"
#include "graph/schedule.h"
#include "tests/graph/test_trees.h"

namespace raycell {
namespace {

using testing::BruteForceOptimum;
using testing::CellList;
using testing::FromPaths;
using testing::RandomTree;

AnalyzeOptions Bracketed(const std::string& effort, bool exact = false) {
  AnalyzeOptions o;
  o.bracket = true;
  o.bracket_options = BracketEffort(effort);
  o.exact = exact;
  return o;
}

void ExpectValidBracket(const CellTree& t, const FrameAnalysis& a, std::size_t optimum) {
  ASSERT_TRUE(a.lower_bound && a.best_length) << t.ToString();
  EXPECT_LE(a.bound, *a.lower_bound) << t.ToString();
  EXPECT_LE(*a.lower_bound, optimum) << t.ToString();
  EXPECT_LE(optimum, *a.best_length) << t.ToString();
  EXPECT_LE(*a.best_length, a.peel_length()) << t.ToString();
  EXPECT_EQ(a.best_schedule.size(), *a.best_length);
  EXPECT_TRUE(IsFeasible(t, a.best_schedule)) << t.ToString();
  if (a.optimum) {
    EXPECT_EQ(*a.optimum, optimum) << t.ToString();
  }
  const double gap = double(*a.best_length - *a.lower_bound) / double(*a.lower_bound);
  EXPECT_DOUBLE_EQ(*a.gap(), *a.lower_bound ? gap : 0.0);
  EXPECT_FALSE(a.lower_bound_method.empty());
  EXPECT_FALSE(a.best_method.empty());
}

TEST(AnalysisBracketTest, RandomTreesAreBracketedAroundTheOptimum) {
  std::mt19937 rng(5);
  int met = 0;
  for (int i = 0; i < 300; ++i) {
    const CellTree t = RandomTree(rng, 2 + rng() % 4, 1 + rng() % 10, 5);
    const std::size_t optimum = BruteForceOptimum(t);
    const FrameAnalysis a = AnalyzeTree(t, Bracketed(i % 2 ? "quick" : "default", i % 3 == 0));
    ExpectValidBracket(t, a, optimum);
    met += a.optimum.has_value();
    if (::testing::Test::HasFailure()) return;
  }
  EXPECT_GT(met, 250);  // small trees: the two sides meet on nearly all
}

// Random paths over a few cells of an 8x8x8 grid (512 cells), taken from its 4x4x4 corner so
// that they fall in several of the 2x2x2 boxes: paths of 1..6 visits without consecutive
// repeats.
CellTree RandomGridTree(std::mt19937& rng) {
  std::vector<CellId> cells;
  const std::uint32_t count = 4 + rng() % 4;
  while (cells.size() < count) {
    const CellId c(rng() % 4 + 8 * (rng() % 4 + 8 * (rng() % 4)));
    if (std::find(cells.begin(), cells.end(), c) == cells.end()) cells.push_back(c);
  }
  std::vector<CellList> paths(1 + rng() % 6);
  for (CellList& p : paths) {
    const std::size_t length = 1 + rng() % 6;
    while (p.size() < length) {
      const CellId c = cells[rng() % cells.size()];
      if (p.empty() || p.back() != c) p.push_back(c);
    }
  }
  return FromPaths(paths);
}

// The bracket as configured at 512 cells (issue 43): the lower bound with the grid's 2x2x2
// tiles first (max_blocks below the number of boxes, as on a 512-cell frame), pairs sampled by
// their conflicts within a small state budget, and the search's two-level schedule (its beam
// budget below width x Peel x nodes, as on a 512-cell frame). On trees small enough for the
// brute force: the bound never above the optimum, the two-level schedule feasible (BestSchedule
// checks every schedule it is offered) and never below it.
TEST(AnalysisBracketTest, AtHundredsOfCellsTheBoundsHoldOnRandomTrees) {
  std::mt19937 rng(43);
  int tiled = 0, sampled = 0, raised = 0, two_level = 0;
  for (int i = 0; i < 300; ++i) {
    const CellTree t = RandomGridTree(rng);
    if (t.node_count() > 22) continue;  // keep the brute force fast
    SCOPED_TRACE("tree " + std::to_string(i) + ": " + t.ToString());
    const std::size_t optimum = BruteForceOptimum(t);
    BracketOptions o = BracketEffort(i % 2 ? "quick" : "default");
    o.lower.grid = {8, 8, 8};
    o.lower.max_blocks = 1;
    o.lower.max_total_states = 20 + rng() % 2000;
    const LowerBoundResult lb = LowerBound(t, o.lower);
    ASSERT_LE(lb.value, optimum) << lb.ToString();
    EXPECT_GE(lb.value, Bound(t));
    tiled += lb.tiles > 0;
    sampled += lb.pairs_conflicting < lb.pairs_sharing;
    raised += lb.value > lb.max_gen;
    BestScheduleOptions b = o.best;
    b.threads = 1;
    b.coarse_of = BoardCells(o.lower.grid);
    b.beam_max_node_visits = 1 + rng() % 400;
    b.chains = 0;
    b.exact_states = 0;
    const BestScheduleResult r = BestSchedule(t, b);
    ASSERT_TRUE(IsFeasible(t, r.schedule));
    EXPECT_GE(r.length, optimum);
    if (r.two_level_length > 0) {
      ++two_level;
      EXPECT_GE(r.two_level_length, optimum) << r.ToString();
    }
  }
  EXPECT_GT(tiled, 50);
  EXPECT_GT(sampled, 50);
  EXPECT_GT(raised, 50);
  EXPECT_GT(two_level, 50);
}

// The lower bound on a thread of its own beside the search (BracketOptions::overlap) reports
// what the two in turn report, field by field, with and without the exact search.
TEST(AnalysisBracketTest, OverlappedBoundAndSearchReportTheSame) {
  std::mt19937 rng(23);
  for (int i = 0; i < 60; ++i) {
    const CellTree t =
        i % 4 == 0 ? RandomTree(rng, 6, 16) : RandomTree(rng, 2 + rng() % 4, 1 + rng() % 10, 5);
    SCOPED_TRACE("tree " + std::to_string(i) + ": " + t.ToString());
    AnalyzeOptions o = Bracketed("quick", i % 3 == 0);
    o.bracket_options.overlap = false;
    const FrameAnalysis in_turn = AnalyzeTree(t, o);
    o.bracket_options.overlap = true;
    const FrameAnalysis overlapped = AnalyzeTree(t, o);
    EXPECT_EQ(overlapped.lower_bound, in_turn.lower_bound);
    EXPECT_EQ(overlapped.lower_bound_method, in_turn.lower_bound_method);
    EXPECT_EQ(overlapped.best_schedule, in_turn.best_schedule);
    EXPECT_EQ(overlapped.best_method, in_turn.best_method);
    EXPECT_EQ(overlapped.optimum, in_turn.optimum);
    EXPECT_EQ(overlapped.optimum_status, in_turn.optimum_status);
    if (HasFailure()) return;
  }
}

// An error in the lower bound on its own thread reaches the caller as the same InputError
// (not std::terminate), after the search has finished with it.
TEST(AnalysisBracketTest, AnErrorOfTheOverlappedBoundReachesTheCaller) {
  const CellTree t = FromPaths({{0, 1, 2}, {2, 1, 0}});
  for (bool overlap : {false, true}) {
    AnalyzeOptions o = Bracketed("quick");
    o.bracket_options.overlap = overlap;
    o.bracket_options.lower.grid = {1, 1, 1};  // fewer cells than the tree's 3
    EXPECT_THROW(AnalyzeTree(t, o), InputError) << "overlap " << overlap;
  }
}

TEST(AnalysisBracketTest, WithoutBracketNothingIsReported) {
  const FrameAnalysis a = AnalyzeTree(FromPaths({{0, 1}, {1, 0}}), AnalyzeOptions{});
  EXPECT_FALSE(a.lower_bound || a.best_length || a.gap());
  EXPECT_TRUE(a.best_schedule.empty());
}

TEST(AnalysisBracketTest, EmptyTreeAndUnknownEffort) {
  const FrameAnalysis a = AnalyzeTree(FromPaths({}), Bracketed("quick"));
  EXPECT_EQ(*a.lower_bound, 0u);
  EXPECT_EQ(*a.best_length, 0u);
  EXPECT_EQ(*a.gap(), 0.0);
  EXPECT_THROW(BracketEffort("fast"), InputError);
}

}  // namespace
}  // namespace raycell
