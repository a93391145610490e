// Peel (docs/design.md §1 "Peel"): builds a feasible schedule for a Cell Tree backwards, by
// peeling the leaves of one cell at a time.
#pragma once

#include <cstddef>
#include <cstdint>
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

}  // namespace raycell
