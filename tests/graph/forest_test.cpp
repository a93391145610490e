#include "graph/forest.h"

#include <gtest/gtest.h>

#include <random>

#include "graph/peel.h"
#include "graph/schedule.h"
#include "tests/cell_list.h"
#include "tests/graph/test_trees.h"

namespace raycell {
namespace {

using testing::FromPaths;
using testing::RandomTree;
using Index = CellForest::Index;
using Schedule = testing::CellList;
constexpr CellId A{0}, B{1}, C{2};

TEST(CellForestTest, FromTreeKeepsCellsParentsAndGenerations) {
  // A B A and A C: tree nodes 1 A, 2 B, 3 A, 4 C; forest nodes 0..3.
  const CellTree t = FromPaths({{A, B, A}, {A, C}});
  const CellForest f = CellForest::FromTree(t);
  ASSERT_EQ(f.size(), 4u);
  EXPECT_EQ(f.parent(0), CellForest::kNone);
  EXPECT_EQ(f.parent(1), 0u);
  EXPECT_EQ(f.parent(2), 1u);
  EXPECT_EQ(f.parent(3), 0u);
  EXPECT_EQ(f.cell(2), A);
  EXPECT_EQ(f.same_cell_above(2), 0u);
  EXPECT_EQ(f.generation(2), 2u);
  EXPECT_EQ(f.height(0), 3u);
  EXPECT_EQ(f.child_count(0), 2u);
  EXPECT_EQ(f.nodes_of(A), (std::vector<Index>{0, 2}));
  EXPECT_EQ(f.bound(), Bound(t));
  EXPECT_EQ(f.cells(), (testing::CellList{A, B, C}));
  EXPECT_EQ(f.ToString(), "forest of 4 nodes, 3 cells, bound 4");
}

TEST(CellForestTest, SubRenumbersAndCutsParents) {
  const CellForest f = CellForest::FromTree(FromPaths({{A, B, A}, {A, C}}));
  const CellForest s = CellForest::Sub(f, {1, 2, 3});  // B A under the root's A, and C
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s.parent(0), CellForest::kNone);
  EXPECT_EQ(s.parent(1), 0u);
  EXPECT_EQ(s.parent(2), CellForest::kNone);
  EXPECT_EQ(s.bound(), 3u);
}

// A naive run: at each entry, scan every node.
std::vector<std::int32_t> NaiveEarliest(const CellForest& f, const Schedule& s) {
  std::vector<std::int32_t> at(f.size(), -1);
  for (std::size_t i = 0; i < s.size(); ++i) {
    std::vector<Index> now;
    for (Index n = 0; n < f.size(); ++n) {
      const Index p = f.parent(n);
      if (at[n] < 0 && f.cell(n) == s[i] && (p == CellForest::kNone || at[p] >= 0)) {
        now.push_back(n);
      }
    }
    for (Index n : now) at[n] = std::int32_t(i);
  }
  return at;
}

// A random schedule that is feasible: Peel's with random cells inserted.
Schedule Padded(const CellTree& t, std::mt19937& rng, int extra) {
  Schedule s = Peel(t).schedule;
  for (int k = 0; k < extra; ++k) {
    s.insert(s.begin() + rng() % (s.size() + 1),
             CellId(rng() % std::max<std::uint32_t>(1, t.cell_count())));
  }
  return s;
}

TEST(ScheduleTimesTest, EarliestIsTheRunAndLatestBoundsIt) {
  std::mt19937 rng(7);
  for (int i = 0; i < 500; ++i) {
    const CellTree t = RandomTree(rng, 2 + rng() % 4, 1 + rng() % 6);
    const CellForest f = CellForest::FromTree(t);
    const Schedule s = Padded(t, rng, rng() % 4);
    ScheduleTimer timer(f);
    const ScheduleTimes& times = timer.Compute(s);
    ASSERT_TRUE(times.feasible);
    EXPECT_EQ(times.earliest, NaiveEarliest(f, s));
    for (Index n = 0; n < f.size(); ++n) {
      EXPECT_LE(times.earliest[n], times.latest[n]);
      EXPECT_EQ(s[times.latest[n]], f.cell(n));
      for (auto* k = f.child_begin(n); k != f.child_end(n); ++k) {
        EXPECT_LT(times.latest[n], times.latest[*k]);
      }
    }
  }
}

// Entry p can be deleted exactly when no node has earliest == latest == p: compared with
// running every schedule with one entry deleted.
TEST(ScheduleTimesTest, DeletableExactlyWhenNoNodeIsTight) {
  std::mt19937 rng(11);
  int deletable = 0, kept = 0;
  for (int i = 0; i < 500; ++i) {
    const CellTree t = RandomTree(rng, 2 + rng() % 4, 1 + rng() % 6);
    const CellForest f = CellForest::FromTree(t);
    const Schedule s = Padded(t, rng, rng() % 3);
    ScheduleTimer timer(f);
    const ScheduleTimes& times = timer.Compute(s);
    for (std::size_t p = 0; p < s.size(); ++p) {
      bool tight = false;
      for (Index n = 0; n < f.size(); ++n) {
        tight |= times.earliest[n] == std::int32_t(p) && times.latest[n] == std::int32_t(p);
      }
      Schedule without = s;
      without.erase(without.begin() + p);
      EXPECT_EQ(IsFeasible(t, without), !tight);
      ++(tight ? kept : deletable);
    }
  }
  EXPECT_GT(deletable, 100);
  EXPECT_GT(kept, 100);
}

// Replacing entries i..j-1 by w is feasible exactly when w is feasible for the window's
// sub-forest {i <= earliest, latest < j}: compared on random windows and random w.
TEST(ScheduleTimesTest, WindowReplacementIsFeasibleExactlyForTheWindowForest) {
  std::mt19937 rng(13);
  int feasible = 0, infeasible = 0;
  for (int i = 0; i < 2000; ++i) {
    const CellTree t = RandomTree(rng, 2 + rng() % 3, 1 + rng() % 5);
    const CellForest f = CellForest::FromTree(t);
    const Schedule s = Padded(t, rng, rng() % 3);
    ScheduleTimer timer(f);
    const ScheduleTimes& times = timer.Compute(s);
    const std::size_t a = rng() % (s.size() + 1), b = rng() % (s.size() + 1);
    const std::size_t lo = std::min(a, b), hi = std::max(a, b);
    std::vector<Index> nodes;
    for (Index n = 0; n < f.size(); ++n) {
      if (times.earliest[n] >= std::int32_t(lo) && times.latest[n] < std::int32_t(hi)) {
        nodes.push_back(n);
      }
    }
    const CellForest sub = CellForest::Sub(f, nodes);
    Schedule w;
    for (std::size_t k = rng() % (hi - lo + 2); k > 0; --k) w.push_back(CellId(rng() % 4));
    Schedule replaced(s.begin(), s.begin() + lo);
    replaced.insert(replaced.end(), w.begin(), w.end());
    replaced.insert(replaced.end(), s.begin() + hi, s.end());
    const bool expected = IsFeasible(t, replaced);
    EXPECT_EQ(IsFeasible(sub, w), expected);
    ++(expected ? feasible : infeasible);
  }
  EXPECT_GT(feasible, 200);
  EXPECT_GT(infeasible, 200);
}

TEST(ScheduleTimesTest, InfeasibleScheduleIsReported) {
  const CellForest f = CellForest::FromTree(FromPaths({{A, B}}));
  EXPECT_FALSE(IsFeasible(f, {B, A}));
  EXPECT_TRUE(IsFeasible(f, {B, A, B}));
  ScheduleTimer timer(f);
  EXPECT_FALSE(timer.Compute({B, A}).feasible);
  EXPECT_EQ(timer.times().earliest[1], -1);
}

// In a projection a child may have its parent's cell: it waits for the next fetch.
TEST(CellForestTest, SameCellChildWaitsForTheNextFetch) {
  const CellForest f = CellForest::FromArrays({CellForest::kNone, 0}, {A, A});
  EXPECT_FALSE(IsFeasible(f, {A}));
  EXPECT_TRUE(IsFeasible(f, {A, A}));
  ScheduleTimer timer(f);
  const ScheduleTimes& t = timer.Compute({A, B, A});
  EXPECT_EQ(t.earliest, (std::vector<std::int32_t>{0, 2}));
  EXPECT_EQ(t.latest, (std::vector<std::int32_t>{0, 2}));
}

}  // namespace
}  // namespace raycell
