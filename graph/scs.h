// Shortest common supersequence (SCS) of a set of strings over cell ids, and the question
// whether some common supersequence fits per-symbol budgets. Independent of Cell Trees: the
// lower bounds of graph/lower_bound.h feed them projections (graph/projection.h), and an
// exact schedule search can use them on any sub-forest's paths.
//
// Both searches run over position vectors (how far each string is matched) and are exact
// unless a state limit stops them; the limit is counted in states, so the answers are
// deterministic. The problem is NP-hard: what a limit buys depends on the strings.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "graph/projection.h"

namespace raycell {

struct ScsLimits {
  // States stored (A*) or visited (the budget search) before giving up.
  std::uint64_t max_states = 200'000;
};

struct ScsResult {
  // No common supersequence is shorter than lower_bound. When exact, lower_bound is the SCS
  // length and `supersequence` is a common supersequence of that length; otherwise it is the
  // smallest f = g + h on the A* open list when the limit stopped the search (still a proof,
  // see scs.cpp), and `supersequence` is the best one found (of length upper_bound).
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
  explicit ScsSolver(const std::vector<CellString>& strings);
  ~ScsSolver();
  ScsSolver(ScsSolver&&) noexcept;
  ScsSolver& operator=(ScsSolver&&) noexcept;

  // Strings kept (after dominance removal) and their distinct symbols, increasing.
  std::size_t strings() const;
  const std::vector<CellId>& symbols() const;
  // Copies of `cell` that a common supersequence can ever need: its copies in all strings
  // together (drop from any common supersequence the copies no string is matched to).
  std::uint32_t MostUseful(CellId cell) const;

  // The SCS length, by A* over position vectors with the largest of three admissible
  // heuristics (the longest remaining string; the sum over symbols of the most copies any
  // remaining string needs; the exact SCS of a few fixed pairs of strings), a greedy
  // supersequence as the incumbent, and forced moves (a symbol that every string still
  // needing it wants next is taken without branching). max_states counts stored states;
  // each takes about strings * bits per position / 8 + 40 bytes.
  ScsResult Shortest(const ScsLimits& limits = {}) const;

  // Groups of symbols whose remaining SCS FitsBudget also compares, at every state, with the
  // copies their budgets leave (a state where it exceeds them is a dead end). Costs memory per
  // group and node; not used by Shortest.
  void AddChecks(const std::vector<std::vector<CellId>>& groups);

  // Is there a common supersequence with at most budget[c] copies of every symbol c?
  // `budget` is indexed by cell id and must cover every symbol (RAYCELL_CHECK). Depth-first
  // search over (position vector, copies used) with a memo of failed states, pruned by the
  // heuristics per symbol and in total; kUnknown when max_states (states visited) is reached.
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
