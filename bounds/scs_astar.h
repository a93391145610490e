// A* over the frontiers of the string DAG (bounds/string_dag.h) for the shortest common
// supersequence, with the heuristics of bounds/scs_heuristics.h. Internal to bounds/.
//
// Why its answers are proofs, continued from scs_heuristics.h: h is consistent and h = 0 at
// the end.
// So A* never needs to reopen a closed state (it does so anyway when a cheaper path appears,
// which keeps it correct for any admissible h), takes the end first at its optimal g, and,
// when stopped early, the smallest f = g + h on the open list is a lower bound: some state of a
// shortest path is on the open list with g at its optimum, so its f is at most the optimum.
//
// Incumbent. A greedy supersequence of length U is known; only states with f < U are stored.
// A shortest path with length < U has f < U all along, so it is never cut; if the open list
// runs empty, nothing shorter than U exists and U is the SCS. The bound reported after a stop
// is min(smallest open f, U).
//
// Determinism: the open list is ordered by (f, larger g first, creation order).
#pragma once

#include <cstdint>
#include <queue>
#include <vector>

#include "bounds/scs.h"
#include "bounds/scs_heuristics.h"
#include "bounds/string_dag.h"

namespace raycell::scs {

struct OpenEntry {
  std::uint32_t f, g;
  StateId state;
  // std::priority_queue pops the largest: smallest f, then largest g, then oldest state.
  bool operator<(const OpenEntry& o) const {
    if (f != o.f) return f > o.f;
    if (g != o.g) return g < o.g;
    return state > o.state;
  }
};

class AStar {
 public:
  AStar(const Dag& dag, const ScsLimits& limits, std::vector<PartTable>* parts = nullptr)
      : dag_(dag), moves_(dag, parts), limits_(limits) {}

  ScsResult Run();

 private:
  StateId Add(const Frontier& f, std::uint32_t g, std::uint32_t h, StateId parent, Symbol move);
  CellString Path(StateId s) const;
  static ScsResult Exact(ScsResult r, std::uint32_t length);

  const Dag& dag_;
  Moves moves_;
  ScsLimits limits_;
  StateStore store_;
  // Scratch of Run's loop, reused: the state expanded, a child, an evaluation, the moves.
  Frontier f_, next_;
  Eval e_;
  std::vector<Symbol> symbols_;
  std::priority_queue<OpenEntry> open_;
  std::vector<std::uint32_t> g_, h_;
  std::vector<StateId> parent_;
  std::vector<Symbol> move_;
};

}  // namespace raycell::scs
