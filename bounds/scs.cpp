#include "bounds/scs.h"

#include <sstream>
#include <utility>

#include "base/check.h"
#include "bounds/scs_astar.h"
#include "bounds/scs_budget.h"
#include "bounds/scs_heuristics.h"
#include "bounds/string_dag.h"

// The searches and why their answers are proofs: the strings as a DAG and the states over it
// (string_dag.h), the heuristics (scs_heuristics.h), A* (scs_astar.h) and the budget search
// (scs_budget.h).

namespace raycell {

std::string ScsResult::ToString() const {
  std::ostringstream s;
  if (exact) {
    s << "exact " << lower_bound;
  } else {
    s << "in [" << lower_bound << ", " << upper_bound << "]";
  }
  s << " (" << states << " states)";
  return s.str();
}

const char* ToString(Realisability r) {
  switch (r) {
    case Realisability::kRealisable:
      return "realisable";
    case Realisability::kNotRealisable:
      return "not realisable";
    case Realisability::kUnknown:
      return "unknown";
  }
  return "?";
}

using scs::AStar;
using scs::BudgetSearch;
using scs::ChooseParts;
using scs::Dag;
using scs::kNoSymbol;
using scs::PartTable;
using scs::Symbol;

class ScsSolver::Instance {
 public:
  Instance(const std::vector<CellString>& strings, bool merge_parts)
      : dag(strings), parts(ChooseParts(dag, strings, kSubStates, merge_parts)) {}
  static constexpr std::uint64_t kSubStates = 20'000;
  Dag dag;
  // The heuristic's memo tables fill as searches run (not thread-safe; see scs.h).
  mutable std::vector<PartTable> parts;
};

ScsSolver::ScsSolver(const std::vector<CellString>& strings, bool merge_parts)
    : in_(std::make_unique<const Instance>(strings, merge_parts)) {}
ScsSolver::~ScsSolver() = default;
ScsSolver::ScsSolver(ScsSolver&&) noexcept = default;
ScsSolver& ScsSolver::operator=(ScsSolver&&) noexcept = default;

std::size_t ScsSolver::strings() const { return in_->dag.strings(); }
const std::vector<CellId>& ScsSolver::symbols() const { return in_->dag.cells(); }

std::uint32_t ScsSolver::MostUseful(CellId cell) const {
  const Symbol a = in_->dag.Dense(cell);
  return a == kNoSymbol ? 0 : in_->dag.total(a);
}

ScsResult ScsSolver::Shortest(const ScsLimits& limits) const {
  if (in_->dag.strings() == 0) {
    ScsResult r;
    r.exact = true;
    return r;
  }
  return AStar(in_->dag, limits, &in_->parts).Run();
}

BudgetResult ScsSolver::FitsBudget(const std::vector<std::uint32_t>& budget,
                                   const ScsLimits& limits) const {
  const Dag& dag = in_->dag;
  std::vector<std::uint32_t> dense(dag.symbols());
  for (Symbol a = 0; a < dag.symbols(); ++a) {
    RAYCELL_CHECK_LT(std::size_t{dag.cell(a).value()}, budget.size());
    dense[a] = budget[dag.cell(a).value()];
  }
  return BudgetSearch(dag, std::move(dense), limits, &in_->parts).Run();
}

ScsResult ShortestCommonSupersequence(const std::vector<CellString>& strings,
                                      const ScsLimits& limits) {
  return ScsSolver(strings).Shortest(limits);
}

}  // namespace raycell
