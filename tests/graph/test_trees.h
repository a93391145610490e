// Cell Trees for the tests: from given paths, and random ones.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <vector>

#include "graph/cell_tree.h"
#include "tests/cell_list.h"

namespace raycell::testing {

// The vocabulary of hand-made trees: cells A..F and a schedule (or path) of cells.
namespace cells {
inline constexpr CellId A{0}, B{1}, C{2}, D{3}, E{4}, F{5};
}  // namespace cells
using Schedule = CellList;

// One ray of a hand-made frame: its parent (kNoParent for a primary ray), the parent's visit
// it was spawned at, and its cells. Rays come one ray tree at a time.
struct TestRay {
  RayId parent = kNoParent;
  std::uint32_t spawn = 0;
  CellList cells;
};

// The rays as a frame, `samples` samples per visit.
inline RayBatch RaysOf(const std::vector<TestRay>& rays, std::uint32_t samples = 1) {
  RayBatch b(false);
  for (const TestRay& r : rays) {
    b.BeginRay(r.parent == kNoParent ? RayKind::kPrimary : RayKind::kShadow, r.parent, r.spawn, 0,
               0);
    for (CellId c : r.cells) b.AddVisit(c, samples, 0.f, 0.f);
  }
  return b;
}

inline CellTree TreeOf(const RayBatch& rays) {
  CellTreeBuilder builder;
  builder.AddBatch(rays);
  return builder.Finish();
}

// Primary rays with the given paths, one sample per visit.
inline CellTree FromPaths(const std::vector<CellList>& paths) {
  std::vector<TestRay> rays;
  for (const auto& p : paths) rays.push_back({kNoParent, 0, p});
  return TreeOf(RaysOf(rays));
}

// Random rays over `cells` cells: primary rays and rays spawned at a random visit of an
// earlier ray of the same ray tree (rays come one ray tree at a time, as the recorder writes
// them), paths of 1..max_length visits without consecutive repeats, one sample per visit.
inline CellTree RandomTree(std::mt19937& rng, std::uint32_t cells, int rays, int max_length = 6) {
  RayBatch b(false);
  std::uniform_int_distribution<std::uint32_t> cell_number(0, cells - 1);
  const auto cell = [&](std::mt19937& r) { return CellId(cell_number(r)); };
  std::uniform_int_distribution<int> length(1, max_length);
  int tree_start = 0;
  for (int i = 0; i < rays; ++i) {
    const bool primary = i == 0 || rng() % 3 == 0;
    if (primary) tree_start = i;
    const RayId parent = primary ? kNoParent : tree_start + rng() % (i - tree_start);
    const std::size_t pv = primary ? 0 : b.visit_end(parent) - b.visit_begin(parent);
    const auto spawn = static_cast<std::uint32_t>(primary ? 0 : rng() % pv);
    CellId prev = primary ? cell(rng) : b.cells()[b.visit_begin(parent) + spawn];
    b.BeginRay(primary ? RayKind::kPrimary : RayKind::kShadow, parent, spawn, 0, 0);
    b.AddVisit(prev, 1, 0.f, 0.f);
    for (int v = length(rng); v > 1; --v) {
      CellId next;
      do next = cell(rng);
      while (next == prev);
      b.AddVisit(prev = next, 1, 0.f, 0.f);
    }
  }
  CellTreeBuilder builder;
  builder.AddBatch(b);
  return builder.Finish();
}

// Primary paths: the `cells` rotations of 0 1 .. cells-1. maxGen (the bound) `cells`,
// optimum 2 cells - 1, Peel above the bound.
inline CellTree Rotations(std::uint32_t cells) {
  std::vector<Schedule> paths;
  for (std::uint32_t r = 0; r < cells; ++r) {
    Schedule p;
    for (std::uint32_t i = 0; i < cells; ++i) p.push_back(CellId((r + i) % cells));
    paths.push_back(p);
  }
  return FromPaths(paths);
}

// Calls `check(tree)` on `count` random trees of 2..5 cells and 1..8 rays, skipping those of
// more than 22 nodes (where BruteForceOptimum gets slow), each under a SCOPED_TRACE of the
// tree; returns how many trees it checked.
template <typename Check>
int ForSmallRandomTrees(std::mt19937& rng, int count, Check check) {
  int tried = 0;
  for (int i = 0; i < count; ++i) {
    const CellTree t = RandomTree(rng, 2 + rng() % 4, 1 + rng() % 8);
    if (t.node_count() > 22) continue;
    ++tried;
    SCOPED_TRACE(t.ToString());
    check(t);
  }
  return tried;
}

// The fewest fetches (one-cell cache) by breadth-first search over sets of processed nodes,
// no heuristic, no incumbent: each level tries every cell, scanning every node. The
// reference every bound and schedule of graph/ is tested against; small trees only.
inline std::size_t BruteForceOptimum(const CellTree& t) {
  std::vector<bool> start(t.size(), false);
  start[kRootNode.index()] = true;
  std::set<std::vector<bool>> seen{start};
  std::vector<std::vector<bool>> level{start};
  for (std::size_t depth = 0;; ++depth) {
    std::vector<std::vector<bool>> next;
    for (const std::vector<bool>& done : level) {
      if (std::all_of(done.begin(), done.end(), [](bool d) { return d; })) return depth;
      for (CellId c : CellRange(t.cell_count())) {
        std::vector<bool> after = done;
        for (NodeId n : t.nodes()) {
          if (!done[n.index()] && done[t.parent(n).index()] && t.cell(n) == c)
            after[n.index()] = true;
        }
        if (seen.insert(after).second) next.push_back(after);
      }
    }
    level = std::move(next);
  }
}

}  // namespace raycell::testing
