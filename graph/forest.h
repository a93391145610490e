// A forest of cells: the Cell Tree without its virtual root, or the part of one that a
// stretch of a schedule must process. The common input of the schedule searches (beam
// search, local search, exact search), in flat arrays.
//
// Node i of CellForest::FromTree(tree) is tree node i + 1. Parents come before their
// children (parent(n) < n), so a pass in index order visits ancestors first. In a Cell Tree
// a child never has its parent's cell (rays never repeat a cell consecutively); a forest
// built by FromArrays, e.g. a projection onto a few cells, may.
//
// Running a schedule on a forest is docs/design.md §1's run: at each entry c, every unprocessed
// node of cell c whose parent was processed before the entry (a root: always) is processed;
// a child of c made ready by the entry waits for the next fetch of c.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "graph/cell_tree.h"

namespace raycell {

class CellForest {
 public:
  using Index = std::uint32_t;
  static constexpr Index kNone = std::numeric_limits<Index>::max();

  // Node i is tree node i + 1; the root's children are the roots.
  static CellForest FromTree(const CellTree& tree);
  // The nodes `nodes` of `forest` (strictly increasing indices), renumbered 0.. in that
  // order; a node whose parent is not among them becomes a root. Cell ids are kept.
  static CellForest Sub(const CellForest& forest, const std::vector<Index>& nodes);
  // From (parent, cell) lists: parent[i] < i or kNone. For tests and tools.
  static CellForest FromArrays(const std::vector<Index>& parent, const std::vector<CellId>& cell);

  std::size_t size() const { return cell_.size(); }
  // One more than the largest cell id of any node (0 when empty).
  std::uint32_t cell_count() const { return cell_count_; }
  // Cells with at least one node, increasing.
  const std::vector<CellId>& cells() const { return cells_; }

  CellId cell(Index n) const { return cell_[n]; }
  Index parent(Index n) const { return parent_[n]; }  // kNone for a root
  // Nearest proper ancestor with the same cell, or kNone.
  Index same_cell_above(Index n) const { return same_cell_above_[n]; }
  // Nodes of the same cell on the path from its root to n, inclusive.
  std::uint32_t generation(Index n) const { return generation_[n]; }
  // Children of n: child_begin(n) .. child_end(n) into children().
  const Index* child_begin(Index n) const { return children_.data() + child_start_[n]; }
  const Index* child_end(Index n) const { return children_.data() + child_start_[n + 1]; }
  std::size_t child_count(Index n) const { return child_start_[n + 1] - child_start_[n]; }
  // Nodes of cell c, increasing (ancestors first). Empty for c >= cell_count().
  const std::vector<Index>& nodes_of(CellId c) const;
  // Longest path (in nodes) from n down to a leaf, n included.
  std::uint32_t height(Index n) const { return height_[n]; }

  // maxGen per cell (size cell_count()) and their sum: docs/design.md's bound for this forest.
  const std::vector<std::uint32_t>& max_generations() const { return max_gen_; }
  std::uint64_t bound() const { return bound_; }

  // "forest of 7 nodes, 3 cells, bound 5".
  std::string ToString() const;

 private:
  void Finish();

  std::vector<CellId> cell_;
  std::vector<Index> parent_, same_cell_above_;
  std::vector<std::uint32_t> generation_, height_;
  std::vector<std::size_t> child_start_;
  std::vector<Index> children_;
  std::vector<std::vector<Index>> nodes_of_;
  std::vector<CellId> cells_;
  std::vector<std::uint32_t> max_gen_;
  std::uint64_t bound_ = 0;
  std::uint32_t cell_count_ = 0;
};

// When each node is processed by a schedule, and how late it could be.
//
// earliest[n]: the entry (index into the schedule) at which the run processes n, or -1.
// latest[n]: the last entry at which n can be processed so that the rest of the schedule
// still processes n's whole subtree: the last entry of cell(n) before the latest entries of
// all of n's children (before the end for a leaf), or -1 when there is none.
//
// For a feasible schedule earliest[n] <= latest[n] for every node, and (proved in
// forest.cpp):
//  - the prefix before entry i leaves processed exactly {n : earliest[n] < i};
//  - the suffix from entry j finishes the forest from a downward-closed processed set X if
//    and only if X contains R_j = {n : latest[n] < j};
// so replacing entries i..j-1 by w keeps the schedule feasible if and only if w is a feasible
// schedule of the sub-forest {n : i <= earliest[n], latest[n] < j}. In particular entry p can
// be deleted if and only if no node has earliest[n] == latest[n] == p.
struct ScheduleTimes {
  std::vector<std::int32_t> earliest, latest;
  bool feasible = false;  // every node has an earliest entry
};

// Computes ScheduleTimes in O(nodes + schedule length), reusing its buffers between calls.
// Cells >= forest.cell_count() are allowed and process nothing.
class ScheduleTimer {
 public:
  explicit ScheduleTimer(const CellForest& forest);
  const ScheduleTimes& Compute(const std::vector<CellId>& schedule);
  const ScheduleTimes& times() const { return times_; }
  // Only the earliest entries (and feasibility); latest is left as it was.
  bool ComputeEarliest(const std::vector<CellId>& schedule);

 private:
  void ComputeLatest(const std::vector<CellId>& schedule);

  const CellForest& f_;
  ScheduleTimes times_;
  std::vector<std::vector<CellForest::Index>> pending_;  // per cell
  std::vector<CellForest::Index> batch_;
  std::vector<std::uint32_t> children_left_;
};

// True when `schedule` processes every node of `forest`.
bool IsFeasible(const CellForest& forest, const std::vector<CellId>& schedule);

}  // namespace raycell
