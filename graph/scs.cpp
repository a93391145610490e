#include "graph/scs.h"

#include <algorithm>
#include <functional>
#include <iterator>
#include <limits>
#include <map>
#include <queue>
#include <sstream>
#include <unordered_map>
#include <utility>

#include "base/check.h"

// Why the answers are proofs.
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
// Heuristics (each a lower bound on the moves still needed, and consistent: one move lowers
// it by at most one).
//  - hl: the longest path of a node of F. Each move advances a path by at most one symbol.
//  - hc: the sum over symbols a of the most copies of a on one path of a node of F. A move on
//    a removes at most one a from each path and changes no other symbol's term; moves on
//    different symbols are different moves.
// h = max(hl, hc), a maximum of consistent heuristics, is consistent, and h = 0 at the end.
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
// The budget search is a depth-first search over (F, copies used so far) with the forced
// moves and dominated nodes above, cut when some symbol needs more copies than its budget
// leaves (hc per symbol) or the remaining budget in total is below hl; a state is remembered
// only once its whole subtree failed, so meeting it again (same F, same copies used) fails.
//
// Determinism: symbols are renumbered in increasing cell order, nodes are numbered in a fixed
// order, moves are tried in a fixed order and the open list is ordered by (f, larger g first,
// creation order).

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

namespace {

using Symbol = std::uint32_t;
using Node = std::uint32_t;
using StateId = std::uint32_t;
using Frontier = std::vector<Node>;
constexpr StateId kNoState = std::numeric_limits<StateId>::max();
constexpr Symbol kNoSymbol = std::numeric_limits<Symbol>::max();

std::uint64_t Mix(std::uint64_t x) {  // splitmix64's finalizer
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

std::uint64_t HashValues(const std::uint32_t* v, std::size_t n, std::uint64_t seed = 0) {
  std::uint64_t h = Mix(seed + n);
  for (std::size_t i = 0; i < n; ++i) h = Mix(h ^ v[i]);
  return h;
}

struct VectorHash {
  std::size_t operator()(const std::vector<std::uint32_t>& v) const {
    return HashValues(v.data(), v.size());
  }
};

// The strings as a DAG of merged trie subtrees, with the tables the heuristics read.
class Dag {
 public:
  explicit Dag(const std::vector<CellString>& input) {
    const std::vector<CellString> strings = RemoveDominated(input);
    for (const CellString& s : strings) cells_.insert(cells_.end(), s.begin(), s.end());
    std::sort(cells_.begin(), cells_.end());
    cells_.erase(std::unique(cells_.begin(), cells_.end()), cells_.end());
    k_ = static_cast<std::uint32_t>(cells_.size());
    Build(strings);
  }

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
  bool CoveredSlow(Node u, Node v) const {
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

  void Build(const std::vector<CellString>& strings) {
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

  void Add(const std::vector<std::uint32_t>& key) {
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

  // Calls fn(path) for every path of v until fn returns false; false if it did.
  template <typename F>
  bool ForEachPath(Node v, std::vector<Symbol>& path, F fn) const {
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

  // Whether p is a subsequence of some path of v: reach(i, w) = p[i..] embeds in a path of w.
  bool Embeds(const std::vector<Symbol>& p, Node v) const {
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

// What a state's frontier says: its heuristic, its forced move, and per symbol the most copies
// one remaining path needs.
struct Eval {
  std::uint32_t h = 0;
  std::uint32_t hl = 0;
  Symbol forced = kNoSymbol;
  std::vector<std::uint32_t> need;
  std::vector<std::uint32_t> parts;  // remaining SCS of each part (PartTable)
};

// A group of symbols P and, for every node v, the projection onto P of v's paths (as the id of
// a set of strings without dominated ones). The remaining SCS of P at a frontier F is the SCS
// of the union of its nodes' projections, memoised by the set of ids.
//
// Why adding it up is a consistent heuristic: the projection onto P of a completion of F is a
// common supersequence of F's projections onto P, so the moves on symbols of P still needed
// are at least that SCS, and for disjoint groups these are different moves (plus, for the
// symbols in no group, hc's terms). A move on a symbol outside P replaces nodes whose symbol is
// not in P by their children, which have the same projections together: the term is
// unchanged. A move on a in P leaves each remaining projected string as it was or one symbol
// shorter at its front, so the remaining strings are subsequences of what P's own move on a
// leaves, whose SCS is at least the old one minus one. So a move lowers the sum by at most
// one. A sub-search stopped by its limit gives a smaller (still admissible) value.
class PartTable {
 public:
  // sub_states: per sub-search; total_states: all sub-searches of this table together (states
  // stored), after which new sets get hc's terms instead (max copies of each symbol of P on
  // one remaining string, a weaker but still admissible value; A* stays correct with an
  // admissible h that is not consistent, as it reopens states, see above).
  PartTable(const Dag& dag, std::vector<Symbol> part, std::uint64_t sub_states,
            std::uint64_t total_states = std::numeric_limits<std::uint64_t>::max())
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

  const std::vector<Symbol>& part() const { return part_; }

  // Declared here, defined after AStar, which it runs.
  std::uint32_t Remaining(const Frontier& f);

 private:
  std::uint32_t Intern(std::vector<CellString> set) {
    std::vector<std::uint32_t> flat;
    for (const CellString& s : set) {
      flat.insert(flat.end(), s.begin(), s.end());
      flat.push_back(kNoCell);
    }
    auto [it, inserted] = ids_.emplace(flat, static_cast<std::uint32_t>(sets_.size()));
    if (inserted) sets_.push_back(std::move(set));
    return it->second;
  }

  const Dag& dag_;
  std::vector<Symbol> part_;
  std::uint64_t sub_states_;
  std::uint64_t left_;  // states the sub-searches may still store
  std::vector<std::uint32_t> phi_;
  std::vector<std::vector<CellString>> sets_;
  std::unordered_map<std::vector<std::uint32_t>, std::uint32_t, VectorHash> ids_, memo_;
  std::vector<std::uint32_t> key_;
};

class Moves {
 public:
  // `parts` (may be null): disjoint groups of symbols whose remaining SCS is added up in h.
  Moves(const Dag& dag, std::vector<PartTable>* parts = nullptr)
      : dag_(dag), parts_(parts), blocked_(dag.symbols()), present_(dag.symbols()) {}

  Eval Evaluate(const Frontier& f);
  void EvaluateInto(const Frontier& f, Eval& e);  // the same, reusing e's memory
  const std::vector<PartTable>* parts() const { return parts_; }

  // The symbols of the frontier's nodes, increasing, into `out`.
  void SymbolsInto(const Frontier& f, std::vector<Symbol>& out) {
    std::fill(present_.begin(), present_.end(), 0);
    for (Node v : f) present_[dag_.symbol(v)] = 1;
    out.clear();
    for (Symbol a = 0; a < dag_.symbols(); ++a) {
      if (present_[a]) out.push_back(a);
    }
  }

  // The frontier after a move on a, into `out` (not f), reusing its memory: nodes of a
  // replaced by their children, sorted, without duplicates and dominated nodes.
  void MoveInto(const Frontier& f, Symbol a, Frontier& out) const {
    // f has no dominated node; only pairs with a new node (a child) need a test.
    olds_.clear();
    news_.clear();
    for (Node v : f) {
      if (dag_.symbol(v) != a) {
        olds_.push_back(v);  // increasing, as f
      } else {
        news_.insert(news_.end(), dag_.children_begin(v), dag_.children_end(v));
      }
    }
    std::sort(news_.begin(), news_.end());
    news_.erase(std::unique(news_.begin(), news_.end()), news_.end());
    // A child that is also an old node stays an old one.
    fresh_.clear();
    std::set_difference(news_.begin(), news_.end(), olds_.begin(), olds_.end(),
                        std::back_inserter(fresh_));
    Reduce(olds_, fresh_, out);
  }

  Frontier WithoutDominated(Frontier f) const {
    std::sort(f.begin(), f.end());
    f.erase(std::unique(f.begin(), f.end()), f.end());
    Frontier out;
    Reduce({}, f, out);
    return out;
  }

 private:
  // olds and news (disjoint, each increasing) without the nodes dominated by another; two old
  // nodes are known not to dominate each other. Dominance is a strict partial order (see
  // above), so a node dominated by a dropped node is dominated by a kept one too, and each
  // test can look at the whole set.
  void Reduce(const std::vector<Node>& olds, const std::vector<Node>& news, Frontier& out) const {
    kept_old_.clear();
    kept_new_.clear();
    for (Node o : olds) {
      bool dominated = false;
      for (Node n : news) {
        if (dag_.Covered(o, n)) {
          dominated = true;
          break;
        }
      }
      if (!dominated) kept_old_.push_back(o);
    }
    for (Node n : news) {
      bool dominated = false;
      for (Node y : olds) {
        if (dag_.Covered(n, y)) {
          dominated = true;
          break;
        }
      }
      for (std::size_t i = 0; i < news.size() && !dominated; ++i) {
        dominated = news[i] != n && dag_.Covered(n, news[i]);
      }
      if (!dominated) kept_new_.push_back(n);
    }
    out.resize(kept_old_.size() + kept_new_.size());
    std::merge(kept_old_.begin(), kept_old_.end(), kept_new_.begin(), kept_new_.end(), out.begin());
  }

  const Dag& dag_;
  std::vector<PartTable>* parts_;
  std::vector<char> blocked_, present_;
  mutable std::vector<Node> olds_, news_, fresh_, kept_old_, kept_new_;  // scratch
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

std::uint64_t HashOf(const std::vector<std::uint32_t>& v) { return HashValues(v.data(), v.size()); }

// One step of lookahead: the forced symbol if any, else the move whose result has the smallest
// h, then the one that removes the most path length, then the smallest symbol.
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

  ScsResult Run() {
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

 private:
  StateId Add(const Frontier& f, std::uint32_t g, std::uint32_t h, StateId parent, Symbol move) {
    const StateId s = store_.Add(f, HashOf(f));
    g_.push_back(g), h_.push_back(h), parent_.push_back(parent), move_.push_back(move);
    return s;
  }
  CellString Path(StateId s) const {
    CellString out;
    for (; parent_[s] != kNoState; s = parent_[s]) out.push_back(dag_.cell(move_[s]));
    std::reverse(out.begin(), out.end());
    return out;
  }
  static ScsResult Exact(ScsResult r, std::uint32_t length) {
    r.exact = true;
    r.lower_bound = r.upper_bound = length;
    return r;
  }

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

// Depth-first search for a common supersequence within per-symbol budgets.
class BudgetSearch {
 public:
  BudgetSearch(const Dag& dag, std::vector<std::uint32_t> budget, const ScsLimits& limits,
               std::vector<PartTable>* parts = nullptr)
      : dag_(dag), moves_(dag, parts), budget_(std::move(budget)), limits_(limits) {}

  BudgetResult Run() {
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

 private:
  enum Outcome { kFound, kFail, kStopped };

  Outcome Search(const Frontier& f, std::vector<std::uint32_t>& used, std::uint64_t left) {
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

// Disjoint groups of symbols for the heuristic (PartTable). First pairs: each pair's SCS at the
// start minus its two maxima is its gain; pairs are taken greedily, the largest gain first
// (then the smaller symbols), while both symbols are free. Then, with at least kMergeSymbols
// symbols, parts (the pairs and the symbols left alone) are merged two at a time, up to
// kMostPartSymbols symbols a part: the merge whose union's SCS at the start exceeds the sum of
// the two parts' values the most (then the first in part order), while some merge gains. The
// sum of disjoint parts' remaining SCS is admissible and consistent for any partition (see
// PartTable), so merging only changes how strong h is: a union's SCS is at least the sum of
// its parts' (a supersequence restricted to each part is one of the part's projections), so
// at the start h never drops, and the merges chosen raise it. Only for 4 to kMostSymbols
// symbols.
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

}  // namespace

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
    RAYCELL_CHECK_LT(std::size_t{dag.cell(a)}, budget.size());
    dense[a] = budget[dag.cell(a)];
  }
  return BudgetSearch(dag, std::move(dense), limits, &in_->parts).Run();
}

ScsResult ShortestCommonSupersequence(const std::vector<CellString>& strings,
                                      const ScsLimits& limits) {
  return ScsSolver(strings).Shortest(limits);
}

}  // namespace raycell
