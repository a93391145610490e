#include "bounds/scs_astar.h"

#include <algorithm>

namespace raycell::scs {

ScsResult AStar::Run() {
  ScsResult r;
  r.supersequence = Greedy(dag_, moves_);
  r.upper_bound = static_cast<std::uint32_t>(r.supersequence.size());
  const Frontier start = moves_.WithoutDominated(dag_.start());
  const std::uint32_t h0 = moves_.Evaluate(start).h;
  r.lower_bound = std::min(h0, r.upper_bound);
  if (r.lower_bound == r.upper_bound) return Exact(r, r.upper_bound);
  Add(start, 0, h0, kNoState, kNoSymbol);
  open_.push({h0, 0, 0});
  while (!open_.empty()) {
    const OpenEntry top = open_.top();
    open_.pop();
    if (top.g > g_[top.state]) continue;  // stale: the state was reached cheaper since
    store_.GetInto(top.state, f_);
    const Frontier& f = f_;
    if (f.empty()) {
      r.supersequence = Path(top.state);
      return Exact(r, top.g);
    }
    if (store_.size() >= limits_.max_states) {
      r.lower_bound = std::min(top.f, r.upper_bound);  // the smallest f on the open list
      return r;
    }
    ++r.states;
    moves_.EvaluateInto(f, e_);
    if (e_.forced != kNoSymbol) {
      symbols_.assign(1, e_.forced);
    } else {
      moves_.SymbolsInto(f, symbols_);
    }
    const std::uint32_t g = top.g + 1;
    for (Symbol a : symbols_) {
      moves_.MoveInto(f, a, next_);
      const Frontier& next = next_;
      const std::uint64_t hash = HashOf(next);
      StateId s = store_.Find(next, hash);
      if (s != kNoState && g_[s] <= g) continue;
      std::uint32_t h;
      if (s != kNoState) {
        h = h_[s];
      } else {
        moves_.EvaluateInto(next, e_);
        h = e_.h;
      }
      if (g + h >= r.upper_bound) continue;
      if (s == kNoState) {
        s = Add(next, g, h, top.state, a);
      } else {
        g_[s] = g, parent_[s] = top.state, move_[s] = a;
      }
      open_.push({g + h, g, s});
    }
  }
  return Exact(r, r.upper_bound);  // nothing shorter than the greedy supersequence exists
}

StateId AStar::Add(const Frontier& f, std::uint32_t g, std::uint32_t h, StateId parent,
                   Symbol move) {
  const StateId s = store_.Add(f, HashOf(f));
  g_.push_back(g), h_.push_back(h), parent_.push_back(parent), move_.push_back(move);
  return s;
}

CellString AStar::Path(StateId s) const {
  CellString out;
  for (; parent_[s] != kNoState; s = parent_[s]) out.push_back(dag_.cell(move_[s]));
  std::reverse(out.begin(), out.end());
  return out;
}

ScsResult AStar::Exact(ScsResult r, std::uint32_t length) {
  r.exact = true;
  r.lower_bound = r.upper_bound = length;
  return r;
}

}  // namespace raycell::scs
