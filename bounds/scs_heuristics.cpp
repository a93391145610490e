#include "bounds/scs_heuristics.h"

#include <algorithm>
#include <iterator>
#include <map>
#include <utility>

#include "bounds/scs_astar.h"

namespace raycell::scs {

PartTable::PartTable(const Dag& dag, std::vector<Symbol> part, std::uint64_t sub_states,
                     std::uint64_t total_states)
    : dag_(dag), part_(std::move(part)), sub_states_(sub_states), left_(total_states) {
  std::vector<bool> in(dag.symbols(), false);
  for (Symbol a : part_) in[a] = true;
  sets_.emplace_back();  // id 0: the empty set
  ids_.emplace(std::vector<std::uint32_t>{}, 0);
  phi_.resize(dag.size());
  for (Node v = 0; v < dag.size(); ++v) {  // children have smaller ids
    std::vector<CellString> strings;
    for (const Node* c = dag.children_begin(v); c != dag.children_end(v); ++c) {
      const auto& child = sets_[phi_[*c]];
      strings.insert(strings.end(), child.begin(), child.end());
    }
    if (in[dag.symbol(v)]) {
      if (strings.empty()) strings.emplace_back();
      for (CellString& s : strings) s.insert(s.begin(), dag.cell(dag.symbol(v)));
    }
    phi_[v] = Intern(RemoveDominated(std::move(strings)));
  }
}

std::uint32_t PartTable::Intern(std::vector<CellString> set) {
  std::vector<std::uint32_t> flat;
  for (const CellString& s : set) {
    for (CellId c : s) flat.push_back(c.value());
    flat.push_back(kNoCell.value());
  }
  auto [it, inserted] = ids_.emplace(flat, static_cast<std::uint32_t>(sets_.size()));
  if (inserted) sets_.push_back(std::move(set));
  return it->second;
}

std::uint32_t PartTable::Remaining(const Frontier& f) {
  key_.clear();
  for (Node v : f) {
    if (phi_[v] != 0) key_.push_back(phi_[v]);
  }
  if (key_.empty()) return 0;
  std::sort(key_.begin(), key_.end());
  key_.erase(std::unique(key_.begin(), key_.end()), key_.end());
  const auto it = memo_.find(key_);
  if (it != memo_.end()) return it->second;
  std::vector<CellString> strings;
  for (std::uint32_t id : key_) strings.insert(strings.end(), sets_[id].begin(), sets_[id].end());
  ScsLimits limits;
  limits.max_states = std::min(sub_states_, left_);
  std::uint32_t value = 0;
  if (limits.max_states == 0) {
    for (Symbol a : part_) {
      std::uint32_t most = 0;
      for (const CellString& s : strings) {
        most = std::max<std::uint32_t>(
            most, static_cast<std::uint32_t>(std::count(s.begin(), s.end(), dag_.cell(a))));
      }
      value += most;
    }
  } else {
    const Dag sub(strings);
    const ScsResult r = AStar(sub, limits).Run();
    value = r.lower_bound;
    left_ -= std::min(left_, r.states + 1);
  }
  memo_.emplace(key_, value);
  return value;
}

Eval Moves::Evaluate(const Frontier& f) {
  Eval e;
  EvaluateInto(f, e);
  return e;
}

void Moves::EvaluateInto(const Frontier& f, Eval& e) {
  const std::uint32_t k = dag_.symbols();
  e.h = e.hl = 0;
  e.forced = kNoSymbol;
  e.parts.clear();
  e.need.assign(k, 0);
  std::fill(blocked_.begin(), blocked_.end(), 0);
  for (Node v : f) {
    e.hl = std::max(e.hl, dag_.height(v));
    const std::uint32_t* n = dag_.need(v);
    const Symbol s = dag_.symbol(v);
    for (Symbol a = 0; a < k; ++a) {
      if (n[a] == 0) continue;
      e.need[a] = std::max(e.need[a], n[a]);
      if (a != s) blocked_[a] = 1;
    }
  }
  std::uint32_t hc = 0;
  for (Symbol a = 0; a < k; ++a) {
    hc += e.need[a];
    if (e.forced == kNoSymbol && e.need[a] > 0 && !blocked_[a]) e.forced = a;
  }
  e.h = std::max(e.hl, hc);
  if (parts_ != nullptr && !parts_->empty() && !f.empty()) {
    std::uint32_t hp = hc;
    for (PartTable& p : *parts_) {
      for (Symbol a : p.part()) hp -= e.need[a];
      e.parts.push_back(p.Remaining(f));
      hp += e.parts.back();
    }
    e.h = std::max(e.h, hp);
  }
}

CellString Greedy(const Dag& dag, Moves& moves) {
  Frontier f = moves.WithoutDominated(dag.start()), next;
  CellString out;
  Eval e;
  std::vector<Symbol> symbols;
  while (!f.empty()) {
    moves.EvaluateInto(f, e);
    Symbol best = e.forced;
    if (best == kNoSymbol) {
      std::uint32_t best_h = std::numeric_limits<std::uint32_t>::max();
      std::uint64_t best_gain = 0;
      moves.SymbolsInto(f, symbols);
      for (Symbol a : symbols) {
        moves.MoveInto(f, a, next);
        moves.EvaluateInto(next, e);
        const std::uint32_t h = e.h;
        std::uint64_t gain = 0;
        for (Node v : f) {
          if (dag.symbol(v) == a) gain += dag.height(v);
        }
        if (h < best_h || (h == best_h && gain > best_gain)) {
          best = a, best_h = h, best_gain = gain;
        }
      }
    }
    out.push_back(dag.cell(best));
    moves.MoveInto(f, best, next);
    f.swap(next);
  }
  return out;
}

std::vector<PartTable> ChooseParts(const Dag& dag, const std::vector<CellString>& strings,
                                   std::uint64_t sub_states, bool merge) {
  constexpr std::uint32_t kMostSymbols = 40;
  constexpr std::uint32_t kMergeSymbols = 8;
  constexpr std::size_t kMostPartSymbols = 4;
  constexpr std::uint64_t kMergedSubStates = 2000, kMergedTotalStates = 50'000;
  std::vector<PartTable> parts;
  const std::uint32_t k = dag.symbols();
  if (k < 4 || k > kMostSymbols) return parts;
  Moves moves(dag);
  const Eval root = moves.Evaluate(dag.start());
  std::vector<std::pair<std::uint32_t, std::pair<Symbol, Symbol>>> gains;
  ScsLimits limits;
  limits.max_states = sub_states;
  auto start_scs = [&](const std::vector<Symbol>& group) {
    std::vector<CellId> cells;
    for (Symbol a : group) cells.push_back(dag.cell(a));
    const Dag sub(ProjectStrings(strings, cells));
    return AStar(sub, limits).Run().lower_bound;
  };
  for (Symbol a = 0; a < k; ++a) {
    for (Symbol b = a + 1; b < k; ++b) {
      const std::uint32_t scs = start_scs({a, b});
      if (scs > root.need[a] + root.need[b]) {
        gains.push_back({scs - root.need[a] - root.need[b], {a, b}});
      }
    }
  }
  std::stable_sort(gains.begin(), gains.end(),
                   [](const auto& x, const auto& y) { return x.first > y.first; });
  std::vector<bool> used(k, false);
  std::vector<std::vector<Symbol>> groups;
  std::vector<std::uint32_t> value;  // each group's SCS at the start (a lower bound of it)
  for (const auto& g : gains) {
    const auto [a, b] = g.second;
    if (used[a] || used[b]) continue;
    used[a] = used[b] = true;
    groups.push_back({a, b});
    value.push_back(g.first + root.need[a] + root.need[b]);
  }
  if (merge && k >= kMergeSymbols) {
    for (Symbol a = 0; a < k; ++a) {
      if (!used[a]) groups.push_back({a}), value.push_back(root.need[a]);
    }
    std::map<std::vector<Symbol>, std::uint32_t> known;
    for (;;) {
      std::uint32_t best_gain = 0;
      std::size_t bi = 0, bj = 0;
      std::uint32_t best_value = 0;
      for (std::size_t i = 0; i < groups.size(); ++i) {
        for (std::size_t j = i + 1; j < groups.size(); ++j) {
          if (groups[i].size() + groups[j].size() > kMostPartSymbols) continue;
          std::vector<Symbol> both;
          std::merge(groups[i].begin(), groups[i].end(), groups[j].begin(), groups[j].end(),
                     std::back_inserter(both));
          auto it = known.find(both);
          if (it == known.end()) it = known.emplace(both, start_scs(both)).first;
          if (it->second > value[i] + value[j] + best_gain) {
            best_gain = it->second - value[i] - value[j];
            bi = i, bj = j, best_value = it->second;
          }
        }
      }
      if (best_gain == 0) break;
      std::vector<Symbol> both;
      std::merge(groups[bi].begin(), groups[bi].end(), groups[bj].begin(), groups[bj].end(),
                 std::back_inserter(both));
      groups[bi] = both;
      value[bi] = best_value;
      groups.erase(groups.begin() + static_cast<std::ptrdiff_t>(bj));
      value.erase(value.begin() + static_cast<std::ptrdiff_t>(bj));
    }
  }
  for (auto& g : groups) {
    if (g.size() == 2) parts.emplace_back(dag, std::move(g), sub_states);
    if (g.size() > 2) parts.emplace_back(dag, std::move(g), kMergedSubStates, kMergedTotalStates);
  }
  return parts;
}

}  // namespace raycell::scs
