// Shortest common supersequence (SCS) of a set of strings over cell ids, and the question
// whether some common supersequence fits per-symbol budgets. Independent of Cell Trees: the
// lower bounds of bounds/lower_bound.h feed them projections (bounds/projection.h), and an
// exact schedule search can use them on any sub-forest's paths.
//
// Both searches run over frontiers of a DAG of the strings (a trie whose identical subtrees are
// merged; a frontier is the set of nodes still to match, without nodes whose paths are
// subsequences of another's) and are exact unless a state limit stops them; the limit is
// counted in states, so the answers are deterministic. The problem is NP-hard: what a limit
// buys depends on the strings. An ScsSolver keeps memo tables that its searches fill, so one
// solver must not be used by two threads at once (separate solvers may).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "bounds/projection.h"

namespace raycell {

struct ScsLimits {
  // States stored (A*) or visited (the budget search) before giving up.
  std::uint64_t max_states = 200'000;
};

struct ScsResult {
  // No common supersequence is shorter than lower_bound. When exact, lower_bound is the SCS
  // length and `supersequence` is a common supersequence of that length; otherwise it is the
  // smallest f = g + h on the A* open list when the limit stopped the search (still a proof,
  // see bounds/scs_astar.h), and `supersequence` is the best one found (of length upper_bound).
  std::uint32_t lower_bound = 0;
  std::uint32_t upper_bound = 0;  // length of `supersequence`
  bool exact = false;
  CellString supersequence;
  std::uint64_t states = 0;  // states expanded
  // "exact 7 (12 states)" or "in [5, 7] (200000 states)".
  std::string ToString() const;
};

enum class Realisability { kRealisable, kNotRealisable, kUnknown };
const char* ToString(Realisability r);

struct BudgetResult {
  Realisability answer = Realisability::kUnknown;
  CellString witness;  // a common supersequence within the budgets when kRealisable
  std::uint64_t states = 0;
};

// A set of strings prepared once (duplicates, empty strings and strings that are
// subsequences of others removed; symbols renumbered; the heuristics' tables built) and then
// asked any number of questions. Movable, not copyable.
class ScsSolver {
 public:
  // Any number of strings over any cell ids.
  // merge_parts: Shortest's heuristic also merges pairs into parts of up to 4 symbols (see
  // there).
  explicit ScsSolver(const std::vector<CellString>& strings, bool merge_parts = false);
  ~ScsSolver();
  ScsSolver(ScsSolver&&) noexcept;
  ScsSolver& operator=(ScsSolver&&) noexcept;

  // Strings kept (after dominance removal) and their distinct symbols, increasing.
  std::size_t strings() const;
  const std::vector<CellId>& symbols() const;
  // Copies of `cell` that a common supersequence can ever need: its copies in all strings
  // together (drop from any common supersequence the copies no string is matched to).
  std::uint32_t MostUseful(CellId cell) const;

  // The SCS length, by A* over frontiers with the largest of three admissible, consistent
  // heuristics (the longest remaining path; the sum over symbols of the most copies one
  // remaining path needs; for 4 to 40 symbols, the sum over disjoint pairs of symbols, chosen
  // by their gain at the start, of the pair's remaining SCS, memoised; with merge_parts and 8 or
  // more symbols the pairs and lone symbols are then merged greedily into parts of up to 4 symbols
  // while a part's SCS at the start exceeds its two halves' sum: a stronger h, each state several
  // times dearer), a greedy
  // supersequence as the incumbent, and forced moves (a symbol that every path still needing
  // it wants next is taken without branching). max_states counts stored states; each takes
  // about 4 bytes per frontier node plus 40. Building the solver costs one small SCS search
  // per pair of symbols (for 4 to 40 symbols).
  ScsResult Shortest(const ScsLimits& limits = {}) const;

  // Is there a common supersequence with at most budget[c] copies of every symbol c?
  // `budget` is indexed by cell id and must cover every symbol (RAYCELL_CHECK). Depth-first
  // search over (frontier, copies used) with a memo of failed states, pruned per symbol, per
  // pair of the heuristic and in total; kUnknown when max_states (states visited) is reached.
  BudgetResult FitsBudget(const std::vector<std::uint32_t>& budget,
                          const ScsLimits& limits = {}) const;

 private:
  class Instance;
  std::unique_ptr<const Instance> in_;
};

// ScsSolver(strings).Shortest(limits).
ScsResult ShortestCommonSupersequence(const std::vector<CellString>& strings,
                                      const ScsLimits& limits = {});

}  // namespace raycell
