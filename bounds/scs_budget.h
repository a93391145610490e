// The budget search: is there a common supersequence of the strings with at most budget[a]
// copies of every symbol a (bounds/scs.h FitsBudget)? Internal to bounds/.
//
// Why its answers are proofs, continued from string_dag.h and scs_heuristics.h:
// The budget search is a depth-first search over (F, copies used so far) with the forced
// moves and dominated nodes above, cut when some symbol needs more copies than its budget
// leaves (hc per symbol) or the remaining budget in total is below hl; a state is remembered
// only once its whole subtree failed, so meeting it again (same F, same copies used) fails.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "bounds/scs.h"
#include "bounds/scs_heuristics.h"
#include "bounds/string_dag.h"

namespace raycell::scs {

// Depth-first search for a common supersequence within per-symbol budgets.
class BudgetSearch {
 public:
  BudgetSearch(const Dag& dag, std::vector<std::uint32_t> budget, const ScsLimits& limits,
               std::vector<PartTable>* parts = nullptr)
      : dag_(dag), moves_(dag, parts), budget_(std::move(budget)), limits_(limits) {}

  BudgetResult Run();

 private:
  enum Outcome { kFound, kFail, kStopped };

  Outcome Search(const Frontier& f, std::vector<std::uint32_t>& used, std::uint64_t left);

  const Dag& dag_;
  Moves moves_;
  std::vector<std::uint32_t> budget_;  // per dense symbol
  ScsLimits limits_;
  StateStore failed_;
  std::uint64_t states_ = 0;
  std::vector<Symbol> path_;
  std::vector<Eval> evals_;                       // per depth
  std::vector<std::vector<std::uint32_t>> keys_;  // per depth
  std::vector<Frontier> frontiers_;               // per depth: the frontier searched there
  std::vector<std::vector<Symbol>> symbols_;      // per depth: its moves, in order
  std::vector<std::uint64_t> gain_;               // scratch of one depth's ordering
};

}  // namespace raycell::scs
