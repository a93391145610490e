#include "bounds/lower_bound.h"

#include <gtest/gtest.h>

#include <random>

#include "graph/peel.h"
#include "tests/graph/test_trees.h"
#include "tests/test_util.h"

namespace raycell {
namespace {

using testing::BruteForceOptimum;
using testing::FromPaths;
using testing::RandomTree;
using testing::Rotations;

constexpr CellId A{0}, B{1}, C{2}, D{3};

void ExpectValid(const CellTree& t, const LowerBoundResult& r) {
  EXPECT_EQ(r.max_gen, Bound(t));
  EXPECT_GE(r.value, r.max_gen) << r.ToString();
  EXPECT_LE(r.value, Peel(t).schedule.size()) << r.ToString();
  std::uint64_t previous = 0;
  for (const LowerBoundStage& s : r.stages) {
    EXPECT_GE(s.value, previous) << s.name;
    previous = s.value;
  }
  EXPECT_EQ(r.stages.back().value, r.value);
}

TEST(LowerBoundTest, RotationsReachTheOptimum) {
  for (std::uint32_t n = 2; n <= 6; ++n) {
    const CellTree t = Rotations(n);
    const LowerBoundResult r = LowerBound(t);
    ExpectValid(t, r);
    EXPECT_EQ(r.max_gen, n);
    EXPECT_EQ(r.value, 2u * n - 1) << r.ToString();
    if (n <= 4) {
      EXPECT_EQ(BruteForceOptimum(t), 2u * n - 1);
    }
  }
}

TEST(LowerBoundTest, CrossedPathsAndChains) {
  // A B and B A: 3.
  EXPECT_EQ(LowerBound(FromPaths({{A, B}, {B, A}})).value, 3u);
  // A chain is its own bound.
  EXPECT_EQ(LowerBound(FromPaths({{A, B, C, A, D}})).value, 5u);
  // A B C D and D C B A: 7 (n + n - 1), where maxGen says 4.
  const CellTree t = FromPaths({{A, B, C, D}, {D, C, B, A}});
  const LowerBoundResult r = LowerBound(t);
  EXPECT_EQ(r.value, BruteForceOptimum(t)) << r.ToString();
  EXPECT_GT(r.value, r.max_gen);
}

TEST(LowerBoundTest, NeedsACut) {
  // Pairs and triples alone allow fewer fetches than the optimum: the rotations of 0..4 with a
  // different path per cell pair interplay. Whatever the stages, the result stays between
  // maxGen and the optimum, and the cuts stage is at least the program's value before it.
  const CellTree t = FromPaths(
      {{A, B, C, D}, {B, C, D, A}, {C, D, A, B}, {D, A, B, C}, {A, C, B, D}, {D, B, C, A}});
  const LowerBoundResult r = LowerBound(t);
  ExpectValid(t, r);
  EXPECT_LE(r.value, BruteForceOptimum(t));
}

TEST(LowerBoundTest, RandomTreesStayBetweenMaxGenAndTheOptimum) {
  std::mt19937 rng(21);
  int above = 0, equal = 0;
  const int trials = 1500;
  for (int trial = 0; trial < trials; ++trial) {
    const std::uint32_t cells = 2 + rng() % 5;
    const CellTree t = RandomTree(rng, cells, 1 + rng() % 8, 1 + rng() % 6);
    if (t.node_count() > 22) continue;  // keep the brute force fast
    LowerBoundOptions options;
    if (trial % 3 == 0) options.grid = {cells, 1, 1};
    // Without blocks (one of which is the whole tree here), the cuts have work to do.
    if (trial % 2 == 1) options.blocks = false;
    const LowerBoundResult r = LowerBound(t, options);
    ExpectValid(t, r);
    const std::size_t optimum = BruteForceOptimum(t);
    ASSERT_LE(r.value, optimum) << t.ToString() << r.ToString();
    if (r.value > r.max_gen) ++above;
    if (r.value == optimum) ++equal;
    if (r.optimal) {
      EXPECT_EQ(r.value, optimum) << t.ToString() << r.ToString();
    }
  }
  EXPECT_GT(above, 100);  // the bound does more than maxGen on many of them
  EXPECT_GT(equal, trials / 2);
}

// Trees where the program over pairs and triples stays below the optimum and the cuts (of
// pairs, triples and unions of tight groups; no blocks) have to raise it.
TEST(LowerBoundTest, CutsRaiseTheBoundAndStayValid) {
  std::mt19937 rng(5);
  int cut = 0;
  for (int trial = 0; trial < 700; ++trial) {
    const std::uint32_t cells = 4 + rng() % 3;
    const CellTree t = RandomTree(rng, cells, 4 + rng() % 10, 2 + rng() % 6);
    if (t.node_count() > 26) continue;
    LowerBoundOptions options;
    options.blocks = false;
    const LowerBoundResult r = LowerBound(t, options);
    ExpectValid(t, r);
    ASSERT_LE(r.value, BruteForceOptimum(t)) << t.ToString() << r.ToString();
    if (r.stages.back().value > r.stages[r.stages.size() - 2].value) ++cut;
  }
  EXPECT_GT(cut, 15);
}

TEST(LowerBoundTest, EmptyAndTinyTrees) {
  const CellTree empty = testing::TreeOf(RayBatch(false));
  const LowerBoundResult e = LowerBound(empty);
  EXPECT_EQ(e.value, 0u);
  EXPECT_EQ(LowerBound(FromPaths({{A}})).value, 1u);
  EXPECT_EQ(LowerBound(FromPaths({{C}})).value, 1u);  // cells 0 and 1 have no nodes
  EXPECT_EQ(LowerBound(FromPaths({{A}, {B}, {C}})).value, 3u);
}

TEST(LowerBoundTest, ManyCellsFewNodes) {
  std::mt19937 rng(22);
  for (std::uint32_t cells : {512u, 4096u}) {
    const CellTree t = RandomTree(rng, cells, 60, 8);
    LowerBoundOptions options;
    if (cells == 512) options.grid = {8, 8, 8};
    const LowerBoundResult r = LowerBound(t, options);
    ExpectValid(t, r);
  }
}

TEST(LowerBoundTest, GridMustCoverTheCells) {
  const CellTree t = FromPaths({{A, B, CellId(9)}});
  LowerBoundOptions options;
  options.grid = {2, 2, 2};
  const std::string error = testing::ErrorOf([&] { LowerBound(t, options); });
  EXPECT_NE(error.find("grid 2x2x2"), std::string::npos) << error;
}

TEST(LowerBoundTest, SameTreeGivesTheSameBoundTwice) {
  std::mt19937 rng(23);
  const CellTree t = RandomTree(rng, 6, 40, 7);
  const LowerBoundResult a = LowerBound(t), b = LowerBound(t);
  EXPECT_EQ(a.ToString(), b.ToString());
  EXPECT_EQ(a.groups.size(), b.groups.size());
}

}  // namespace
}  // namespace raycell
