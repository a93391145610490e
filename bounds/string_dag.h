// The strings of a shortest-common-supersequence question (bounds/scs.h) as a DAG, and the
// states the searches walk over it: frontiers of DAG nodes, stored once each (StateStore).
// Internal to bounds/: scs_heuristics.h, scs_astar.h and scs_budget.h build on it.
//
// Why the searches' answers are proofs starts here; the heuristics (scs_heuristics.h), A*
// (scs_astar.h) and the budget search (scs_budget.h) add their parts.
//
// The strings as a DAG. The strings (without duplicates and strings that are subsequences of
// others) are put in a trie, and identical subtrees of the trie are merged: a node is a symbol
// and a set of child nodes, and its *paths* are the strings read from it down to a leaf (its
// own symbol first). No string is a prefix of another, so a node's paths determine it: two
// nodes with the same paths are the same node.
//
// States and moves. A state is a set F of nodes (the frontier): the strings still to be
// matched are the paths of the nodes of F. The start is the set of first nodes of the
// strings; the end is the empty set. A move appends a symbol a to the supersequence and
// replaces every node of F whose symbol is a by its children: that is advancing every string
// whose next symbol is a. Advancing every such string (rather than some) is never worse: from a
// state that is ahead in every string, every continuation that completes the other state
// completes this one too. So the shortest common supersequence is the fewest moves from the
// start to the end.
//
// Dominated nodes. If every path of u is a subsequence of some path of another node v of F,
// u is dropped from F: every supersequence of v's paths is one of u's, so the state with and
// without u have the same completions, of the same lengths and the same copies of each
// symbol. (Two nodes never dominate each other: equal path sets are the same node.)
//
// Forced moves. When some symbol a is wanted next by every node of F whose paths hold an a,
// some shortest completion starts with a: take any completion T = u a v, u free of a; then
// a u v completes too (a path starting with a matches the first a, and the rest of it matched
// inside v before; a path without a matched inside u v already) and has the same length and
// the same copies of every symbol. So from such a state only the move on a (the smallest such
// symbol) is generated. By induction on the remaining optimal length, every state still has a
// shortest completion in this reduced graph, also within per-symbol budgets.
//
// Determinism: symbols are renumbered in increasing cell order, nodes are numbered in a fixed
// order, and every search tries its moves in a fixed order.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <unordered_map>
#include <vector>

#include "base/check.h"
#include "bounds/projection.h"

namespace raycell::scs {

using Symbol = std::uint32_t;
using Node = std::uint32_t;
using StateId = std::uint32_t;
using Frontier = std::vector<Node>;
constexpr StateId kNoState = std::numeric_limits<StateId>::max();
constexpr Symbol kNoSymbol = std::numeric_limits<Symbol>::max();

inline std::uint64_t Mix(std::uint64_t x) {  // splitmix64's finalizer
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

inline std::uint64_t HashValues(const std::uint32_t* v, std::size_t n, std::uint64_t seed = 0) {
  std::uint64_t h = Mix(seed + n);
  for (std::size_t i = 0; i < n; ++i) h = Mix(h ^ v[i]);
  return h;
}

struct VectorHash {
  std::size_t operator()(const std::vector<std::uint32_t>& v) const {
    return HashValues(v.data(), v.size());
  }
};

inline std::uint64_t HashOf(const std::vector<std::uint32_t>& v) {
  return HashValues(v.data(), v.size());
}

// The strings as a DAG of merged trie subtrees, with the tables the heuristics read.
class Dag {
 public:
  explicit Dag(const std::vector<CellString>& input);

  std::uint32_t symbols() const { return k_; }
  CellId cell(Symbol a) const { return cells_[a]; }
  const std::vector<CellId>& cells() const { return cells_; }
  Symbol Dense(CellId c) const {
    const auto it = std::lower_bound(cells_.begin(), cells_.end(), c);
    return it != cells_.end() && *it == c ? static_cast<Symbol>(it - cells_.begin()) : kNoSymbol;
  }
  std::size_t strings() const { return strings_; }
  std::size_t size() const { return symbol_.size(); }
  const Frontier& start() const { return start_; }
  Symbol symbol(Node v) const { return symbol_[v]; }
  const Node* children_begin(Node v) const { return children_.data() + child_begin_[v]; }
  const Node* children_end(Node v) const { return children_.data() + child_begin_[v + 1]; }
  std::uint32_t height(Node v) const { return height_[v]; }
  // Most copies of symbol a on one path of v.
  const std::uint32_t* need(Node v) const { return need_.data() + std::size_t{v} * k_; }
  // Copies of symbol a over all the strings.
  std::uint32_t total(Symbol a) const { return total_[a]; }

  // True when every path of u is a subsequence of some path of v (memoised).
  bool Covered(Node u, Node v) const {
    if (height_[u] > height_[v] || (mask_[u] & ~mask_[v]) != 0) return false;
    if (dense_) {
      const std::size_t at = std::size_t{u} * size() + v;
      const std::uint8_t known = (covered_bits_[at / 4] >> (2 * (at % 4))) & 3;
      if (known != 0) return known == 2;
      const bool all = CoveredSlow(u, v);
      covered_bits_[at / 4] |= static_cast<std::uint8_t>((all ? 2 : 1) << (2 * (at % 4)));
      return all;
    }
    const std::uint64_t key = (std::uint64_t{u} << 32) | v;
    const auto it = covered_.find(key);
    if (it != covered_.end()) return it->second;
    const bool all = CoveredSlow(u, v);
    covered_.emplace(key, all);
    return all;
  }

 private:
  bool CoveredSlow(Node u, Node v) const;
  void Build(const std::vector<CellString>& strings);
  void Add(const std::vector<std::uint32_t>& key);
  // Calls fn(path) for every path of v until fn returns false; false if it did.
  template <typename F>
  bool ForEachPath(Node v, std::vector<Symbol>& path, F fn) const;

  // Whether p is a subsequence of some path of v: reach(i, w) = p[i..] embeds in a path of w.
  bool Embeds(const std::vector<Symbol>& p, Node v) const;

  std::vector<CellId> cells_;
  std::uint32_t k_ = 0;
  std::size_t strings_ = 0;
  std::vector<Symbol> symbol_;
  std::vector<std::uint32_t> child_begin_;
  std::vector<Node> children_;
  std::vector<std::uint32_t> height_;
  std::vector<std::uint64_t> mask_;  // bit a % 64 set when a path of the node holds symbol a
  std::vector<std::uint32_t> need_;
  std::vector<std::uint32_t> total_;
  Frontier start_;
  // Covered's answers: 2 bits per (u, v) pair (0 unknown, 1 no, 2 yes) while the DAG has at
  // most kDenseNodes nodes, else a hash table.
  static constexpr std::size_t kDenseNodes = 8192;
  bool dense_ = false;
  mutable std::vector<std::uint8_t> covered_bits_;
  mutable std::unordered_map<std::uint64_t, bool> covered_;
};

// Frontiers (plus any extra values) stored once each, in creation order, with a hash table.
class StateStore {
 public:
  std::size_t size() const { return begin_.size(); }
  std::size_t bytes() const {
    return values_.size() * 4 + begin_.size() * 16 + table_.size() * sizeof(StateId);
  }
  void GetInto(StateId s, std::vector<std::uint32_t>& out) const {
    out.assign(values_.begin() + begin_[s], values_.begin() + End(s));
  }
  StateId Find(const std::vector<std::uint32_t>& key, std::uint64_t hash) const {
    if (table_.empty()) return kNoState;
    for (std::size_t i = hash & (table_.size() - 1);; i = (i + 1) & (table_.size() - 1)) {
      const StateId s = table_[i];
      if (s == kNoState) return kNoState;
      if (hash_[s] == hash && End(s) - begin_[s] == key.size() &&
          std::equal(key.begin(), key.end(), values_.begin() + begin_[s])) {
        return s;
      }
    }
  }
  StateId Add(const std::vector<std::uint32_t>& key, std::uint64_t hash) {
    RAYCELL_CHECK_LT(size(), std::size_t{kNoState});
    const auto s = static_cast<StateId>(size());
    begin_.push_back(values_.size());
    values_.insert(values_.end(), key.begin(), key.end());
    hash_.push_back(hash);
    if (2 * size() > table_.size()) Rehash(std::max<std::size_t>(1024, 2 * table_.size()));
    Place(s);
    return s;
  }

 private:
  std::size_t End(StateId s) const {
    return std::size_t{s} + 1 < begin_.size() ? begin_[s + 1] : values_.size();
  }
  void Place(StateId s) {
    std::size_t i = hash_[s] & (table_.size() - 1);
    while (table_[i] != kNoState) i = (i + 1) & (table_.size() - 1);
    table_[i] = s;
  }
  void Rehash(std::size_t slots) {
    table_.assign(slots, kNoState);
    for (StateId s = 0; s < size(); ++s) Place(s);
  }

  std::vector<std::uint32_t> values_;
  std::vector<std::size_t> begin_;
  std::vector<std::uint64_t> hash_;
  std::vector<StateId> table_;
};

}  // namespace raycell::scs
