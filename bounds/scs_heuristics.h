// The searches' heuristics over the string DAG (bounds/string_dag.h): what a frontier still
// needs (Eval), the moves from a frontier (Moves), the remaining SCS of groups of symbols
// (PartTable) and the greedy supersequence the searches start from. Internal to bounds/.
//
// Why the answers are proofs, continued from string_dag.h:
// Heuristics (each a lower bound on the moves still needed, and consistent: one move lowers
// it by at most one).
//  - hl: the longest path of a node of F. Each move advances a path by at most one symbol.
//  - hc: the sum over symbols a of the most copies of a on one path of a node of F. A move on
//    a removes at most one a from each path and changes no other symbol's term; moves on
//    different symbols are different moves.
// h = max(hl, hc), a maximum of consistent heuristics, is consistent, and h = 0 at the end.
// A sum over disjoint groups of symbols of their remaining SCS (PartTable) is admissible and
// consistent as well; h is the largest of these.
#pragma once

#include <algorithm>
#include <cstdint>
#include <iterator>
#include <limits>
#include <unordered_map>
#include <vector>

#include "bounds/string_dag.h"

namespace raycell::scs {

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
            std::uint64_t total_states = std::numeric_limits<std::uint64_t>::max());

  const std::vector<Symbol>& part() const { return part_; }

  // The remaining SCS of P at frontier f (an A* run per new set of projections, memoised).
  std::uint32_t Remaining(const Frontier& f);

 private:
  std::uint32_t Intern(std::vector<CellString> set);

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

// A common supersequence by one step of lookahead: the forced symbol if any, else the move whose
// result has the smallest h, then the one that removes the most path length, then the smallest
// symbol.
CellString Greedy(const Dag& dag, Moves& moves);

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
                                   std::uint64_t sub_states, bool merge);

}  // namespace raycell::scs
