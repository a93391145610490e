#include "graph/peel.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "graph/schedule.h"
#include "tests/cell_list.h"
#include "tests/graph/test_trees.h"

namespace raycell {
namespace {

using testing::FromPaths;
using testing::RandomTree;

constexpr CellId A{0}, B{1}, C{2};
using Schedule = testing::CellList;
constexpr PeelKind kC = PeelKind::kCompletion, kS = PeelKind::kSplit;

// An independent, naive run of a schedule: at each entry, scan every node.
struct NaiveRun {
  bool feasible;
  std::size_t useful;
};
NaiveRun RunNaive(const CellTree& t, const Schedule& schedule) {
  std::vector<bool> done(t.size(), false);
  done[kRootNode.index()] = true;
  std::size_t useful = 0;
  for (CellId c : schedule) {
    std::vector<NodeId> now;
    for (NodeId n : t.nodes()) {
      if (!done[n.index()] && t.cell(n) == c && done[t.parent(n).index()]) now.push_back(n);
    }
    for (NodeId n : now) done[n.index()] = true;
    useful += now.empty() ? 0 : 1;
  }
  return {std::all_of(done.begin(), done.end(), [](bool d) { return d; }), useful};
}

// Peel straight from docs/design.md's pseudo-code, recomputing everything at every step
// (O(nodes^2)): the reference the bucketed Peel must match entry for entry.
PeelResult NaivePeel(const CellTree& t) {
  std::vector<bool> gone(t.size(), false);
  gone[kRootNode.index()] = true;
  PeelResult out;
  for (std::size_t left = t.node_count(); left > 0;) {
    std::vector<bool> leaf(t.size(), true);
    for (NodeId n : t.nodes()) {
      if (!gone[n.index()]) leaf[t.parent(n).index()] = false;
    }
    std::vector<std::uint32_t> top(t.cell_count(), 0);
    std::vector<std::size_t> leaves(t.cell_count(), 0);
    for (NodeId n : t.nodes()) {
      if (gone[n.index()]) continue;
      top[t.cell(n).value()] = std::max(top[t.cell(n).value()], t.generation(n));
      leaves[t.cell(n).value()] += leaf[n.index()] ? 1 : 0;
    }
    std::vector<bool> ready(t.cell_count());
    for (std::uint32_t c = 0; c < t.cell_count(); ++c) ready[c] = top[c] > 0;
    for (NodeId n : t.nodes()) {
      if (!gone[n.index()] && !leaf[n.index()] && t.generation(n) == top[t.cell(n).value()])
        ready[t.cell(n).value()] = false;
    }
    const auto r = std::find(ready.begin(), ready.end(), true);
    const bool completion = r != ready.end();
    const auto c = static_cast<CellId>(completion ? r - ready.begin()
                                                  : std::max_element(leaves.begin(), leaves.end()) -
                                                        leaves.begin());
    for (NodeId n : t.nodes()) {
      if (!gone[n.index()] && leaf[n.index()] && t.cell(n) == c) gone[n.index()] = true, --left;
    }
    out.schedule.insert(out.schedule.begin(), c);
    out.kinds.insert(out.kinds.begin(), completion ? kC : kS);
    out.split_peels += completion ? 0 : 1;
  }
  return out;
}

// ------------------------------------------------------------------ hand-made trees

// root -> A1 -> B1, root -> B2 -> A2. Nothing is ready (A1 and B1's sibling B2 are not
// leaves); both cells have one leaf, so split peel A (lowest) removes A2. Then B1 and B2
// are leaves: completion B. Then A1: completion A. Reverse peels: A B A.
TEST(PeelTest, TwoCrossedPaths) {
  const CellTree t = FromPaths({{A, B}, {B, A}});
  const PeelResult p = Peel(t);
  EXPECT_EQ(p.schedule, (Schedule{A, B, A}));
  EXPECT_EQ(p.kinds, (std::vector<PeelKind>{kC, kC, kS}));
  EXPECT_EQ(p.split_peels, 1u);
  EXPECT_EQ(Bound(t), 2u);
  const ScheduleRun run = RunSchedule(t, p.schedule);
  EXPECT_TRUE(run.feasible);
  EXPECT_EQ(run.processed_nodes, 4u);
  EXPECT_EQ(run.useful_fetches, 3u);
  EXPECT_FALSE(IsFeasible(t, {A, B}));
  EXPECT_FALSE(IsFeasible(t, {B, A}));
  EXPECT_TRUE(IsFeasible(t, {B, A, B}));
}

// A B C A: the last A (gen 2) is ready, then C, B, A: all completions, length = bound = 4.
TEST(PeelTest, ChainRevisitingACell) {
  const CellTree t = FromPaths({{A, B, C, A}});
  const PeelResult p = Peel(t);
  EXPECT_EQ(p.schedule, (Schedule{A, B, C, A}));
  EXPECT_EQ(p.kinds, (std::vector<PeelKind>(4, kC)));
  EXPECT_EQ(p.split_peels, 0u);
  EXPECT_EQ(Bound(t), 4u);
  EXPECT_TRUE(IsFeasible(t, p.schedule));
  EXPECT_FALSE(IsFeasible(t, {A, B, C}));
  EXPECT_FALSE(IsFeasible(t, {A, C, B, A}));
}

// Ten root children: every cell is ready from the start; lowest first, so the peels are
// 0 1 ... 9 and the schedule is 9 8 ... 0, length = bound = 10.
TEST(PeelTest, StarPeelsLowestReadyCellFirst) {
  std::vector<Schedule> paths;
  for (CellId c : CellRange(10)) paths.push_back({c});
  const CellTree t = FromPaths(paths);
  const PeelResult p = Peel(t);
  EXPECT_EQ(p.schedule, (Schedule{9, 8, 7, 6, 5, 4, 3, 2, 1, 0}));
  EXPECT_EQ(p.split_peels, 0u);
  EXPECT_EQ(Bound(t), 10u);
  EXPECT_TRUE(IsFeasible(t, p.schedule));
}

// Paths A B C, B C A, C A B: nodes A1 B1 C1 / B2 C2 A2 / C3 A3 B3, all generation 1,
// bound 3. Leaves C1, A2, B3; no cell ready (each has two non-leaves at gen 1).
//  1. split: one leaf each, lowest A: remove A2; C2 becomes a leaf.
//  2. split: C has 2 leaves (C1, C2), B 1, A 0: remove C1, C2; B1 and B2 become leaves.
//  3. B1 B2 B3 all leaves: completion B; A1 and A3 become leaves.
//  4. A1 A3: completion A; C3 becomes a leaf.  5. completion C.
// Reverse peels A C B A C: schedule C A B C A, 5 = bound + 2 splits, which is also the
// shortest common supersequence of the three paths.
TEST(PeelTest, CyclicPathsNeedSplitPeels) {
  const CellTree t = FromPaths({{A, B, C}, {B, C, A}, {C, A, B}});
  const PeelResult p = Peel(t);
  EXPECT_EQ(p.schedule, (Schedule{C, A, B, C, A}));
  EXPECT_EQ(p.kinds, (std::vector<PeelKind>{kC, kC, kC, kS, kS}));
  EXPECT_EQ(p.split_peels, 2u);
  EXPECT_EQ(Bound(t), 3u);
  EXPECT_TRUE(IsFeasible(t, p.schedule));
  EXPECT_EQ(p.ToString(), "schedule 2 0 1 2 0 (5 entries, 2 split peels)");
}

// A completion removes every leaf of the cell, also below its top generation. Paths A B A
// and B A: A1 -> B1 -> A2 (gen 2), B2 -> A3 (gen 1). A's top generation holds only the leaf
// A2, so A is ready and its completion removes A2 and A3. Then B1, B2: completion B; then
// A1. Schedule A B A = bound (2 + 1), no split.
TEST(PeelTest, CompletionRemovesEveryLeafOfTheCell) {
  const CellTree t = FromPaths({{A, B, A}, {B, A}});
  const PeelResult p = Peel(t);
  EXPECT_EQ(p.schedule, (Schedule{A, B, A}));
  EXPECT_EQ(p.split_peels, 0u);
  EXPECT_EQ(Bound(t), 3u);
  EXPECT_TRUE(IsFeasible(t, p.schedule));
}

// Ready cells go lowest first: A B A and A C give A (gen 2 leaf), then B and C are both
// ready: B, then C, then A1. Schedule A C B A.
TEST(PeelTest, LowestReadyCellFirst) {
  const CellTree t = FromPaths({{A, B, A}, {A, C}});
  const PeelResult p = Peel(t);
  EXPECT_EQ(p.schedule, (Schedule{A, C, B, A}));
  EXPECT_EQ(p.split_peels, 0u);
  EXPECT_TRUE(IsFeasible(t, p.schedule));
}

TEST(PeelTest, EmptyTreeGivesAnEmptyFeasibleSchedule) {
  const CellTree t = FromPaths({});
  EXPECT_TRUE(Peel(t).schedule.empty());
  EXPECT_TRUE(IsFeasible(t, {}));
}

TEST(ScheduleTest, UnknownCellsProcessNothing) {
  const CellTree t = FromPaths({{A, B}});
  const ScheduleRun run = RunSchedule(t, {CellId(7), A, A, B});
  EXPECT_TRUE(run.feasible);
  EXPECT_EQ(run.useful_fetches, 2u);
  EXPECT_EQ(run.ToString(), "feasible, 2 nodes processed, 2 useful fetches");
}

// ------------------------------------------------------------------------ properties

template <typename Fn>
void ForRandomTrees(int count, Fn fn) {
  std::mt19937 rng(20020901);
  for (int i = 0; i < count; ++i) {
    const std::uint32_t cells = 2 + rng() % 5;
    const int rays = 1 + static_cast<int>(rng() % 12);
    const CellTree t = RandomTree(rng, cells, rays);
    SCOPED_TRACE(t.ToString());
    fn(t);
    if (::testing::Test::HasFatalFailure()) return;
  }
}

std::size_t Count(const Schedule& s, CellId c) { return std::count(s.begin(), s.end(), c); }

TEST(PeelPropertyTest, ScheduleIsFeasibleAndWithinBoundPlusSplits) {
  ForRandomTrees(3000, [](const CellTree& t) {
    const PeelResult p = Peel(t);
    ASSERT_EQ(p.kinds.size(), p.schedule.size());
    EXPECT_EQ(static_cast<std::size_t>(std::count(p.kinds.begin(), p.kinds.end(), kS)),
              p.split_peels);
    const ScheduleRun run = RunSchedule(t, p.schedule);
    EXPECT_TRUE(run.feasible) << p.ToString();
    EXPECT_EQ(run.processed_nodes, t.node_count());
    EXPECT_TRUE(RunNaive(t, p.schedule).feasible);
    EXPECT_LE(Bound(t), p.schedule.size());
    EXPECT_LE(p.schedule.size(), Bound(t) + p.split_peels);
    const auto max_gen = MaxGenerations(t);
    for (CellId c : CellRange(t.cell_count())) EXPECT_GE(Count(p.schedule, c), max_gen[c.value()]);
  });
}

TEST(PeelPropertyTest, MatchesNaivePeelExactly) {
  ForRandomTrees(3000, [](const CellTree& t) {
    const PeelResult p = Peel(t), naive = NaivePeel(t);
    EXPECT_EQ(p.schedule, naive.schedule);
    EXPECT_EQ(p.kinds, naive.kinds);
    EXPECT_EQ(p.split_peels, naive.split_peels);
  });
}

// Removing any one entry: the checker agrees with the naive run, and removing an entry of a
// cell scheduled exactly maxGen times always breaks feasibility (the bound argument).
TEST(PeelPropertyTest, RemovingAnEntry) {
  ForRandomTrees(2000, [](const CellTree& t) {
    const Schedule s = Peel(t).schedule;
    const auto max_gen = MaxGenerations(t);
    for (std::size_t i = 0; i < s.size(); ++i) {
      Schedule shorter = s;
      shorter.erase(shorter.begin() + static_cast<std::ptrdiff_t>(i));
      const ScheduleRun run = RunSchedule(t, shorter);
      const NaiveRun naive = RunNaive(t, shorter);
      EXPECT_EQ(run.feasible, naive.feasible) << "without entry " << i;
      EXPECT_EQ(run.useful_fetches, naive.useful);
      if (Count(s, s[i]) == max_gen[s[i].value()]) {
        EXPECT_FALSE(run.feasible) << "without entry " << i;
      }
    }
  });
}

TEST(PeelPropertyTest, SwappingAdjacentEntriesMatchesNaiveRun) {
  ForRandomTrees(2000, [](const CellTree& t) {
    const Schedule s = Peel(t).schedule;
    for (std::size_t i = 0; i + 1 < s.size(); ++i) {
      if (s[i] == s[i + 1]) continue;
      Schedule swapped = s;
      std::swap(swapped[i], swapped[i + 1]);
      const ScheduleRun run = RunSchedule(t, swapped);
      const NaiveRun naive = RunNaive(t, swapped);
      EXPECT_EQ(run.feasible, naive.feasible) << "swap at " << i;
      EXPECT_EQ(run.useful_fetches, naive.useful) << "swap at " << i;
    }
  });
}

// A large tree (27 cells, 200k rays) peels feasibly, within the bound plus its split peels.
// (Peel's running time against tree size is measured by tools/bench/cell_tree_scaling.cpp,
// see BENCHMARKS.md, not asserted here.)
TEST(PeelPropertyTest, LargeRandomTreeIsFeasibleWithinSplitPeelsOfTheBound) {
  std::mt19937 rng(7);
  const CellTree t = RandomTree(rng, 27, 200000);
  const PeelResult p = Peel(t);
  EXPECT_TRUE(IsFeasible(t, p.schedule));
  EXPECT_LE(Bound(t), p.schedule.size());
  EXPECT_LE(p.schedule.size(), Bound(t) + p.split_peels);
}

}  // namespace
}  // namespace raycell
