#include "bounds/string_dag.h"

#include <functional>
#include <map>
#include <utility>

namespace raycell::scs {

Dag::Dag(const std::vector<CellString>& input) {
  const std::vector<CellString> strings = RemoveDominated(input);
  for (const CellString& s : strings) cells_.insert(cells_.end(), s.begin(), s.end());
  std::sort(cells_.begin(), cells_.end());
  cells_.erase(std::unique(cells_.begin(), cells_.end()), cells_.end());
  k_ = static_cast<std::uint32_t>(cells_.size());
  Build(strings);
}

// Calls fn(path) for every path of v until fn returns false; false if it did.
template <typename F>
bool Dag::ForEachPath(Node v, std::vector<Symbol>& path, F fn) const {
  path.push_back(symbol_[v]);
  bool go = true;
  if (children_begin(v) == children_end(v)) {
    go = fn(path);
  } else {
    for (const Node* c = children_begin(v); c != children_end(v) && go; ++c) {
      go = ForEachPath(*c, path, fn);
    }
  }
  path.pop_back();
  return go;
}

bool Dag::CoveredSlow(Node u, Node v) const {
  const std::uint32_t* nu = need(u);
  const std::uint32_t* nv = need(v);
  for (Symbol a = 0; a < k_; ++a) {
    if (nu[a] > nv[a]) return false;
  }
  bool all = true;
  std::vector<Symbol> path;
  ForEachPath(u, path, [&](const std::vector<Symbol>& p) {
    all = Embeds(p, v);
    return all;
  });
  return all;
}

void Dag::Build(const std::vector<CellString>& strings) {
  // The trie, nodes in creation order (a parent before its children).
  std::vector<Symbol> sym;
  std::vector<std::vector<std::uint32_t>> kids;
  std::vector<std::uint32_t> first;  // trie node of each string's first symbol
  std::map<std::pair<std::uint32_t, Symbol>, std::uint32_t> edge;
  const std::uint32_t kTop = std::numeric_limits<std::uint32_t>::max();
  for (const CellString& s : strings) {
    std::uint32_t at = kTop;
    for (std::size_t i = 0; i < s.size(); ++i) {
      const Symbol a = Dense(s[i]);
      auto [it, inserted] = edge.insert({{at, a}, static_cast<std::uint32_t>(sym.size())});
      if (inserted) {
        sym.push_back(a);
        kids.emplace_back();
        if (at != kTop) kids[at].push_back(it->second);
      }
      at = it->second;
      if (i == 0) first.push_back(at);
    }
  }
  strings_ = strings.size();
  // Merge identical subtrees, children first: DAG ids are given in that order too, so a
  // child's id is below its parent's.
  std::vector<Node> canon(sym.size());
  std::unordered_map<std::vector<std::uint32_t>, Node, VectorHash> ids;
  child_begin_.push_back(0);
  for (std::size_t t = sym.size(); t-- > 0;) {
    std::vector<std::uint32_t> key{sym[t]};
    for (std::uint32_t c : kids[t]) key.push_back(canon[c]);
    std::sort(key.begin() + 1, key.end());
    key.erase(std::unique(key.begin() + 1, key.end()), key.end());
    auto [it, inserted] = ids.insert({key, static_cast<Node>(symbol_.size())});
    if (inserted) Add(key);
    canon[t] = it->second;
  }
  dense_ = symbol_.size() <= kDenseNodes;
  if (dense_) covered_bits_.assign((symbol_.size() * symbol_.size() + 3) / 4, 0);
  for (std::uint32_t f : first) start_.push_back(canon[f]);
  std::sort(start_.begin(), start_.end());
  start_.erase(std::unique(start_.begin(), start_.end()), start_.end());
  total_.assign(k_, 0);
  for (const CellString& s : strings) {
    for (CellId c : s) ++total_[Dense(c)];
  }
}

void Dag::Add(const std::vector<std::uint32_t>& key) {
  const Node v = static_cast<Node>(symbol_.size());
  symbol_.push_back(key[0]);
  children_.insert(children_.end(), key.begin() + 1, key.end());
  child_begin_.push_back(static_cast<std::uint32_t>(children_.size()));
  std::uint32_t h = 0;
  need_.resize(need_.size() + k_, 0);
  std::uint32_t* n = need_.data() + std::size_t{v} * k_;
  for (auto c = key.begin() + 1; c != key.end(); ++c) {
    h = std::max(h, height_[*c]);
    const std::uint32_t* nc = need(*c);
    for (Symbol a = 0; a < k_; ++a) n[a] = std::max(n[a], nc[a]);
  }
  height_.push_back(h + 1);
  ++n[key[0]];
  std::uint64_t mask = 0;
  for (Symbol a = 0; a < k_; ++a) {
    if (n[a] != 0) mask |= std::uint64_t{1} << (a % 64);
  }
  mask_.push_back(mask);
}

// Whether p is a subsequence of some path of v: reach(i, w) = p[i..] embeds in a path of w.
bool Dag::Embeds(const std::vector<Symbol>& p, Node v) const {
  std::unordered_map<std::uint64_t, bool> memo;
  std::function<bool(std::size_t, Node)> reach = [&](std::size_t i, Node w) -> bool {
    if (i == p.size()) return true;
    if (height_[w] < p.size() - i) return false;
    const std::uint64_t key = (std::uint64_t{w} << 16) | i;
    const auto it = memo.find(key);
    if (it != memo.end()) return it->second;
    bool ok = false;
    if (symbol_[w] == p[i]) {
      ok = i + 1 == p.size();
      for (const Node* c = children_begin(w); c != children_end(w) && !ok; ++c) {
        ok = reach(i + 1, *c);
      }
    }
    for (const Node* c = children_begin(w); c != children_end(w) && !ok; ++c) ok = reach(i, *c);
    memo.emplace(key, ok);
    return ok;
  };
  return reach(0, v);
}

}  // namespace raycell::scs
