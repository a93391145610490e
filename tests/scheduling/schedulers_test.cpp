#include <gtest/gtest.h>

#include <random>
#include <set>

#include "base/check.h"
#include "graph/peel.h"
#include "graph/schedule.h"
#include "scheduling/best_scheduler.h"
#include "scheduling/cell_tree_scheduler.h"
#include "scheduling/max_work.h"
#include "scheduling/peel_oracle.h"
#include "scheduling/plan_cache.h"
#include "scheduling/random_scheduler.h"
#include "scheduling/round_robin.h"
#include "tests/cell_list.h"
#include "tests/graph/test_trees.h"

namespace raycell {
namespace {

constexpr CellId A{0}, B{1}, C{2};
using Queues = std::vector<std::uint64_t>;
using Schedule = testing::CellList;

std::optional<CellId> Ask(Scheduler& s, const Queues& q) { return s.Next(QueueView::Of(q)); }

FrameInfo Frame(std::size_t index, std::uint32_t cells, const CellTree* current = nullptr,
                const CellTree* previous = nullptr) {
  return {index, current, previous, cells};
}

using testing::FromPaths;

// ------------------------------------------------------------------ QueueView, Max Work

TEST(QueueViewTest, HasWorkAndEmpty) {
  const Queues q = {0, 3, 0};
  const QueueView v = QueueView::Of(q, B);
  EXPECT_EQ(v.cells, 3u);
  EXPECT_EQ(v.loaded, B);
  EXPECT_FALSE(v.has_work(A));
  EXPECT_TRUE(v.has_work(B));
  EXPECT_FALSE(v.has_work(CellId(7)));  // outside the grid
  EXPECT_FALSE(v.empty());
  EXPECT_TRUE(QueueView::Of(Queues{0, 0}).empty());
  EXPECT_TRUE(QueueView::Of(Queues{}).empty());
}

TEST(MaxWorkTest, MostQueuedLowestOnTies) {
  MaxWorkScheduler s;
  s.BeginFrame(Frame(0, 4));
  EXPECT_EQ(s.Name(), "maxwork");
  EXPECT_EQ(Ask(s, {1, 5, 2, 5}), CellId(1));
  EXPECT_EQ(Ask(s, {1, 5, 2, 6}), CellId(3));
  EXPECT_EQ(Ask(s, {4, 4, 4, 4}), CellId(0));
  EXPECT_EQ(Ask(s, {0, 0, 0, 1}), CellId(3));
  EXPECT_EQ(Ask(s, {0, 0, 0, 0}), std::nullopt);
  EXPECT_EQ(Ask(s, {}), std::nullopt);
}

// ------------------------------------------------------------------ Round Robin

TEST(RoundRobinTest, NextCellWithWorkAfterTheLastAndWraps) {
  RoundRobinScheduler s;
  s.BeginFrame(Frame(0, 5));
  EXPECT_EQ(s.Name(), "roundrobin");
  EXPECT_EQ(Ask(s, {0, 2, 0, 1, 1}), CellId(1));  // starts the search at 0
  EXPECT_EQ(Ask(s, {0, 0, 0, 1, 1}), CellId(3));
  EXPECT_EQ(Ask(s, {9, 0, 0, 1, 1}), CellId(4));  // after 3, not the fullest
  EXPECT_EQ(Ask(s, {9, 0, 0, 1, 0}), CellId(0));  // wraps
  EXPECT_EQ(Ask(s, {0, 0, 0, 1, 0}), CellId(3));
  EXPECT_EQ(Ask(s, {0, 0, 0, 1, 0}), CellId(3));  // the only cell with work, again
  EXPECT_EQ(Ask(s, {0, 0, 0, 0, 0}), std::nullopt);
}

TEST(RoundRobinTest, EachFrameStartsAtCellZero) {
  RoundRobinScheduler s;
  s.BeginFrame(Frame(0, 3));
  EXPECT_EQ(Ask(s, {1, 1, 1}), CellId(0));
  EXPECT_EQ(Ask(s, {0, 1, 1}), CellId(1));
  s.BeginFrame(Frame(1, 3));
  EXPECT_EQ(Ask(s, {1, 1, 1}), CellId(0));
}

// ------------------------------------------------------------------ Random

TEST(RandomTest, SplitMixAndXoshiroMatchTheReferenceCode) {
  // splitmix64 from seed 0, and xoshiro256** from state {1, 2, 3, 4}: the first two outputs
  // worked out by hand from the reference code (rotl(2 * 5, 7) * 9 = 11520, then s[1] = 0).
  EXPECT_EQ(SplitMix64(0).Next(), 0xe220a8397b1dcdafULL);
  Xoshiro256 x(1, 2, 3, 4);
  EXPECT_EQ(x.Next(), 11520u);
  EXPECT_EQ(x.Next(), 0u);
}

TEST(RandomTest, BelowStaysInRangeAndCoversIt) {
  Xoshiro256 x(42);
  std::vector<int> hits(7, 0);
  for (int i = 0; i < 7000; ++i) {
    const std::uint64_t r = x.Below(7);
    ASSERT_LT(r, 7u);
    ++hits[r];
  }
  for (int h : hits) EXPECT_GT(h, 800);  // 1000 expected; far from 800 by ~6 sigma
  EXPECT_EQ(x.Below(1), 0u);
}

std::vector<CellId> Draws(RandomScheduler& s, std::size_t frame, const Queues& q, int n) {
  s.BeginFrame(Frame(frame, static_cast<std::uint32_t>(q.size())));
  std::vector<CellId> out;
  for (int i = 0; i < n; ++i) out.push_back(*Ask(s, q));
  return out;
}

TEST(RandomTest, OnlyCellsWithWorkAllOfThem) {
  RandomScheduler s(7);
  EXPECT_EQ(s.Name(), "random");
  const Queues q = {0, 3, 0, 1, 0, 0, 8, 0};
  const std::vector<CellId> d = Draws(s, 0, q, 300);
  EXPECT_EQ(std::set<CellId>(d.begin(), d.end()),
            (std::set<CellId>{CellId(1), CellId(3), CellId(6)}));
  EXPECT_EQ(Ask(s, {0, 0, 0}), std::nullopt);
  EXPECT_EQ(Ask(s, {0, 0, 2}), CellId(2));
}

TEST(RandomTest, DeterministicPerSeedAndFrameDifferentAcrossFrames) {
  const Queues q(16, 1);
  RandomScheduler a(123), b(123), other_seed(124);
  const std::vector<CellId> frame3 = Draws(a, 3, q, 20);
  EXPECT_EQ(Draws(a, 0, q, 20), Draws(b, 0, q, 20));
  EXPECT_EQ(Draws(b, 3, q, 20), frame3);  // a frame replays alone, whatever came before
  EXPECT_NE(Draws(a, 4, q, 20), frame3);
  EXPECT_NE(Draws(other_seed, 3, q, 20), frame3);
  EXPECT_NE(RandomScheduler::FrameSeed(1, 0), RandomScheduler::FrameSeed(0, 1));
}

TEST(RandomTest, ChoicesArePinned) {
  // Pins the stream: the same on every compiler and standard library. If this changes,
  // recorded Random baselines stop being reproducible.
  RandomScheduler s(2002);
  EXPECT_EQ(Draws(s, 5, Queues(10, 1), 8), (testing::CellList{3, 7, 6, 8, 2, 4, 4, 0}));
}

// ------------------------------------------------------------------ Peel oracle, Cell Tree

// Paths A B, A B, C A: Peel gives C A B (docs/design.md §1: B is ready and peeled first, then both
// A nodes, then C).
class FollowTest : public ::testing::Test {
 protected:
  const CellTree tree_ = FromPaths({{A, B}, {A, B}, {C, A}});
  void SetUp() override { ASSERT_EQ(Peel(tree_).schedule, (Schedule{C, A, B})); }
};

TEST_F(FollowTest, PeelOracleFollowsTheScheduleThenMaxWork) {
  PeelOracleScheduler s;
  EXPECT_EQ(s.Name(), "peel");
  s.BeginFrame(Frame(0, 3, &tree_));
  EXPECT_EQ(Ask(s, {2, 0, 1}), C);  // not Max Work's A
  EXPECT_EQ(Ask(s, {3, 0, 0}), A);
  EXPECT_EQ(Ask(s, {0, 2, 0}), B);
  EXPECT_EQ(s.follower().cursor(), 3u);
  EXPECT_EQ(Ask(s, {1, 5, 5}), B);  // used up: Max Work
  EXPECT_EQ(Ask(s, {0, 0, 0}), std::nullopt);
  EXPECT_EQ(s.follower().stats().ToString(), "followed 3, skipped 0, deferred 0, max work 1");
}

TEST_F(FollowTest, PeelOracleSkipsEntriesWithoutWork) {
  PeelOracleScheduler s;
  s.BeginFrame(Frame(0, 3, &tree_));
  EXPECT_EQ(s.Reason(), "");        // no Next yet
  EXPECT_EQ(Ask(s, {2, 0, 0}), A);  // C skipped
  EXPECT_EQ(s.Reason(), "followed (skipped 1)");
  EXPECT_EQ(Ask(s, {0, 0, 4}), C);  // B skipped, used up: Max Work
  EXPECT_EQ(s.Reason(), "max work (skipped 1)");
  EXPECT_EQ(Ask(s, {0, 0, 4}), C);
  EXPECT_EQ(s.Reason(), "max work");
  EXPECT_EQ(s.follower().stats().ToString(), "followed 1, skipped 2, deferred 0, max work 2");
  s.BeginFrame(Frame(1, 3, &tree_));  // starts over
  EXPECT_EQ(s.Reason(), "");
  EXPECT_EQ(Ask(s, {1, 1, 1}), C);
  EXPECT_EQ(s.Reason(), "followed");
  EXPECT_EQ(Ask(s, {0, 0, 0}), std::nullopt);
  EXPECT_EQ(s.Reason(), "");  // no work: no choice to explain
  MaxWorkScheduler m;
  m.BeginFrame(Frame(0, 3, &tree_));
  EXPECT_EQ(Ask(m, {1, 1, 1}), A);
  EXPECT_EQ(m.Reason(), "");  // the default: nothing beyond the name
}

// With several processors a processor may ask while every cell with work is being worked
// (its view is empty): it gets nothing, and the schedule keeps its place.
TEST_F(FollowTest, AnEmptyViewSkipsNothing) {
  PeelOracleScheduler s;
  s.BeginFrame(Frame(0, 3, &tree_));
  EXPECT_EQ(Ask(s, {0, 0, 0}), std::nullopt);
  EXPECT_EQ(s.follower().cursor(), 0u);
  EXPECT_EQ(Ask(s, {2, 0, 1}), C);  // still the schedule's first entry, not Max Work's A
  EXPECT_EQ(s.Reason(), "followed");
  EXPECT_EQ(Ask(s, {0, 0, 0}), std::nullopt);
  EXPECT_EQ(Ask(s, {3, 0, 0}), A);
  EXPECT_EQ(s.follower().stats().ToString(), "followed 2, skipped 0, deferred 0, max work 0");
}

// With several processors an entry whose cell another processor is working is deferred, not
// used up: the next entry with work is taken, and the deferred one stays first in line until
// its cell is free; only a free cell without work is skipped.
TEST(ScheduleFollowerTest, EntriesOfBusyCellsAreDeferredNotLost) {
  ScheduleFollower f;
  f.Reset({A, B, C, A}, 3);
  // A is busy (open 0) and masked out of the queues; B has work.
  std::vector<std::uint64_t> open = {0, ~std::uint64_t{0}, ~std::uint64_t{0}};
  const auto view = [&](const Queues& q) {
    QueueView v = QueueView::Of(q);
    v.open = open.data();
    return v;
  };
  Queues q1 = {0, 3, 0};
  EXPECT_EQ(f.Next(view(q1)), B);
  EXPECT_EQ(f.cursor(), 0u);  // the first A waits
  // Still busy, C has work: C, the first A still deferred.
  Queues q2 = {0, 0, 2};
  EXPECT_EQ(f.Next(view(q2)), C);
  // A free again with work: its first entry, not Max Work's B.
  open[0] = ~std::uint64_t{0};
  Queues q3 = {1, 4, 0};
  EXPECT_EQ(f.Next(view(q3)), A);
  EXPECT_EQ(f.cursor(), 3u);       // entries 0..2 taken
  EXPECT_EQ(f.Next(view(q3)), A);  // the last entry
  EXPECT_EQ(f.stats().ToString(), "followed 4, skipped 0, deferred 2, max work 0");
  // Every entry left deferred: Max Work chooses, the entries stay.
  f.Reset({A, B}, 3);
  open[0] = 0;
  open[1] = 0;
  Queues q4 = {0, 0, 5};
  EXPECT_EQ(f.Next(view(q4)), C);
  EXPECT_EQ(f.Reason(), "max work");
  EXPECT_EQ(f.cursor(), 0u);
  // A free cell without work is skipped (used up) as with one processor.
  open[0] = ~std::uint64_t{0};
  EXPECT_EQ(f.Next(view(q4)), C);
  EXPECT_EQ(f.Reason(), "max work (skipped 1)");
  EXPECT_EQ(f.cursor(), 1u);  // A used up, B deferred
}

TEST_F(FollowTest, CellTreeFrameZeroIsMaxWork) {
  CellTreeScheduler s;
  EXPECT_EQ(s.Name(), "celltree");
  s.BeginFrame(Frame(0, 3, &tree_, nullptr));  // the current tree is not looked at
  EXPECT_EQ(Ask(s, {2, 0, 1}), A);
  EXPECT_EQ(Ask(s, {0, 2, 1}), B);
  EXPECT_EQ(Ask(s, {0, 0, 1}), C);
  EXPECT_EQ(s.follower().stats().max_work, 3u);
}

TEST_F(FollowTest, CellTreeFollowsThePreviousFramesPeel) {
  const CellTree current = FromPaths({{B}});  // Peel: B; ignored
  CellTreeScheduler s;
  s.BeginFrame(Frame(1, 3, &current, &tree_));
  EXPECT_EQ(s.follower().schedule(), (Schedule{C, A, B}));
  EXPECT_EQ(Ask(s, {2, 0, 1}), C);
  EXPECT_EQ(Ask(s, {0, 7, 0}), B);  // A skipped
  EXPECT_EQ(Ask(s, {1, 0, 2}), C);  // used up: Max Work
  EXPECT_EQ(Ask(s, {0, 0, 0}), std::nullopt);
  s.BeginFrame(Frame(2, 3, &tree_, nullptr));
  EXPECT_EQ(Ask(s, {2, 0, 1}), A);  // no previous tree: Max Work
}

TEST(PeelOracleDeathTest, NeedsTheCurrentTree) {
  PeelOracleScheduler s;
  EXPECT_DEATH(s.BeginFrame(Frame(0, 3)), "current");
}

TEST(CellTreeDeathTest, TreeCellsMustBeInTheGrid) {
  const CellTree t = FromPaths({{A, C}});
  CellTreeScheduler s;
  EXPECT_DEATH(s.BeginFrame(Frame(1, 2, nullptr, &t)), "CHECK failed");
}

// ------------------------------------------------------------------ best schedules

// Rotations of 0 1 2 3: the optimum is 2n - 1 = 7.
CellTree Rotations() { return FromPaths({{0, 1, 2, 3}, {1, 2, 3, 0}, {2, 3, 0, 1}, {3, 0, 1, 2}}); }

// Paths C A D B and A C A: Peel gives A C A D B A (6), the optimum is A C A D B (5).
// PlanEffort is part of what a planner means (docs/design.md §5 "Planners and PlanEffort"):
// beam 64, one local-search chain with the large windows (vary_windows off gives every chain
// them), 2000 windows within 2*10^8 node visits, the exact search to 20,000 states on trees of
// at most 1000 nodes, one thread, the seed given. A change here changes every planner's plans.
TEST(BestSchedulersTest, PlanEffortIsTheDocumentedBudget) {
  const BestScheduleOptions o = PlanEffort(7);
  EXPECT_EQ(o.seed, 7u);
  EXPECT_EQ(o.beam_width, 64u);
  EXPECT_EQ(o.chains, 1u);
  EXPECT_FALSE(o.vary_windows);
  EXPECT_EQ(o.threads, 1u);
  EXPECT_EQ(o.local.max_windows, 2000u);
  EXPECT_EQ(o.local.max_work, 200'000'000u);
  EXPECT_EQ(o.exact_states, 20000u);
  EXPECT_EQ(o.exact_max_nodes, 1000u);
}

// Fitted to a tree (docs/design.md §5 "Planners and PlanEffort"): on trees of up to a few
// thousand nodes the beam keeps its width and the re-timings' limit does not bind, so the plans
// are those of the unfitted budget.
TEST(BestSchedulersTest, PlanEffortFittedToASmallTreePlansAsTheBudget) {
  std::mt19937 rng(43);
  for (int i = 0; i < 3; ++i) {
    const CellTree t = testing::RandomTree(rng, 6 + i, 40 + 20 * i);
    const BestScheduleOptions fitted = PlanEffort(5, t);
    EXPECT_EQ(fitted.beam_width, 64u);
    // 2*10^8 / 50 node visits of re-timing: 4*10^6 / nodes re-timings.
    EXPECT_EQ(fitted.local.max_retimes, 4'000'000 / t.node_count()) << t.node_count();
    EXPECT_EQ(BestSchedule(t, fitted).schedule, BestSchedule(t, PlanEffort(5)).schedule);
  }
}

// A tree of 20,000 nodes (one ray's path over 4 cells in turn, a chain) whose maxGen bound is
// 20,000: the beam's first layer, 64 x 20,000 x 20,000 node visits, is past its 5*10^8, so no
// beam; re-timings 4*10^6 / 20,000 = 200. The plan is still feasible.
TEST(BestSchedulersTest, PlanEffortFittedToALargeTreeDropsTheBeamAndLimitsRetimes) {
  testing::CellList chain;  // one ray of 20,000 visits: every node a child of the last
  for (std::uint32_t i = 0; i < 20000; ++i) chain.push_back(CellId(i % 4));
  const CellTree t = FromPaths({chain});
  ASSERT_EQ(t.node_count(), 20000u);
  ASSERT_EQ(Bound(t), 20000u);
  const BestScheduleOptions fitted = PlanEffort(5, t);
  EXPECT_EQ(fitted.beam_width, 0u);
  EXPECT_EQ(fitted.local.max_retimes, 200u);
  EXPECT_EQ(fitted.local.max_windows, PlanEffort(5).local.max_windows);
}

// Past 2*10^6 nodes (4*10^6 / nodes < 2) one re-timing is left, the local search's start, after
// which it can change nothing (tests/search/local_search_test.cpp OneRetimeReturnsTheStart): no
// chain, so BestSchedule builds no forest for it (issue 43: the plan of a union of two 4096-cell
// frames, millions of nodes, in Peel's memory). A chain of 2,000,001 nodes over 4 cells.
TEST(BestSchedulersTest, PlanEffortFittedToAHugeTreeRunsNoLocalSearch) {
  testing::CellList chain;
  for (std::uint32_t i = 0; i < 2'000'001; ++i) chain.push_back(CellId(i % 4));
  const CellTree t = FromPaths({chain});
  const BestScheduleOptions fitted = PlanEffort(5, t);
  EXPECT_EQ(fitted.local.max_retimes, 1u);
  EXPECT_EQ(fitted.chains, 0u);
  EXPECT_EQ(fitted.beam_width, 0u);
  // One node fewer: two re-timings (one deletion), and the chain runs.
  chain.pop_back();
  const BestScheduleOptions two = PlanEffort(5, FromPaths({chain}));
  EXPECT_EQ(two.local.max_retimes, 2u);
  EXPECT_EQ(two.chains, 1u);
}

TEST(BestSchedulersTest, TheOracleFollowsItsOwnTreesBestSchedule) {
  const CellTree t = FromPaths({{C, A, CellId(3), B}, {A, C, A}});
  BestOracleScheduler s(3);
  s.BeginFrame(Frame(0, 4, &t, nullptr));
  const Schedule plan = s.follower().schedule();
  EXPECT_EQ(plan, PlanFor(t, 3));
  EXPECT_TRUE(IsFeasible(t, plan));
  EXPECT_EQ(plan.size(), 5u);
  EXPECT_EQ(testing::BruteForceOptimum(t), 5u);
  EXPECT_EQ(Peel(t).schedule.size(), 6u);
}

TEST(BestSchedulersTest, CellTreeBestFollowsThePreviousFramesPlan) {
  const CellTree t0 = Rotations(), t1 = FromPaths({{0, 1}, {1, 0}});
  CellTreeBestScheduler s(3, false);
  s.BeginFrame(Frame(0, 4, &t0, nullptr));
  EXPECT_TRUE(s.follower().schedule().empty());  // frame 0: Max Work
  s.BeginFrame(Frame(1, 4, &t1, &t0));
  EXPECT_EQ(s.follower().schedule(), PlanFor(t0, 3));
  s.BeginFrame(Frame(2, 4, nullptr, &t1));
  EXPECT_EQ(s.follower().schedule(), PlanFor(t1, 3));
}

// The union plan of frames i-1 and i serves both; without frame i-1's tree, frame i's alone.
TEST(BestSchedulersTest, CellTreeUnionPlansTheLastTwoFramesTogether) {
  const CellTree t0 = Rotations(), t1 = FromPaths({{3, 2, 1, 0}}), t2 = FromPaths({{0}});
  CellTreeBestScheduler s(3, true);
  s.BeginFrame(Frame(0, 4, &t0, nullptr));
  EXPECT_TRUE(s.follower().schedule().empty());
  s.BeginFrame(Frame(1, 4, &t1, &t0));
  EXPECT_EQ(s.follower().schedule(), PlanFor(t0, 3));  // no frame before 0: t0 alone
  FrameInfo two = Frame(2, 4, &t2, &t1);
  two.before_previous = &t0;
  s.BeginFrame(two);
  const Schedule plan = s.follower().schedule();
  EXPECT_EQ(plan, PlanFor(UnionTree({&t0, &t1}), 3));
  EXPECT_TRUE(IsFeasible(t0, plan));
  EXPECT_TRUE(IsFeasible(t1, plan));
  EXPECT_FALSE(IsFeasible(t1, PlanFor(t0, 3)));  // t0's plan alone would not serve t1
  EXPECT_EQ(SchedulerByName("celltree-union", "test").history, 2u);
  EXPECT_EQ(SchedulerByName("celltree-best", "test").history, 1u);
}

// ------------------------------------------------------------------ two levels

// Cells 0 and 1 on board cell 0, 2 on board cell 1 (FrameInfo::board_cell_of): frame i+1
// follows frame i's two-level plan (graph/peel.h TwoLevelPeel; two_level_test has its
// properties); without board cells, Peel's schedule (no entry of it wasted on this tree).
TEST(TwoLevelSchedulersTest, FollowThePreviousFramesTwoLevelPlan) {
  const CellTree t0 = FromPaths({{0, 2}, {1, 2, 0}, {2, 1}}), t1 = FromPaths({{0}});
  const std::vector<CellId> board{A, A, CellId(1)};
  TwoLevelScheduler s;
  EXPECT_EQ(s.Name(), "celltree-2level");
  FrameInfo f = Frame(0, 3, &t0, nullptr);
  f.board_cell_of = &board;
  s.BeginFrame(f);
  EXPECT_TRUE(s.follower().schedule().empty());  // frame 0: Max Work
  f = Frame(1, 3, &t1, &t0);
  f.board_cell_of = &board;
  s.BeginFrame(f);
  EXPECT_EQ(s.follower().schedule(), (Schedule{B, A, C, B, A}));  // board cells 0 1 0
  s.BeginFrame(Frame(1, 3, &t1, &t0));
  EXPECT_EQ(s.follower().schedule(), (Schedule{C, B, A, C, A}));  // Peel's

  // With the best-schedule search at both levels: feasible for frame i's tree, its stretches
  // on one board cell those of the plan for the contracted tree.
  TwoLevelBestScheduler b(3);
  EXPECT_EQ(b.Name(), "celltree-2level-best");
  f = Frame(1, 3, &t1, &t0);
  f.board_cell_of = &board;
  b.BeginFrame(f);
  const Schedule plan = b.follower().schedule();
  EXPECT_TRUE(IsFeasible(t0, plan));
  Schedule stretches;
  for (const CellId c : plan) {
    if (stretches.empty() || stretches.back() != board[c.value()])
      stretches.push_back(board[c.value()]);
  }
  EXPECT_EQ(stretches, (Schedule{A, CellId(1), A}));  // X Y X, the shortest for X Y X and Y X
  EXPECT_EQ(plan.size(), 5u);
}

// ------------------------------------------------------------------ factory

TEST(MakeSchedulerTest, EveryNameRoundTrips) {
  for (const std::string& name : SchedulerNames()) {
    const std::unique_ptr<Scheduler> s = MakeScheduler(name, 1);
    ASSERT_NE(s, nullptr);
    EXPECT_EQ(s->Name(), name);
  }
  EXPECT_EQ(SchedulerNames().size(), 22u);
  EXPECT_NE(dynamic_cast<RandomScheduler*>(MakeScheduler("random", 99).get()), nullptr);
  EXPECT_EQ(dynamic_cast<RandomScheduler&>(*MakeScheduler("random", 99)).seed(), 99u);
}

// Each scheduler's file declares its entry; the registry lists them in the order --help,
// sweeps and the study show. Every entry's flags, as the replay, prefetch, the seed key's help
// and the study read them (history, seeded, predicts, oracle, studied), and every scheduler an
// entry makes is named by that entry.
TEST(SchedulerRegistryTest, EntriesKeepTheirFlagsAndNameWhatTheyMake) {
  struct Flags {
    const char* name;
    std::uint32_t history;
    bool seeded, predicts, oracle, studied;
  };
  const Flags expected[] = {
      {"maxwork", 0, false, true, false, true},
      {"roundrobin", 0, false, true, false, false},
      {"random", 0, true, false, false, false},
      {"peel", 0, false, true, true, true},
      {"celltree", 1, false, true, false, true},
      {"best", 1, true, true, true, true},
      {"celltree-best", 1, true, true, false, true},
      {"celltree-union", 2, true, true, false, true},
      {"affinity", 1, false, true, false, false},
      {"partition", 1, true, true, false, false},
      {"steal", 1, false, true, false, false},
      {"partition-steal", 1, true, true, false, false},
      {"share", 1, false, true, false, false},
      {"balanced", 1, true, true, false, false},
      {"celltree-2level", 1, false, true, false, false},
      {"celltree-2level-best", 1, true, true, false, false},
      {"balanced-critical", 1, true, true, false, false},
      {"balanced-adaptive", 2, true, true, false, false},
      {"celltree-adaptive", 2, true, true, false, true},
      {"celltree-dag", 1, true, true, false, false},
      {"celltree-dag-oracle", 0, true, true, true, false},
      {"auto", 2, true, true, false, false},
  };
  ASSERT_EQ(SchedulerRegistry().size(), std::size(expected));
  for (std::size_t i = 0; i < std::size(expected); ++i) {
    const SchedulerEntry& e = SchedulerRegistry()[i];
    const Flags& f = expected[i];
    EXPECT_STREQ(e.name, f.name);
    EXPECT_EQ(e.history, f.history) << f.name;
    EXPECT_EQ(e.seeded, f.seeded) << f.name;
    EXPECT_EQ(e.predicts, f.predicts) << f.name;
    EXPECT_EQ(e.oracle, f.oracle) << f.name;
    EXPECT_EQ(e.studied, f.studied) << f.name;
    EXPECT_NE(std::string(e.meaning), "") << f.name;
    EXPECT_NE(std::string(e.label), "") << f.name;
    EXPECT_EQ(&SchedulerByName(f.name, "test"), &e);
    const std::unique_ptr<Scheduler> s = MakeScheduler(e, 1);
    EXPECT_EQ(&s->entry(), &e) << f.name;
    EXPECT_EQ(s->Name(), f.name);
  }
  // The entries by their variables, as the study names them.
  EXPECT_EQ(&SchedulerByName("maxwork", "test"), &kMaxWorkEntry);
  EXPECT_EQ(&SchedulerByName("celltree", "test"), &kCellTreeEntry);
  EXPECT_EQ(&SchedulerByName("celltree-union", "test"), &kCellTreeUnionEntry);
  EXPECT_EQ(SeededSchedulerList(", "),
            "random, best, celltree-best, celltree-union, partition, partition-steal, balanced, "
            "celltree-2level-best, balanced-critical, balanced-adaptive, celltree-adaptive, "
            "celltree-dag, celltree-dag-oracle, auto");
}

TEST(MakeSchedulerTest, UnknownNameListsTheValidOnes) {
  try {
    MakeScheduler("MaxWork", 0);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(),
                 "scheduler: unknown scheduler 'MaxWork' (expected maxwork, roundrobin, random, "
                 "peel, celltree, best, celltree-best, celltree-union, affinity, partition, steal, "
                 "partition-steal, share, balanced, celltree-2level, celltree-2level-best, "
                 "balanced-critical, balanced-adaptive, celltree-adaptive, celltree-dag, "
                 "celltree-dag-oracle or auto)");
  }
  EXPECT_THROW(MakeScheduler("", 0), InputError);
}

// Next on a view without work answers nothing and changes nothing (Scheduler::Next's
// contract, on which the replay's idle processors rely to skip asking): for every scheduler,
// one asked with empty views between its real questions chooses as one that never was, and
// foretells (Peek) and explains (Reason) its choices the same.
TEST(SchedulerContract, AnEmptyViewChangesNothing) {
  const CellTree t0 = FromPaths({{A, B, C}, {C, A}, {B, C, A}});
  const CellTree t1 = FromPaths({{B, A, C}, {A, C}, {C, B}});
  const CellTree t2 = FromPaths({{C, B, A}, {A, B}});
  const CellTree* trees[] = {&t0, &t1, &t2};
  const Queues none{0, 0, 0};
  for (const std::string& name : SchedulerNames()) {
    SCOPED_TRACE(name);
    auto plain = MakeScheduler(name, 7), asked = MakeScheduler(name, 7);
    std::mt19937 rng(11);
    for (std::size_t frame = 0; frame < 3; ++frame) {
      FrameInfo f = Frame(frame, 3, trees[frame], frame >= 1 ? trees[frame - 1] : nullptr);
      f.before_previous = frame >= 2 ? trees[frame - 2] : nullptr;
      plain->BeginFrame(f);
      asked->BeginFrame(f);
      for (int step = 0; step < 12; ++step) {
        const std::uint32_t empties = rng() % 3;
        for (std::uint32_t k = 0; k < empties; ++k) EXPECT_EQ(Ask(*asked, none), std::nullopt);
        Queues q{rng() % 3, rng() % 3, rng() % 3};
        if (q == none) q[rng() % 3] = 1;
        EXPECT_EQ(asked->Peek(QueueView::Of(q)), plain->Peek(QueueView::Of(q)));
        EXPECT_EQ(Ask(*asked, q), Ask(*plain, q)) << "frame " << frame << " step " << step;
        EXPECT_EQ(asked->Reason(), plain->Reason());
      }
    }
  }
}

// Peek foretells Next without changing anything, for every scheduler that predicts (all but
// Random, which has no prediction).
TEST(SchedulerPeek, ForetellsNextAndChangesNothing) {
  const CellTree tree = FromPaths({{A, B, C}, {C, A}, {B, C}});
  std::mt19937 rng(3);
  for (const char* name : {"maxwork", "roundrobin", "peel", "celltree"}) {
    auto s = MakeScheduler(name, 1);
    s->BeginFrame(Frame(1, 3, &tree, &tree));
    for (int step = 0; step < 20; ++step) {
      Queues q{rng() % 3, rng() % 3, rng() % 3};
      const auto first = s->Peek(QueueView::Of(q));
      EXPECT_EQ(s->Peek(QueueView::Of(q)), first) << name;
      EXPECT_EQ(s->Next(QueueView::Of(q)), first) << name << " step " << step;
    }
  }
  auto random = MakeScheduler("random", 1);
  random->BeginFrame(Frame(0, 3));
  EXPECT_EQ(random->Peek(QueueView::Of(Queues{1, 1, 1})), std::nullopt);
}

// A plan cache makes each value once; ReleaseAll (the runner's, once every configuration of a
// frame began) forgets every value: one a holder keeps lives on, one no one holds goes at once,
// and either is made again when asked for again (issue 43).
TEST(PlanCache, ReleaseAllForgetsEveryValueWhileHoldersKeepTheirs) {
  PlanCache cache;
  int made = 0;
  const auto make = [&] { return ++made; };
  const std::shared_ptr<const int> held = cache.Get<int>(1, make);
  std::weak_ptr<const int> dropped = cache.Get<int>(2, make);
  EXPECT_EQ(*cache.Get<int>(1, make), 1);
  EXPECT_EQ(cache.made(), 2u);
  EXPECT_FALSE(dropped.expired());  // the cache keeps it
  cache.ReleaseAll();
  EXPECT_TRUE(dropped.expired());
  EXPECT_EQ(*held, 1);
  EXPECT_EQ(*cache.Get<int>(1, make), 3);  // made again
  EXPECT_EQ(*cache.Get<int>(2, make), 4);
  EXPECT_EQ(cache.made(), 4u);
}

}  // namespace
}  // namespace raycell
