// Schedulers driven by a small, independent functional replay with a one-cell cache
// (docs/design.md §1 "Max Work", "Cell Tree scheduling"), checked against the Cell Tree of the
// same rays: its bound, Peel and the schedule feasibility checker.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "graph/peel.h"
#include "graph/schedule.h"
#include "scheduling/best_scheduler.h"
#include "scheduling/cell_tree_scheduler.h"
#include "scheduling/scheduler.h"
#include "tests/cell_list.h"
#include "tests/graph/test_trees.h"

namespace raycell {
namespace {

constexpr CellId A{0}, B{1}, C{2};
using Schedule = testing::CellList;

// One ray of a test frame. Rays are listed in id order, one ray tree at a time (a primary
// ray, then its descendants), as CellTreeBuilder wants them.
using testing::TestRay;
using TestFrame = std::vector<TestRay>;

TestRay P(Schedule cells) { return {kNoParent, 0, std::move(cells)}; }
TestRay S(RayId parent, std::uint32_t spawn, Schedule cells) {
  return {parent, spawn, std::move(cells)};
}

CellTree TreeOf(const TestFrame& frame) { return testing::TreeOf(testing::RaysOf(frame)); }

struct ReplayResult {
  Schedule fetched;        // the cells fetched, in order
  bool conserved = false;  // every visit worked exactly once
  std::size_t fetches() const { return fetched.size(); }
};

// The reference replay: per-cell queues of (ray, visit). A primary ray is queued at its
// first cell. Fetching cell c works every ray queued at c: the ray moves on to its next
// visit's cell and is queued there, and the rays spawned at the worked visit are worked in c
// at once, recursively (spawned rays are not queued).
class FunctionalReplay {
 public:
  FunctionalReplay(const TestFrame& frame, std::uint32_t cells)
      : frame_(frame), queues_(cells), counts_(cells, 0), spawned_(frame.size()) {
    for (std::size_t r = 0; r < frame.size(); ++r) {
      worked_.emplace_back(frame[r].cells.size(), 0);
      spawned_[r].resize(frame[r].cells.size());
      if (frame[r].parent != kNoParent) spawned_[frame[r].parent][frame[r].spawn].push_back(r);
      if (frame[r].parent == kNoParent && !frame[r].cells.empty()) Enqueue(r, 0);
    }
  }

  // Asks `scheduler` (BeginFrame already called) for cells until it has none.
  ReplayResult Run(Scheduler& scheduler) {
    ReplayResult out;
    std::optional<CellId> loaded;
    while (const std::optional<CellId> c = scheduler.Next(QueueView::Of(counts_, loaded))) {
      EXPECT_LT(c->value(), counts_.size());
      EXPECT_GT(counts_[c->value()], 0u) << "fetch " << out.fetches() << " of a cell without work";
      if (c->value() >= counts_.size() || counts_[c->value()] == 0 || out.fetches() > kMaxFetches)
        return out;
      Fetch(*c);
      loaded = *c;
      out.fetched.push_back(*c);
    }
    for (std::uint64_t n : counts_) EXPECT_EQ(n, 0u) << "nullopt while rays are queued";
    out.conserved = Conserved();
    return out;
  }

 private:
  static constexpr std::size_t kMaxFetches = 100000;

  void Enqueue(std::size_t ray, std::size_t visit) {
    const CellId c = frame_[ray].cells[visit];
    queues_[c.value()].push_back({ray, visit});
    ++counts_[c.value()];
  }
  void Fetch(CellId c) {
    std::vector<std::pair<std::size_t, std::size_t>> work;
    work.swap(queues_[c.value()]);
    counts_[c.value()] = 0;
    for (const auto& [ray, visit] : work) Work(ray, visit, c);
    EXPECT_EQ(counts_[c.value()], 0u) << "a ray was queued at the loaded cell " << c;
  }
  void Work(std::size_t ray, std::size_t visit, CellId loaded) {
    EXPECT_EQ(frame_[ray].cells[visit], loaded);
    ++worked_[ray][visit];
    for (std::size_t child : spawned_[ray][visit]) Work(child, 0, loaded);
    if (visit + 1 < frame_[ray].cells.size()) Enqueue(ray, visit + 1);
  }
  bool Conserved() const {
    for (const std::vector<int>& w : worked_) {
      for (int n : w) {
        if (n != 1) return false;
      }
    }
    return true;
  }

  const TestFrame& frame_;
  std::vector<std::vector<std::pair<std::size_t, std::size_t>>> queues_;
  std::vector<std::uint64_t> counts_;
  std::vector<std::vector<std::vector<std::size_t>>> spawned_;  // [ray][visit] -> rays
  std::vector<std::vector<int>> worked_;                        // [ray][visit] -> times
};

ReplayResult Replay(const std::string& name, const TestFrame& frame, std::uint32_t cells,
                    std::size_t index = 0, const CellTree* previous = nullptr) {
  const CellTree tree = TreeOf(frame);
  const std::unique_ptr<Scheduler> s = MakeScheduler(name, 5);
  s->BeginFrame({index, &tree, previous, cells});
  return FunctionalReplay(frame, cells).Run(*s);
}

// ------------------------------------------------------------------ hand-made frames

// A B, A B, C A. Tree: A1 -> B1 (enter 2), C1 -> A2; every maxGen 1, bound 3.
// Max Work: queues A2 C1 -> A; B2 C1 -> B; C1 -> C; A1 -> A: 4 fetches.
// Peel: B is ready first, then both A nodes, then C: schedule C A B; the oracle fetches C
// (r2 to A), A (r0, r1 to B, r2 done), B: 3 fetches, the bound.
const TestFrame kCrossed = {P({A, B}), P({A, B}), P({C, A})};

TEST(FetchReferenceTest, MaxWorkAndPeelOracleOnCrossedPaths) {
  const CellTree tree = TreeOf(kCrossed);
  EXPECT_EQ(Bound(tree), 3u);
  EXPECT_EQ(Peel(tree).schedule, (Schedule{C, A, B}));
  const ReplayResult mw = Replay("maxwork", kCrossed, 3);
  EXPECT_EQ(mw.fetched, (Schedule{A, B, C, A}));
  EXPECT_TRUE(mw.conserved);
  const ReplayResult peel = Replay("peel", kCrossed, 3);
  EXPECT_EQ(peel.fetched, (Schedule{C, A, B}));
  EXPECT_TRUE(peel.conserved);
}

// r0: A B; r1 spawned by r0 in A: A C; r2 spawned by r0 in B: B A.
// Max Work: A (r0 to B; r1 worked in A at once, to C); B C tie -> B (r0 done; r2 worked in
// B, to A); A C tie -> A (r2 done); C (r1 done): 4 fetches. Had spawned rays been queued,
// A and B would each need a second fetch.
// Tree: A1 -> B1 -> A2 (gen 2), A1 -> C1: bound 2 + 1 + 1 = 4. Peel: A (A2 ready), B, C,
// A: schedule A C B A, and the oracle fetches all four.
const TestFrame kSpawning = {P({A, B}), S(0, 0, {A, C}), S(0, 1, {B, A})};

TEST(FetchReferenceTest, SpawnedRaysAreWorkedInTheLoadedCell) {
  const CellTree tree = TreeOf(kSpawning);
  EXPECT_EQ(Bound(tree), 4u);
  EXPECT_EQ(Peel(tree).schedule, (Schedule{A, C, B, A}));
  const ReplayResult mw = Replay("maxwork", kSpawning, 3);
  EXPECT_EQ(mw.fetched, (Schedule{A, B, A, C}));
  EXPECT_TRUE(mw.conserved);
  const ReplayResult peel = Replay("peel", kSpawning, 3);
  EXPECT_EQ(peel.fetched, (Schedule{A, C, B, A}));
  EXPECT_TRUE(peel.conserved);
}

// A B, B A: bound 2, Peel A B A (one split peel). Every schedule needs 3 fetches here.
TEST(FetchReferenceTest, PeelOracleBetweenBoundAndPeelLengthWithASplit) {
  const TestFrame frame = {P({A, B}), P({B, A})};
  const CellTree tree = TreeOf(frame);
  const ReplayResult peel = Replay("peel", frame, 2);
  EXPECT_EQ(peel.fetched, (Schedule{A, B, A}));
  EXPECT_GT(peel.fetches(), Bound(tree));
  EXPECT_EQ(peel.fetches(), Peel(tree).schedule.size());
}

// Frame 0 is kCrossed (Peel C A B). Cell Tree scheduling:
//  - frame 0 is Max Work: A B C A;
//  - frame 1 with the same rays follows C A B: 3 fetches where Max Work needs 4;
//  - frame 1 = A B, A B: C has no work and is skipped, then A, B: 2 fetches;
//  - frame 1 = B C, C A, A B: C (r1 to A), A (r1 done, r2 to B), B (r0 to C, r2 done), then
//    the schedule is used up and Max Work fetches C: 4 fetches (the optimum: the paths form
//    a cycle).
TEST(FetchReferenceTest, CellTreeSchedulingFollowsTheLastFramesPeel) {
  const CellTree frame0 = TreeOf(kCrossed);
  EXPECT_EQ(Replay("celltree", kCrossed, 3, 0, nullptr).fetched, (Schedule{A, B, C, A}));
  EXPECT_EQ(Replay("celltree", kCrossed, 3, 1, &frame0).fetched, (Schedule{C, A, B}));
  EXPECT_EQ(Replay("maxwork", kCrossed, 3, 1).fetches(), 4u);
  EXPECT_EQ(Replay("celltree", {P({A, B}), P({A, B})}, 3, 1, &frame0).fetched, (Schedule{A, B}));
  const TestFrame cycle = {P({B, C}), P({C, A}), P({A, B})};
  const ReplayResult r = Replay("celltree", cycle, 3, 1, &frame0);
  EXPECT_EQ(r.fetched, (Schedule{C, A, B, C}));
  EXPECT_TRUE(r.conserved);
}

TEST(FetchReferenceTest, CellTreeStatsCountFollowedSkippedAndMaxWork) {
  const CellTree frame0 = TreeOf(kCrossed);
  const TestFrame frame1 = {P({B, C}), P({C, A}), P({A, B}), P({B})};
  CellTreeScheduler s;
  s.BeginFrame({1, nullptr, &frame0, 3});
  // C (r1 to A), A (r1 done, r2 to B), B (r0 to C; r2, r3 done), then Max Work C.
  EXPECT_EQ(FunctionalReplay(frame1, 3).Run(s).fetched, (Schedule{C, A, B, C}));
  EXPECT_EQ(s.follower().stats().ToString(), "followed 3, skipped 0, deferred 0, max work 1");
}

// ------------------------------------------------------------------ random frames

// A random frame: 1..6 ray trees; paths of 1..5 visits with no cell twice in a row; each
// visit spawns a ray (starting in the visit's cell) with probability 1/4, to depth 2.
class FrameMaker {
 public:
  FrameMaker(std::uint64_t seed, std::uint32_t cells) : rng_(seed), cells_(cells) {}
  TestFrame Make() {
    TestFrame frame;
    for (std::uint64_t t = 1 + Draw(6); t > 0; --t)
      AddRay(frame, kNoParent, 0, CellId(Draw(cells_)), 0);
    return frame;
  }

 private:
  std::uint64_t Draw(std::uint64_t n) { return rng_() % n; }
  void AddRay(TestFrame& frame, RayId parent, std::uint32_t spawn, CellId first, int depth) {
    const RayId id = frame.size();
    frame.push_back({parent, spawn, {first}});
    for (std::uint64_t n = Draw(5); n > 0; --n) {
      const std::uint64_t step = 1 + Draw(cells_ - 1);
      frame[id].cells.push_back(CellId((frame[id].cells.back().value() + step) % cells_));
    }
    if (depth == 2) return;
    for (std::uint32_t v = 0; v < frame[id].cells.size(); ++v) {
      if (Draw(4) == 0) AddRay(frame, id, v, frame[id].cells[v], depth + 1);
    }
  }

  std::mt19937_64 rng_;  // the engine's output is fixed by the standard; only % is used
  std::uint32_t cells_;
};

// Over 1000 seeded frames (250 each on 2, 3, 4 and 8 cells, each frame's Cell Tree passed on
// as the next frame's previous tree): every scheduler empties all queues, works every visit
// once, fetches at least the bound, and its fetch order is a feasible schedule. The Peel
// oracle's fetches are exactly the useful entries of the Peel schedule, so within
// [bound, Peel length]. The frames must also exercise the interesting cases: the oracle
// skipping Peel entries, Max Work missing the bound, Cell Tree scheduling beating Max Work.
TEST(FetchReferenceTest, EverySchedulerConservesWorkAndFetchesFeasiblyOnRandomFrames) {
  std::size_t frames = 0, oracle_skips = 0, max_work_above_bound = 0, cell_tree_wins = 0;
  for (std::uint32_t cells : {2u, 3u, 4u, 8u}) {
    FrameMaker maker(1000 + cells, cells);
    std::optional<CellTree> previous;
    for (std::size_t i = 0; i < 250; ++i, ++frames) {
      const TestFrame frame = maker.Make();
      const CellTree tree = TreeOf(frame);
      const PeelResult peel = Peel(tree);
      const std::size_t max_work = Replay("maxwork", frame, cells).fetches();
      max_work_above_bound += max_work > Bound(tree) ? 1 : 0;
      for (const std::string& name : SchedulerNames()) {
        const ReplayResult r = Replay(name, frame, cells, i, previous ? &*previous : nullptr);
        ASSERT_TRUE(r.conserved) << name << ", cells " << cells << ", frame " << i;
        ASSERT_GE(r.fetches(), Bound(tree)) << name << ", frame " << i;
        ASSERT_TRUE(IsFeasible(tree, r.fetched)) << name << ", frame " << i;
        cell_tree_wins += name == "celltree" && r.fetches() < max_work ? 1 : 0;
        if (name == "best") {  // the useful entries of its own tree's best schedule
          const std::vector<CellId> plan = PlanFor(tree, 5);
          ASSERT_LE(plan.size(), peel.schedule.size());
          ASSERT_EQ(r.fetches(), RunSchedule(tree, plan).useful_fetches);
        }
        if (name != "peel") continue;
        oracle_skips += r.fetches() < peel.schedule.size() ? 1 : 0;
        ASSERT_LE(r.fetches(), peel.schedule.size()) << tree.ToString();
        ASSERT_EQ(r.fetches(), RunSchedule(tree, peel.schedule).useful_fetches);
      }
      previous = tree;
    }
  }
  EXPECT_EQ(frames, 1000u);
  EXPECT_GT(oracle_skips, 10u);
  EXPECT_GT(max_work_above_bound, 10u);
  EXPECT_GT(cell_tree_wins, 10u);
  std::printf(
      "oracle skipped entries in %zu frames, Max Work above the bound in %zu, Cell Tree "
      "beat Max Work in %zu\n",
      oracle_skips, max_work_above_bound, cell_tree_wins);
}

}  // namespace
}  // namespace raycell
