#include "graph/cell_tree.h"

#include <gtest/gtest.h>

#include <random>
#include <type_traits>

#include "base/check.h"
#include "graph/peel.h"
#include "graph/schedule.h"
#include "tests/graph/test_trees.h"

namespace raycell {
namespace {

// Typed ids (CONTRIBUTING.md, docs/design.md §1 "Cell and node ids"): a node and a cell, both
// 32-bit numbers, never convert into each other, in either direction, by construction or
// assignment, nor into or from numbers; a number becomes a node or a cell only explicitly,
// NodeId(i), CellId(i). Checked at compile time: this file does not build if they do.
static_assert(!std::is_convertible_v<NodeId, CellId> && !std::is_convertible_v<CellId, NodeId>);
static_assert(!std::is_assignable_v<CellId&, NodeId> && !std::is_assignable_v<NodeId&, CellId>);
static_assert(!std::is_convertible_v<std::uint32_t, NodeId> &&
              !std::is_convertible_v<std::size_t, NodeId>);
static_assert(std::is_constructible_v<NodeId, std::uint32_t> && NodeId(7).index() == 7);
static_assert(!std::is_convertible_v<std::uint32_t, CellId> &&
              !std::is_convertible_v<std::size_t, CellId> && !std::is_convertible_v<int, CellId>);
static_assert(!std::is_convertible_v<CellId, std::uint32_t> &&
              !std::is_convertible_v<CellId, std::size_t> && !std::is_convertible_v<CellId, bool>);
static_assert(!std::is_assignable_v<CellId&, std::uint32_t> && !std::is_assignable_v<CellId&, int>);
static_assert(std::is_constructible_v<CellId, std::uint32_t> && CellId(7).value() == 7);
// And no cost: four bytes, copied as the number they hold.
static_assert(sizeof(NodeId) == sizeof(std::uint32_t) && std::is_trivially_copyable_v<NodeId>);
static_assert(sizeof(CellId) == sizeof(std::uint32_t) && std::is_trivially_copyable_v<CellId>);

constexpr CellId A{0}, B{1}, C{2};

struct TestRay {
  RayId parent;
  std::uint32_t spawn;
  std::vector<CellId> cells;
  std::vector<std::uint32_t> samples;  // empty: one sample per visit
};

RayBatch MakeBatch(const std::vector<TestRay>& rays, RayId first_id = 0) {
  RayBatch b(false);
  b.set_first_id(first_id);
  for (const TestRay& r : rays) {
    const RayKind kind = r.parent == kNoParent ? RayKind::kPrimary : RayKind::kReflection;
    b.BeginRay(kind, r.parent, r.spawn, 0, 0);
    for (std::size_t v = 0; v < r.cells.size(); ++v) {
      b.AddVisit(r.cells[v], r.samples.empty() ? 1 : r.samples[v], 0.f, 0.f);
    }
  }
  return b;
}

CellTree Build(const std::vector<TestRay>& rays) {
  CellTreeBuilder builder;
  builder.AddBatch(MakeBatch(rays));
  return builder.Finish();
}

// Follows `path` of cells from the root; kNoNode when some step is missing.
NodeId Find(const CellTree& t, const std::vector<CellId>& path) {
  NodeId n = kRootNode;
  for (CellId c : path) {
    n = t.FindChild(n, c);
    if (n == kNoNode) return kNoNode;
  }
  return n;
}

TEST(CellTreeTest, EmptyTreeHasNoNodesNoCellsAndBoundZero) {
  const CellTree t = Build({});
  EXPECT_EQ(t.node_count(), 0u);
  EXPECT_EQ(t.cell_count(), 0u);
  EXPECT_EQ(Bound(t), 0u);
}

// Paths A B and B A: root -> A -> B and root -> B -> A, all generation 1; bound 1 + 1 = 2.
TEST(CellTreeTest, TwoCrossedPaths) {
  const CellTree t = Build({{kNoParent, 0, {A, B}, {}}, {kNoParent, 0, {B, A}, {}}});
  EXPECT_EQ(t.node_count(), 4u);
  EXPECT_EQ(t.cell_count(), 2u);
  for (NodeId n : t.nodes()) EXPECT_EQ(t.generation(n), 1u);
  EXPECT_EQ(MaxGenerations(t), (std::vector<std::uint32_t>{1, 1}));
  EXPECT_EQ(Bound(t), 2u);
  EXPECT_EQ(t.children(kRootNode), (std::vector<NodeId>{Find(t, {A}), Find(t, {B})}));
}

// Chain A B C A: generations 1 1 1 2, maxGen A = 2, B = C = 1, bound 4.
TEST(CellTreeTest, ChainRevisitingACell) {
  const CellTree t = Build({{kNoParent, 0, {A, B, C, A}, {}}});
  ASSERT_EQ(t.node_count(), 4u);
  EXPECT_EQ(t.generation(Find(t, {A})), 1u);
  EXPECT_EQ(t.generation(Find(t, {A, B, C})), 1u);
  EXPECT_EQ(t.generation(Find(t, {A, B, C, A})), 2u);
  EXPECT_EQ(MaxGenerations(t), (std::vector<std::uint32_t>{2, 1, 1}));
  EXPECT_EQ(Bound(t), 4u);
}

// Star: one primary ray per cell 0..9; ten children of the root, bound 10.
TEST(CellTreeTest, DistinctOneCellRaysFormAStarBoundedByTheCellCount) {
  std::vector<TestRay> rays;
  for (CellId c : CellRange(10)) rays.push_back({kNoParent, 0, {c}, {}});
  const CellTree t = Build(rays);
  EXPECT_EQ(t.node_count(), 10u);
  EXPECT_EQ(t.children(kRootNode).size(), 10u);
  EXPECT_EQ(Bound(t), 10u);
}

// Shared prefixes merge: A B C and A B A give root -> A -> B -> {C, A}; A enters twice.
TEST(CellTreeTest, SharedPrefixesMergeAndCountEntries) {
  const CellTree t =
      Build({{kNoParent, 0, {A, B, C}, {1, 2, 3}}, {kNoParent, 0, {A, B, A}, {10, 20, 30}}});
  EXPECT_EQ(t.node_count(), 4u);
  EXPECT_EQ(t.enter(Find(t, {A})), 2u);
  EXPECT_EQ(t.samples(Find(t, {A})), 11u);
  EXPECT_EQ(t.enter(Find(t, {A, B})), 2u);
  EXPECT_EQ(t.samples(Find(t, {A, B})), 22u);
  EXPECT_EQ(t.samples(Find(t, {A, B, C})), 3u);
  EXPECT_EQ(t.samples(Find(t, {A, B, A})), 30u);
  EXPECT_EQ(t.generation(Find(t, {A, B, A})), 2u);
}

// Ray 0 (primary): A B C, samples 1 2 3.
// Ray 1 (reflection, parent 0, spawn 1): B A, samples 10 20. It starts at ray 0's node
//   A.B without entering it (enter stays at 1, samples 2 + 10), then enters A.B.A.
// Ray 2 (shadow, parent 1, spawn 1): A, samples 7: works in A.B.A without entering it.
// Ray 3 (primary, a second ray tree): A B, samples 5 6: enters A and A.B again.
// Nodes: A (enter 2, samples 6), A.B (enter 2, samples 18), A.B.C (1, 3), A.B.A (1, 27).
TEST(CellTreeTest, SpawnedRaysStartAtTheirParentsSpawnVisitNode) {
  const CellTree t = Build({{kNoParent, 0, {A, B, C}, {1, 2, 3}},
                            {0, 1, {B, A}, {10, 20}},
                            {1, 1, {A}, {7}},
                            {kNoParent, 0, {A, B}, {5, 6}}});
  ASSERT_EQ(t.node_count(), 4u);
  EXPECT_EQ(t.enter(Find(t, {A})), 2u);
  EXPECT_EQ(t.samples(Find(t, {A})), 6u);
  EXPECT_EQ(t.enter(Find(t, {A, B})), 2u);
  EXPECT_EQ(t.samples(Find(t, {A, B})), 18u);
  EXPECT_EQ(t.enter(Find(t, {A, B, C})), 1u);
  EXPECT_EQ(t.samples(Find(t, {A, B, C})), 3u);
  EXPECT_EQ(t.enter(Find(t, {A, B, A})), 1u);
  EXPECT_EQ(t.samples(Find(t, {A, B, A})), 27u);
  EXPECT_EQ(t.generation(Find(t, {A, B, A})), 2u);
  EXPECT_EQ(Bound(t), 4u);
}

// One ray tree split over two batches, the parents in the first: the same tree.
TEST(CellTreeTest, ParentsInEarlierBatches) {
  CellTreeBuilder builder;
  builder.AddBatch(MakeBatch({{kNoParent, 0, {A, B, C}, {1, 2, 3}}, {0, 1, {B, A}, {10, 20}}}));
  builder.AddBatch(MakeBatch({{1, 1, {A}, {7}}, {kNoParent, 0, {A, B}, {5, 6}}}, 2));
  const CellTree t = builder.Finish();
  EXPECT_EQ(t.node_count(), 4u);
  EXPECT_EQ(t.samples(Find(t, {A, B, A})), 27u);
  EXPECT_EQ(t.enter(Find(t, {A, B})), 2u);
}

std::string BuildError(const std::vector<TestRay>& rays) {
  try {
    Build(rays);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

// Rays come one ray tree at a time; that is what bounds the builder's memory by the tree's
// nodes. A parent in an earlier tree is an error that says so.
TEST(CellTreeTest, ParentInAnEarlierRayTreeIsAnError) {
  EXPECT_EQ(BuildError({{kNoParent, 0, {A, B}, {}}, {kNoParent, 0, {A}, {}}, {0, 1, {B}, {}}}),
            "ray 2: unknown parent 0 (it is not in the current ray tree: rays must come one "
            "tree at a time, a primary ray followed by its descendants)");
}

TEST(CellTreeTest, MalformedRaysNameTheRay) {
  EXPECT_EQ(BuildError({{kNoParent, 0, {A}, {}}, {5, 0, {A}, {}}}), "ray 1: unknown parent 5");
  EXPECT_EQ(BuildError({{kNoParent, 0, {A}, {}}, {0, 1, {A}, {}}}),
            "ray 1: spawn 1 out of range: parent 0 has 1 visits");
  EXPECT_EQ(BuildError({{kNoParent, 0, {A, B}, {}}, {0, 1, {A}, {}}}),
            "ray 1: first cell 0 is not the cell 1 of parent 0's spawn visit 1");
  EXPECT_EQ(BuildError({{kNoParent, 0, {A, B, B}, {}}}), "ray 0: cell 1 repeated at visit 2");
}

TEST(CellTreeTest, RayIdsMustIncrease) {
  CellTreeBuilder builder;
  builder.AddBatch(MakeBatch({{kNoParent, 0, {A}, {}}}, 5));
  EXPECT_THROW(builder.AddBatch(MakeBatch({{kNoParent, 0, {A}, {}}}, 5)), InputError);
}

TEST(CellTreeTest, ToStringListsNodesDepthFirst) {
  const CellTree t = Build({{kNoParent, 0, {A, B}, {3, 4}}});
  EXPECT_EQ(t.ToString(),
            "CellTree(2 nodes)\n"
            "  cell 0 gen 1 enter 1 samples 3\n"
            "    cell 1 gen 1 enter 1 samples 4\n");
}

// Random ray trees (primary rays and rays spawned at a visit of an earlier ray of the same
// tree), as testing::TestRay with parents indexing this list.
std::vector<testing::TestRay> RandomRays(std::mt19937& rng, std::uint32_t cells, int rays) {
  std::vector<testing::TestRay> out;
  std::size_t tree_start = 0;
  for (int i = 0; i < rays; ++i) {
    testing::TestRay r;
    const bool primary = out.empty() || rng() % 3 == 0;
    if (primary) {
      tree_start = out.size();
      r.cells.push_back(CellId(rng() % cells));
    } else {
      r.parent = tree_start + rng() % (out.size() - tree_start);
      r.spawn = std::uint32_t(rng() % out[r.parent].cells.size());
      r.cells.push_back(out[r.parent].cells[r.spawn]);
    }
    for (int v = int(rng() % 5); v > 0; --v) {
      CellId next;
      do next = CellId(rng() % cells);
      while (next == r.cells.back());
      r.cells.push_back(next);
    }
    out.push_back(r);
  }
  return out;
}

// shape_only: b's counts are not compared (a's must read 0).
void ExpectSameTree(const CellTree& a, const CellTree& b, bool shape_only = false) {
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(a.rays(), b.rays());
  EXPECT_EQ(a.cell_count(), b.cell_count());
  for (std::uint32_t i = 0; i < a.size(); ++i) {  // the root too
    const NodeId n(i);
    EXPECT_EQ(a.cell(n), b.cell(n)) << n;
    EXPECT_EQ(a.parent(n), b.parent(n)) << n;
    EXPECT_EQ(a.enter(n), shape_only ? 0 : b.enter(n)) << n;
    EXPECT_EQ(a.samples(n), shape_only ? 0 : b.samples(n)) << n;
    EXPECT_EQ(a.visits(n), shape_only ? 0 : b.visits(n)) << n;
    EXPECT_EQ(a.generation(n), b.generation(n)) << n;
    EXPECT_EQ(a.first_child(n), b.first_child(n)) << n;
    EXPECT_EQ(a.next_sibling(n), b.next_sibling(n)) << n;
  }
}

// The union of two frames' trees is the tree of both frames' rays in one frame, and any
// schedule feasible for the union is feasible for each.
TEST(UnionTreeTest, EqualsTheTreeOfAllRaysAndItsSchedulesServeEach) {
  std::mt19937 rng(11);
  for (int round = 0; round < 200; ++round) {
    const std::uint32_t cells = 2 + rng() % 6;
    const auto a = RandomRays(rng, cells, 1 + int(rng() % 12));
    const auto b = RandomRays(rng, cells, 1 + int(rng() % 12));
    auto both = a;
    for (testing::TestRay r : b) {
      if (r.parent != kNoParent) r.parent += a.size();
      both.push_back(r);
    }
    const CellTree ta = testing::TreeOf(testing::RaysOf(a, 2));
    const CellTree tb = testing::TreeOf(testing::RaysOf(b, 2));
    const CellTree u = UnionTree({&ta, &tb});
    const CellTree all = testing::TreeOf(testing::RaysOf(both, 2));
    ExpectSameTree(u, all);
    EXPECT_TRUE(u.counted());
    // The shape alone: the same nodes, numbers and generations, counts 0.
    const CellTree shape = UnionShape({&ta, &tb});
    EXPECT_FALSE(shape.counted());
    ExpectSameTree(shape, all, /*shape_only=*/true);
    const std::vector<CellId> plan = Peel(u).schedule;
    EXPECT_TRUE(IsFeasible(ta, plan));
    EXPECT_TRUE(IsFeasible(tb, plan));
  }
  const CellTree empty = UnionTree({});
  EXPECT_EQ(empty.node_count(), 0u);
  EXPECT_EQ(UnionShape({}).node_count(), 0u);
}

// A parked tree (kept for a later frame while nothing reads it, issue 43) holds its nodes as
// varints only; unparked, it is the tree it was, link for link, for the builder's
// trees and the unions of two.
TEST(CellTreeTest, UnparkedTreesAreTheTreesParked) {
  std::mt19937 rng(5);
  for (int round = 0; round < 100; ++round) {
    const std::uint32_t cells = 2 + rng() % 6;
    const CellTree ta =
        testing::TreeOf(testing::RaysOf(RandomRays(rng, cells, 1 + int(rng() % 12)), 2));
    const CellTree tb =
        testing::TreeOf(testing::RaysOf(RandomRays(rng, cells, 1 + int(rng() % 12)), 2));
    for (const CellTree& original : {ta, UnionTree({&ta, &tb}), UnionShape({&tb, &ta})}) {
      CellTree t = original;
      t.Park();
      EXPECT_TRUE(t.parked());
      EXPECT_EQ(t.size(), original.size());
      t.Unpark();
      EXPECT_FALSE(t.parked());
      ExpectSameTree(t, original, /*shape_only=*/!original.counted());
    }
  }
}

}  // namespace
}  // namespace raycell
