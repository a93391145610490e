#include "bounds/scs_budget.h"

#include <algorithm>

namespace raycell::scs {

BudgetResult BudgetSearch::Run() {
  BudgetResult r;
  std::vector<std::uint32_t> used(dag_.symbols(), 0);
  std::uint64_t left = 0;
  for (std::uint32_t b : budget_) left += b;
  // Every move advances some path, so the depth is at most the strings' total length.
  std::uint64_t deepest = 0;
  for (Symbol a = 0; a < dag_.symbols(); ++a) deepest += dag_.total(a);
  evals_.resize(std::min(left, deepest) + 2);
  keys_.resize(evals_.size());
  frontiers_.resize(evals_.size());
  symbols_.resize(evals_.size());
  const Outcome o = Search(moves_.WithoutDominated(dag_.start()), used, left);
  r.states = states_;
  if (o == kFound) {
    r.answer = Realisability::kRealisable;
    for (Symbol a : path_) r.witness.push_back(dag_.cell(a));
  } else {
    r.answer = o == kFail ? Realisability::kNotRealisable : Realisability::kUnknown;
  }
  return r;
}

BudgetSearch::Outcome BudgetSearch::Search(const Frontier& f, std::vector<std::uint32_t>& used,
                                           std::uint64_t left) {
  if (f.empty()) return kFound;
  const std::size_t depth = path_.size();
  RAYCELL_CHECK_LT(depth, evals_.size());  // sized by Run
  Eval& e = evals_[depth];
  moves_.EvaluateInto(f, e);
  if (e.h > left) return kFail;
  for (Symbol a = 0; a < dag_.symbols(); ++a) {
    if (e.need[a] + used[a] > budget_[a]) return kFail;
  }
  for (std::size_t i = 0; i < e.parts.size(); ++i) {
    std::uint64_t left_in_part = 0;
    for (Symbol a : (*moves_.parts())[i].part()) left_in_part += budget_[a] - used[a];
    if (e.parts[i] > left_in_part) return kFail;
  }
  std::vector<std::uint32_t>& key = keys_[depth];
  key.assign(f.begin(), f.end());
  key.push_back(kNoSymbol);  // separates the frontier from the copies used
  key.insert(key.end(), used.begin(), used.end());
  const std::uint64_t hash = HashOf(key);
  if (failed_.Find(key, hash) != kNoState) return kFail;
  if (++states_ > limits_.max_states) return kStopped;
  std::vector<Symbol>& symbols = symbols_[depth];
  if (e.forced != kNoSymbol) {
    symbols.assign(1, e.forced);
  } else {
    moves_.SymbolsInto(f, symbols);
    // The nodes advanced with the most path length first; then the smaller symbol.
    gain_.assign(dag_.symbols(), 0);
    for (Node v : f) gain_[dag_.symbol(v)] += dag_.height(v);
    std::stable_sort(symbols.begin(), symbols.end(),
                     [&](Symbol a, Symbol b) { return gain_[a] > gain_[b]; });
  }
  for (Symbol a : symbols) {
    if (used[a] >= budget_[a]) continue;
    ++used[a];
    path_.push_back(a);
    RAYCELL_CHECK_LT(depth + 1, frontiers_.size());
    Frontier& next = frontiers_[depth + 1];  // the next level's (f is this one's or the start)
    moves_.MoveInto(f, a, next);
    const Outcome o = Search(next, used, left - 1);
    if (o != kFail) return o;
    path_.pop_back();
    --used[a];
  }
  failed_.Add(keys_[depth], hash);
  return kFail;
}

}  // namespace raycell::scs
