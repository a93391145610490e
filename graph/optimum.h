// The exact optimum (DESIGN.md §1 "Schedule and feasibility"): the shortest feasible
// schedule of a Cell Tree with a one-cell cache, found by A* over sets of processed nodes.
// The problem is NP-hard (shortest common supersequence), so the search has limits and,
// past one, answers "unknown" instead of a guess. Meant for small trees: to measure how far
// Peel and the bound are from the truth.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "graph/cell_tree.h"

namespace raycell {

struct OptimumLimits {
  std::uint64_t max_states = 2'000'000;  // states expanded
  double max_seconds = 10;               // wall time of the search
  std::size_t max_nodes = 4096;          // trees with more nodes (without the root): kTooLarge
  // Memory held by the search (stored states, hash table, open list), estimated.
  std::size_t max_bytes = std::size_t{1} << 30;
};

struct OptimumResult {
  enum Status { kOptimal, kUnknown, kTooLarge };
  Status status = kUnknown;
  std::uint64_t length = 0;      // fewest fetches; valid only if kOptimal
  std::vector<CellId> schedule;  // an optimal schedule if kOptimal, else empty
  std::uint64_t states_expanded = 0;
  double seconds = 0;
  std::string reason;  // how the answer was reached, or which limit stopped the search
  // "optimal 5 (schedule 2 0 1 2 0; 12 states, 0.001 s): ..." or "unknown (...): reason".
  std::string ToString() const;
};
const char* ToString(OptimumResult::Status status);

// The shortest feasible schedule of `tree` (fewest fetches with a one-cell cache).
//
// A* over downward-closed sets of processed nodes. A move picks a cell c and processes every
// node of c whose parent is processed (moves that process nothing are skipped); each move is
// one fetch. Heuristic: the bound of the remaining forest. Peel's length is the incumbent:
// only schedules strictly shorter than Peel's are searched for, and if there are none Peel's
// schedule is returned as optimal. Deterministic: the same tree gives the same schedule.
//
// kTooLarge when tree.node_count() > limits.max_nodes (checked first, before anything else);
// kUnknown when the state, time or memory limit stops the search (reason names it).
OptimumResult ExactOptimum(const CellTree& tree, const OptimumLimits& limits = {});

}  // namespace raycell
