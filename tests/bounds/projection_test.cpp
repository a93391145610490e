#include "bounds/projection.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

#include "tests/graph/test_trees.h"

namespace raycell {
namespace {

using testing::FromPaths;
using testing::RandomTree;
using Strings = std::vector<CellString>;

constexpr CellId A{0}, B{1}, C{2}, D{3};

// Subsequence by recursion over both strings (independent of the greedy scan under test).
bool SubsequenceReference(const CellString& a, std::size_t i, const CellString& b, std::size_t j) {
  if (i == a.size()) return true;
  if (j == b.size()) return false;
  if (a[i] == b[j] && SubsequenceReference(a, i + 1, b, j + 1)) return true;
  return SubsequenceReference(a, i, b, j + 1);
}

// Every leaf path of `t` walked from the leaf up, projected, then every string that is a
// subsequence of a different one dropped, by comparing all pairs.
std::set<CellString> ProjectionReference(const CellTree& t, const std::set<CellId>& cells) {
  std::set<CellString> all;
  for (NodeId n : t.nodes()) {
    if (!t.is_leaf(n)) continue;
    CellString s;
    for (NodeId a = n; a != kRootNode; a = t.parent(a)) {
      if (cells.count(t.cell(a))) s.insert(s.begin(), t.cell(a));
    }
    if (!s.empty()) all.insert(s);
  }
  std::set<CellString> kept;
  for (const CellString& s : all) {
    bool dominated = false;
    for (const CellString& o : all) {
      if (o != s && SubsequenceReference(s, 0, o, 0)) dominated = true;
    }
    if (!dominated) kept.insert(s);
  }
  return kept;
}

std::set<CellString> AsSet(const Strings& v) { return {v.begin(), v.end()}; }

TEST(ProjectionTest, IsSubsequenceKeepsOrderAndCountsRepeats) {
  EXPECT_TRUE(IsSubsequence({}, {A}));
  EXPECT_TRUE(IsSubsequence({A, C}, {A, B, C}));
  EXPECT_TRUE(IsSubsequence({A, A}, {A, B, A}));
  EXPECT_FALSE(IsSubsequence({A, A}, {A, B}));
  EXPECT_FALSE(IsSubsequence({C, A}, {A, B, C}));
  EXPECT_FALSE(IsSubsequence({A, B, C}, {A, B}));
}

TEST(ProjectionTest, HandMadeTree) {
  // Paths A B C, A B D A, C A: onto {A, C} they are A C, A A, C A; none is a subsequence of
  // another. Onto {A}: A, A A, A -> only A A is kept.
  const CellTree t = FromPaths({{A, B, C}, {A, B, D, A}, {C, A}});
  EXPECT_EQ(AsSet(ProjectPaths(t, {A, C})), (std::set<CellString>{{A, C}, {A, A}, {C, A}}));
  EXPECT_EQ(ProjectPaths(t, {A}), (Strings{{A, A}}));
  // Onto {B, D}: B C -> B, B D A -> B D; B is dropped.
  EXPECT_EQ(ProjectPaths(t, {B, D}), (Strings{{B, D}}));
  // Cells that match nothing, and none at all.
  EXPECT_TRUE(ProjectPaths(t, {CellId(7)}).empty());
  EXPECT_TRUE(ProjectPaths(t, {}).empty());
  // Longest first, then lexicographic.
  EXPECT_EQ(ProjectPaths(t, {A, C}), (Strings{{A, A}, {A, C}, {C, A}}));
}

TEST(ProjectionTest, RemoveDominatedKeepsOnlyMaximalStrings) {
  EXPECT_EQ(RemoveDominated({{A}, {}, {A, B}, {B, A}, {A, B}, {B}, {A, C, B}}),
            (Strings{{A, C, B}, {B, A}}));
  EXPECT_TRUE(RemoveDominated({{}, {}}).empty());
}

TEST(ProjectionTest, RandomTreesMatchTheReference) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 400; ++trial) {
    const std::uint32_t cells = 2 + rng() % 6;
    const CellTree t = RandomTree(rng, cells, 1 + rng() % 12, 1 + rng() % 7);
    std::set<CellId> subset;
    for (CellId c : CellRange(cells)) {
      if (rng() % 2) subset.insert(c);
    }
    const std::vector<CellId> list(subset.begin(), subset.end());
    const Strings got = ProjectPaths(t, list);
    ASSERT_EQ(AsSet(got), ProjectionReference(t, subset)) << t.ToString();
    ASSERT_EQ(got.size(), AsSet(got).size());
    EXPECT_EQ(ProjectStrings(TreePaths(t), list), got);
  }
}

// TreeProjector, built once per tree, projects onto many sets of cells (repeated ones and
// cells past the tree's included) exactly as ProjectPaths does, string for string and in order.
TEST(ProjectionTest, TreeProjectorMatchesProjectPaths) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 200; ++trial) {
    const std::uint32_t cells = 2 + rng() % 7;
    const CellTree t = RandomTree(rng, cells, 1 + rng() % 12, 1 + rng() % 7);
    const TreeProjector projector(t);
    for (int set = 0; set < 8; ++set) {
      std::vector<CellId> list;
      for (CellId c : CellRange(cells + 1)) {
        if (rng() % 2) list.push_back(c);
      }
      if (!list.empty() && rng() % 4 == 0) list.push_back(list.front());
      std::shuffle(list.begin(), list.end(), rng);
      ASSERT_EQ(projector.Project(list), ProjectPaths(t, list)) << t.ToString();
      std::set<CellId> subset(list.begin(), list.end());
      ASSERT_EQ(AsSet(projector.Project(list)), ProjectionReference(t, subset)) << t.ToString();
    }
  }
}

TEST(ProjectionTest, TreePathsAreTheLeafPaths) {
  const CellTree t = FromPaths({{A, B, C}, {A, B, D, A}, {C, A}, {A, B}});
  EXPECT_EQ(AsSet(TreePaths(t)), (std::set<CellString>{{A, B, C}, {A, B, D, A}, {C, A}}));
}

}  // namespace
}  // namespace raycell
