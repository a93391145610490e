// Peel (docs/design.md §1 "Peel"): builds a feasible schedule for a Cell Tree backwards, by
// peeling the leaves of one cell at a time.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "graph/cell_tree.h"

namespace raycell {

enum class PeelKind : std::uint8_t {
  kCompletion,  // the cell was ready: every remaining node at its maxGen was a leaf
  kSplit,       // no cell was ready: the cell with the most leaves was taken
};
const char* ToString(PeelKind kind);

struct PeelResult {
  std::vector<CellId> schedule;  // in execution order, one fetch per entry
  std::vector<PeelKind> kinds;   // kinds[i]: the peel that produced schedule[i]
  std::size_t split_peels = 0;
  // "schedule 2 0 1 2 0 (5 entries, 2 split peels)".
  std::string ToString() const;
};

// Runs Peel exactly as docs/design.md specifies, tie-breaks included: the lowest-numbered ready
// cell, else the cell with the most leaves (lowest number on ties); each step removes the
// leaves of that cell present at the start of the step. O(nodes log cells) time, O(nodes)
// memory.
PeelResult Peel(const CellTree& tree);

// A schedule of `tree`'s cells planned at two levels (issue 23; docs/design.md §5 "Two-level
// scheduling"): `coarse_of` maps each cell to a coarser cell holding it (a board's cell; the
// tree's cells are a cache's). First the order of the coarse cells: Peel of the tree
// contracted to them (ContractTree). That schedule is run on the coarse tree (the run of §1:
// each entry processes every coarse node of its cell whose parent is done); then, per entry,
// the tree's nodes inside the coarse nodes it processed, a forest whose parents are all done
// by earlier entries, are ordered by Peel of that forest (SubTree), without its entries that
// process nothing in the run. The schedules of the entries, concatenated, are the result: feasible
// for `tree` (each forest's schedule is, once the forests before it are done), and every stretch of
// it stays inside one coarse cell, so a board that holds one coarse cell at a time fetches each
// coarse cell as often as the coarse schedule says. With every cell its own coarse cell it is
// Peel's schedule without the entries that process nothing in the run. O(nodes log cells + coarse
// entries x cells).
std::vector<CellId> TwoLevelPeel(const CellTree& tree, const std::vector<CellId>& coarse_of);

// A feasible schedule of a tree (Peel's, or a best-schedule search's).
using TreePlanner = std::function<std::vector<CellId>(const CellTree&)>;
// TwoLevelPeel with other planners: `coarse_plan` orders the coarse cells (it is given the
// contracted tree), `fine_plan` each entry's forest. Both must return feasible schedules.
std::vector<CellId> TwoLevelSchedule(const CellTree& tree, const std::vector<CellId>& coarse_of,
                                     const TreePlanner& coarse_plan, const TreePlanner& fine_plan);

}  // namespace raycell
