// The exact optimum (docs/design.md §1 "Schedule and feasibility"): the shortest feasible
// schedule of a Cell Tree with a one-cell cache, found by A* over sets of processed nodes.
// The problem is NP-hard (shortest common supersequence), so the search has limits and,
// past one, answers a bracket [lower, upper] instead of a guess. Meant for small trees, and
// for the short windows that the local search (search/local_search.h) re-solves.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "graph/cell_tree.h"
#include "graph/forest.h"
#include "search/search_util.h"

namespace raycell {

struct OptimumLimits {
  std::uint64_t max_states = 2'000'000;  // states expanded
  // Wall time of the search: a safety net only (a run that hits it is not reproducible).
  double max_seconds = 10;
  std::size_t max_nodes = 4096;  // trees with more nodes (without the root): kTooLarge
  // Memory held by the search (stored states, hash table, open list, heuristic tables),
  // estimated.
  std::size_t max_bytes = std::size_t{1} << 30;
};

// A lower bound on the fetches still needed from a set of processed nodes (bits over the
// forest's nodes, search/search_util.h). It must be consistent: 0 for the complete set, and
// at most one more than its value after any move. The search uses the largest of its own
// heuristic and this one.
using RemainingBound = std::function<std::uint32_t(const CellForest&, const Word* processed)>;

struct OptimumOptions {
  OptimumLimits limits;
  // A feasible schedule (checked): only strictly shorter schedules are searched for, and it
  // is the answer when there is none. Empty: Peel's schedule.
  std::vector<CellId> incumbent;
  // A known lower bound on the optimum (0: none), e.g. from projections: when the incumbent
  // meets it the incumbent is optimal without a search, and it floors the bracket.
  std::uint64_t lower_bound = 0;
  // Strengthen the maxGen heuristic with exact shortest common supersequences of pairs of
  // cells (see optimum.cpp, "Heuristic").
  bool pair_heuristic = true;
  RemainingBound extra_bound;  // optional
};

struct OptimumResult {
  enum Status { kOptimal, kUnknown, kTooLarge };
  Status status = kUnknown;
  std::uint64_t length = 0;      // fewest fetches; valid only if kOptimal
  std::vector<CellId> schedule;  // an optimal schedule if kOptimal, else empty
  // The optimum is in [lower, upper]: equal when kOptimal; for kUnknown, upper is the
  // incumbent's length and lower the best bound the search proved (at least the maxGen bound
  // and the given lower_bound). 0 and 0 for kTooLarge.
  std::uint64_t lower = 0, upper = 0;
  std::uint64_t states_expanded = 0;
  double seconds = 0;
  std::string reason;  // how the answer was reached, or which limit stopped the search
  // "optimal 5 (schedule 2 0 1 2 0; 12 states, 0.001 s): ..." or
  // "unknown in [78, 85] (...): reason".
  std::string ToString() const;
};
const char* ToString(OptimumResult::Status status);

// The shortest feasible schedule of `tree` (fewest fetches with a one-cell cache), with
// Peel's schedule as the incumbent and the pair heuristic.
//
// A* over downward-closed sets of processed nodes. A move picks a cell c and processes every
// node of c whose parent is processed (moves that process nothing are skipped); each move is
// one fetch. Deterministic: the same tree and options give the same schedule.
//
// kTooLarge when tree.node_count() > limits.max_nodes (checked first, before anything else);
// kUnknown when the state, time or memory limit stops the search (reason names it).
OptimumResult ExactOptimum(const CellTree& tree, const OptimumLimits& limits = {});
OptimumResult ExactOptimum(const CellTree& tree, const OptimumOptions& options);

// The search itself, on a forest: the shortest schedule strictly shorter than `upper`
// (0: no limit).
struct ShorterResult {
  enum Status { kFound, kNone, kStopped };
  Status status = kStopped;
  std::vector<CellId> schedule;  // kFound: a shortest schedule, shorter than upper
  // kFound, kNone: the optimum's lower bound is exact (the found length, or upper).
  // kStopped: every schedule has at least `lower` entries.
  std::uint64_t lower = 0;
  std::uint64_t expanded = 0;
  std::uint64_t work = 0;  // node visits (scans for ready nodes, bitsets copied, heuristic)
  std::size_t bytes = 0;   // peak memory estimate
  std::string stopped;     // which limit stopped the search
};
struct ShorterOptions {
  std::uint64_t upper = 0;
  // Ties between states of equal f and g are broken by creation order (0) or by a hash of
  // the state with this seed: another shortest schedule, deterministically.
  std::uint64_t seed = 0;
  OptimumLimits limits;  // max_nodes is not used here
  bool pair_heuristic = false;
  RemainingBound extra_bound;
};
ShorterResult FindShorter(const CellForest& forest, const ShorterOptions& options);

}  // namespace raycell
