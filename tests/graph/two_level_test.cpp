// Two levels of cells (issue 23; docs/design.md §5 "Two-level scheduling"): the tree contracted
// to coarser cells, a sub-forest as a tree of its own, and TwoLevelPeel, checked against
// independent walks of root-to-node paths and an independent run of schedules.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <set>

#include "graph/cell_tree.h"
#include "graph/peel.h"
#include "graph/schedule.h"
#include "tests/cell_list.h"
#include "tests/graph/test_trees.h"

namespace raycell {
namespace {

using testing::CellList;
using testing::FromPaths;
using testing::RandomTree;

// Node n's cells from the root down, by parent links.
CellList PathOf(const CellTree& t, NodeId n) {
  CellList p;
  for (; n != kRootNode; n = t.parent(n)) p.push_back(t.cell(n));
  std::reverse(p.begin(), p.end());
  return p;
}
// A path mapped to coarse cells, consecutive repeats merged (as regrouping merges visits).
CellList Coarse(const CellList& path, const std::vector<CellId>& map) {
  CellList out;
  for (const CellId c : path) {
    if (out.empty() || out.back() != map[c.value()]) out.push_back(map[c.value()]);
  }
  return out;
}
// An independent run (docs/design.md §1): per entry, every node of its cell whose parent was
// done before the entry. The entries that process something.
CellList Useful(const CellTree& t, const CellList& schedule) {
  std::vector<bool> done(t.size(), false);
  done[kRootNode.index()] = true;
  CellList useful;
  for (const CellId c : schedule) {
    std::vector<NodeId> now;
    for (NodeId n : t.nodes()) {
      if (!done[n.index()] && t.cell(n) == c && done[t.parent(n).index()]) now.push_back(n);
    }
    for (const NodeId n : now) done[n.index()] = true;
    if (!now.empty()) useful.push_back(c);
  }
  return useful;
}
std::vector<CellId> RandomMap(std::mt19937& rng, std::uint32_t cells) {
  const std::uint32_t coarse = 1 + rng() % cells;
  std::vector<CellId> map(cells);
  for (auto& c : map) c = CellId(rng() % coarse);
  return map;
}

template <typename Fn>
void ForRandomTrees(int count, Fn fn) {
  std::mt19937 rng(2323);
  for (int i = 0; i < count; ++i) {
    const std::uint32_t cells = 2 + rng() % 7;
    const CellTree t = RandomTree(rng, cells, 1 + int(rng() % 14));
    const std::vector<CellId> map = RandomMap(rng, cells);
    SCOPED_TRACE(t.ToString());
    fn(t, map);
    if (::testing::Test::HasFatalFailure()) return;
  }
}

TEST(ContractTree, HandWorkedTreeContractsToTheCoarsePathsKeepingRaysAndSamples) {
  // Cells 0 and 1 in coarse cell 0, 2 and 3 in coarse cell 1. Paths 0 1 2, 0 2 3 and 2 0:
  // coarse paths 0 1, 0 1 and 1 0.
  const CellTree t = FromPaths({{0, 1, 2}, {0, 2, 3}, {2, 0}});
  std::vector<NodeId> image;
  const CellTree c = ContractTree(t, {CellId(0), CellId(0), CellId(1), CellId(1)}, &image);
  EXPECT_EQ(c.node_count(), 4u);  // 0, 0 1, 1, 1 0
  for (NodeId n : t.nodes()) {
    EXPECT_EQ(PathOf(c, image[n.index()]),
              Coarse(PathOf(t, n), {CellId(0), CellId(0), CellId(1), CellId(1)}));
  }
  // Node "0" stands for fine nodes 0 and 0 1: two rays enter it, four samples are worked in it.
  const NodeId zero = c.FindChild(kRootNode, CellId(0));
  EXPECT_EQ(c.enter(zero), 2u);
  EXPECT_EQ(c.samples(zero), 3u);                          // 0 (twice) and 0 1
  EXPECT_EQ(c.samples(c.FindChild(zero, CellId(1))), 3u);  // 2, 2 and 3
  EXPECT_EQ(c.rays(), t.rays());
}

TEST(ContractTree, ItsNodesAreTheCoarsePathsOfTheTreesNodes) {
  ForRandomTrees(2000, [](const CellTree& t, const std::vector<CellId>& map) {
    std::vector<NodeId> image;
    const CellTree c = ContractTree(t, map, &image);
    std::set<CellList> expected, got;
    std::uint64_t samples = 0;
    for (NodeId n : t.nodes()) {
      expected.insert(Coarse(PathOf(t, n), map));
      ASSERT_EQ(PathOf(c, image[n.index()]), Coarse(PathOf(t, n), map));
      samples += t.samples(n);
    }
    std::uint64_t coarse_samples = 0;
    for (NodeId n : c.nodes()) {
      got.insert(PathOf(c, n));
      coarse_samples += c.samples(n);
      ASSERT_NE(c.cell(n), c.cell(c.parent(n)));  // merged, as regrouped rays are
    }
    EXPECT_EQ(got, expected);
    EXPECT_EQ(got.size(), c.node_count());  // each path once
    EXPECT_EQ(coarse_samples, samples);
  });
}

TEST(SubTree, KeepsTheEdgesInsideTheSetAndHangsTheRestFromTheRoot) {
  std::mt19937 rng(7);
  for (int i = 0; i < 500; ++i) {
    const CellTree t = RandomTree(rng, 2 + rng() % 5, 1 + int(rng() % 10));
    std::vector<NodeId> nodes;
    for (NodeId n : t.nodes()) {
      if (rng() % 2) nodes.push_back(n);
    }
    const CellTree s = SubTree(t, nodes);
    ASSERT_EQ(s.node_count(), nodes.size());
    for (std::size_t k = 0; k < nodes.size(); ++k) {
      const NodeId m(std::uint32_t(k + 1)), n = nodes[k];
      EXPECT_EQ(s.cell(m), t.cell(n));
      EXPECT_EQ(s.samples(m), t.samples(n));
      const auto in = std::find(nodes.begin(), nodes.end(), t.parent(n));
      EXPECT_EQ(s.parent(m),
                in == nodes.end() ? kRootNode : NodeId(std::uint32_t(in - nodes.begin() + 1)));
    }
  }
}

// The plan is feasible, and its stretches in one coarse cell are the useful entries of the
// coarse tree's Peel schedule, in order: a board holding one coarse cell fetches as often as
// the coarse schedule says.
TEST(TwoLevelPeel, FeasibleAndFollowsTheCoarseSchedule) {
  ForRandomTrees(3000, [](const CellTree& t, const std::vector<CellId>& map) {
    const std::vector<CellId> plan = TwoLevelPeel(t, map);
    ASSERT_TRUE(IsFeasible(t, plan));
    EXPECT_EQ(Useful(t, plan).size(), plan.size());  // no entry wasted
    CellList stretches;
    for (const CellId c : plan) {
      if (stretches.empty() || stretches.back() != map[c.value()])
        stretches.push_back(map[c.value()]);
    }
    const CellTree coarse = ContractTree(t, map);
    EXPECT_EQ(stretches, Useful(coarse, Peel(coarse).schedule));
  });
}

// Any planners: a coarse plan that is not Peel's (every coarse cell in turn, as often as the
// coarse tree is deep) is followed stretch for stretch, and the plan stays feasible.
TEST(TwoLevelSchedule, FollowsAnyCoarsePlan) {
  ForRandomTrees(1000, [](const CellTree& t, const std::vector<CellId>& map) {
    const CellTree coarse = ContractTree(t, map);
    std::size_t depth = 0;
    for (NodeId n : coarse.nodes()) depth = std::max(depth, PathOf(coarse, n).size());
    std::vector<CellId> rounds;
    for (std::size_t r = 0; r < depth; ++r) {
      for (const CellId c : CellRange(coarse.cell_count())) rounds.push_back(c);
    }
    const TreePlanner peel = [](const CellTree& u) { return Peel(u).schedule; };
    const std::vector<CellId> plan = TwoLevelSchedule(
        t, map, [&](const CellTree&) { return rounds; }, peel);
    ASSERT_TRUE(IsFeasible(t, plan));
    CellList stretches;
    for (const CellId c : plan) {
      if (stretches.empty() || stretches.back() != map[c.value()])
        stretches.push_back(map[c.value()]);
    }
    EXPECT_EQ(stretches, Useful(coarse, rounds));
  });
}

// With every cell its own coarse cell, the plan is Peel's schedule without the entries that
// process nothing.
TEST(TwoLevelPeel, OneLevelIsPeel) {
  ForRandomTrees(3000, [](const CellTree& t, const std::vector<CellId>&) {
    std::vector<CellId> own(t.cell_count());
    for (const CellId c : CellRange(t.cell_count())) own[c.value()] = c;
    EXPECT_EQ(CellList(TwoLevelPeel(t, own)), Useful(t, Peel(t).schedule));
  });
}

// Cells 0 and 1 in coarse cell X, 2 in coarse cell Y. Paths 0 2, 1 2 0 and 2 1: coarse paths
// X Y, X Y X and Y X, whose shortest supersequence is X Y X. Peel of the fine tree takes
// 2 1 0 2 0: five fetches, but Y X Y X, four stretches (a board holding one coarse cell loads
// four times). The two-level plan takes 1 0 2 1 0: also five, in X Y X, three stretches.
TEST(TwoLevelPeel, HandWorkedTheBoardLoadsOnceLess) {
  const std::vector<CellId> map{CellId(0), CellId(0), CellId(1)};
  const CellTree t = FromPaths({{0, 2}, {1, 2, 0}, {2, 1}});
  EXPECT_EQ(CellList(Peel(t).schedule), (CellList{2, 1, 0, 2, 0}));
  EXPECT_EQ(CellList(TwoLevelPeel(t, map)), (CellList{1, 0, 2, 1, 0}));
}

}  // namespace
}  // namespace raycell
