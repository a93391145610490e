// Beam search for short schedules (docs/design.md §1 "Schedule and feasibility"): a breadth-first
// search over sets of processed nodes that keeps only the `width` most promising states of
// each depth.
//
// States and moves are those of the exact search (search/optimum.h): a state is a downward-
// closed set of processed nodes; a move on cell c processes every node of c whose parent is
// processed, and is generated only when it processes at least one node. All states of a
// layer have made the same number of moves g.
//
// Ordering. A child is ranked by
//   1. f = g + h, h = the bound (sum over cells of maxGen) of the unprocessed forest: the
//      fewest fetches any schedule through the child can have; lower first;
//   2. the nodes left unprocessed: fewer first;
//   3. a tie-break: the order children were generated (parent rank, then cell) when
//      seed == 0, else a hash of (seed, parent rank, cell): deterministic, but differently
//      ordered per seed, so several beams explore different states.
// The best `width` distinct children form the next layer; duplicates (the same set reached
// from two parents) are merged through a hash of the set. The search stops at the first
// layer holding the complete set, so it always returns a feasible schedule unless an
// `upper` limit pruned every state.
//
// Cost. A move on cell c is scored by one pass over c's nodes (its ready nodes and the change
// of its maxGen term). A state's scores are computed when it is kept, from its parent's: only
// the cells its move changes are scored again (the moved cell, and the cells of its processed
// nodes' children, now ready); the others read the same bits as in the parent. A layer then
// costs the scoring of its kept states plus picking its best 2 * width children (nth_element,
// then a sort). The work limit counts, per state, a pass over all the forest's nodes (scoring
// every cell afresh, as the search once did), so that it gives the same widths and schedules:
// the width shrinks (never below 1) when width * nodes * (moves still expected) would pass
// max_node_visits, so huge forests degrade to a greedy search instead of blowing up; every
// limit counts work, not time.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "graph/cell_tree.h"
#include "graph/forest.h"

namespace raycell {

struct BeamOptions {
  std::size_t width = 256;  // states kept per layer
  std::uint64_t seed = 0;   // 0: tie-break by generation order; else by a seeded hash
  // Children with f >= upper are dropped (0: no limit): only schedules shorter than `upper`
  // are looked for, and none may be found.
  std::uint64_t upper = 0;
  // Work limit, in node visits (each child scored costs the nodes of its cell, each state
  // kept its bitset): the width is lowered to fit; a search that ran over continues with
  // width 1 until it completes.
  std::uint64_t max_node_visits = 1'000'000'000;
};

struct BeamResult {
  bool found = false;            // false only when `upper` pruned every state
  std::vector<CellId> schedule;  // feasible for the forest searched, when found
  std::size_t width = 0;         // the largest width used
  std::uint64_t states = 0;      // states kept, over all layers
  std::uint64_t children = 0;    // children scored
  std::uint64_t node_visits = 0;
  // "beam 256: 91 entries, 23000 states, 600000 children".
  std::string ToString() const;
};

BeamResult BeamSearch(const CellForest& forest, const BeamOptions& options = {});
BeamResult BeamSearch(const CellTree& tree, const BeamOptions& options = {});

}  // namespace raycell
