// Cache-saving links and conflicts (docs/design.md §1 "Cache-saving links and conflicts").
//
// A schedule groups the tree's nodes into fetches; two nodes of one cell processed by the
// same fetch share that fetch and are joined by a cache-saving link. A group of k nodes is
// described by k - 1 links (a chain through its nodes in id order, a spanning set), so for a
// feasible schedule in which every fetch processes at least one node
//     fetches = nodes - links.
// In general "links" counts the nodes merged: nodes - (classes of the link partition).
//
// A set of links is feasible when contracting the linked nodes (union-find over the links,
// one vertex per class) leaves the dependency graph acyclic (LinksFeasible).
//
// Why acyclic contraction <=> some schedule realises every link. Here a schedule entry
// processes a chosen set of the ready nodes of its cell (it may leave some for a later
// fetch of that cell); "realises" means both ends of every link are processed by one fetch.
//  (<=) Take a topological order of the classes and fetch one class per entry, in that
//       order, processing exactly that class. A class's nodes all have one cell (links join
//       nodes of one cell); their parents lie in other classes (a child never has its
//       parent's cell), which come earlier in the order, so every node is ready when its
//       class is fetched, every node is processed once, and linked nodes share a fetch.
//  (=>) Let f(n) be the fetch that processes n. A tree edge p -> n gives f(p) < f(n) and a
//       link a - b gives f(a) = f(b), so f is constant on classes and strictly increases
//       along every edge of the contracted graph; a cycle K -> ... -> K would give
//       f(K) < f(K).
// Under docs/design.md's greedy run (RunSchedule: an entry processes *every* ready node of its
// cell) (=>) still holds, so the links of any schedule (LinksOf) are feasible, but (<=) does
// not: greedy processing can be forced to separate linked nodes. Paths A B and C A B D B:
// nodes A1 B2 / C3 A4 B5 D6 B7, links {A1, A4} and {B2, B7}. The contraction is acyclic (C3,
// {A1 A4}, B5, D6, {B2 B7}), but greedily the fetch that processes A1 and A4 makes B2 and B5
// ready together, so B2 is always processed before B7 (tested in links_test). What survives,
// and what matters for optimal schedules: the cells of a topological order of the classes
// (ScheduleFromLinks) run greedily are feasible with at most (classes) useful fetches, since
// greedy processes every node no later than its class's entry. So the fewest fetches is
// nodes - (the most nodes merged by a feasible set of links) under both rules.
#pragma once

#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "graph/cell_tree.h"
#include "graph/dependency_graph.h"

namespace raycell {

// A cache-saving link between two distinct nodes of the same cell, a < b (neither the root).
// Functions taking links CHECK this.
struct Link {
  NodeId a{0}, b{0};
  static Link Create(NodeId x, NodeId y) { return x < y ? Link{x, y} : Link{y, x}; }
  std::string ToString() const {
    return std::to_string(a.index()) + "-" + std::to_string(b.index());
  }
  friend bool operator==(const Link& l, const Link& r) { return l.a == r.a && l.b == r.b; }
  friend bool operator!=(const Link& l, const Link& r) { return !(l == r); }
  friend bool operator<(const Link& l, const Link& r) { return l.a != r.a ? l.a < r.a : l.b < r.b; }
};
std::ostream& operator<<(std::ostream& out, const Link& link);

// Runs `schedule` with RunSchedule's greedy rule and returns, per node id, the index of the
// schedule entry that processed it; -1 for the root and for nodes never processed.
std::vector<std::int64_t> ScheduleGroups(const CellTree& tree, const std::vector<CellId>& schedule);

// The links `schedule` implies: for each fetch, its nodes in id order joined as a chain
// (k nodes give k - 1 links). Sorted by (a, b).
std::vector<Link> LinksOf(const CellTree& tree, const std::vector<CellId>& schedule);

// The dependency graph with linked nodes merged (see QuotientGraph).
struct Contraction {
  DependencyGraph graph;                // one vertex per class
  std::vector<std::uint32_t> class_of;  // per node id; class_of[kRootNode] = kNoClass
  std::vector<CellId> class_cell;       // the cell of each class's nodes
  static constexpr std::uint32_t kNoClass = 0xffffffffu;
  std::size_t classes() const { return class_cell.size(); }
};
// Classes are numbered by their smallest node id, so the result is deterministic.
Contraction ContractLinks(const CellTree& tree, const std::vector<Link>& links);

// True iff the contraction is acyclic: some schedule realises every link (see above).
bool LinksFeasible(const CellTree& tree, const std::vector<Link>& links);

// When the links are feasible, the cells of a topological order of the classes: one fetch per
// class. Run greedily (RunSchedule) it is feasible with at most classes() useful fetches.
std::optional<std::vector<CellId>> ScheduleFromLinks(const CellTree& tree,
                                                     const std::vector<Link>& links);

// Two links conflict when no schedule realises both: !LinksFeasible({l1, l2}).
bool Conflict(const CellTree& tree, const Link& l1, const Link& l2);

// Every link the tree admits, and the conflicting pairs among them.
//
// Candidates are the pairs of distinct nodes of one cell neither of which is an ancestor of
// the other. An ancestor-descendant link is never feasible: a child never has its parent's
// cell, so the tree path a -> m1 -> ... -> mk -> b has k >= 1 intermediate nodes of other
// cells, which stay outside the class {a, b}; contracting gives the cycle
// {a, b} -> m1 -> ... -> mk -> {a, b}. (Siblings never share a cell: each node has at most one
// child per cell.)
//
// Conflicts compare every pair of candidates, in O(1) each with ancestor bit sets (see
// links.cpp; tested against Conflict), so the tree may have at most kMaxCandidateNodes nodes.
inline constexpr std::size_t kMaxCandidateNodes = 64;
struct LinkCandidates {
  std::vector<Link> links;                                     // sorted by (a, b)
  std::vector<std::pair<std::size_t, std::size_t>> conflicts;  // indices i < j into links
  // "12 candidate links, 3 conflicts".
  std::string ToString() const;
};
// Throws InputError when the tree has more than kMaxCandidateNodes nodes.
LinkCandidates CandidateLinks(const CellTree& tree);

// The tree as a Graphviz digraph via boost::write_graphviz: one node per tree node except the
// root, named by its id, labelled "cellC gG eE" (cell, generation, enter) and filled with one
// colour per cell (a fixed palette of 12, cycling); tree edges solid, parent -> child; each
// link one dashed edge with dir=none, constraint=false. Deterministic.
void WriteDot(std::ostream& out, const CellTree& tree, const std::vector<Link>& links = {});

}  // namespace raycell
