#include "graph/links.h"

#include <algorithm>
#include <array>
#include <boost/graph/graphviz.hpp>
#include <numeric>
#include <ostream>
#include <utility>

#include "base/check.h"

namespace raycell {

std::ostream& operator<<(std::ostream& out, const Link& link) { return out << link.ToString(); }

// ---------------------------------------------------------------------- schedule groups

std::vector<std::int64_t> ScheduleGroups(const CellTree& tree,
                                         const std::vector<CellId>& schedule) {
  std::vector<std::vector<NodeId>> ready(tree.cell_count());
  const auto make_ready = [&](NodeId p) {
    for (NodeId c = tree.first_child(p); c != kNoNode; c = tree.next_sibling(c)) {
      ready[tree.cell(c).value()].push_back(c);
    }
  };
  std::vector<std::int64_t> fetch(tree.size(), -1);
  make_ready(kRootNode);
  std::vector<NodeId> batch;
  for (std::size_t i = 0; i < schedule.size(); ++i) {
    const CellId c = schedule[i];
    if (c.value() >= tree.cell_count()) continue;
    batch.clear();
    std::swap(batch, ready[c.value()]);  // processing c's nodes makes no node of c ready
    for (NodeId n : batch) fetch[n.index()] = static_cast<std::int64_t>(i), make_ready(n);
  }
  return fetch;
}

std::vector<Link> LinksOf(const CellTree& tree, const std::vector<CellId>& schedule) {
  const std::vector<std::int64_t> fetch = ScheduleGroups(tree, schedule);
  std::vector<std::pair<std::int64_t, NodeId>> by_fetch;  // (fetch, node), processed nodes
  for (NodeId n : tree.nodes()) {
    if (fetch[n.index()] >= 0) by_fetch.emplace_back(fetch[n.index()], n);
  }
  std::sort(by_fetch.begin(), by_fetch.end());
  std::vector<Link> links;
  for (std::size_t i = 1; i < by_fetch.size(); ++i) {
    if (by_fetch[i - 1].first == by_fetch[i].first) {
      links.push_back({by_fetch[i - 1].second, by_fetch[i].second});
    }
  }
  std::sort(links.begin(), links.end());
  return links;
}

// -------------------------------------------------------------------------- contraction

namespace {

void CheckLink(const CellTree& tree, const Link& l) {
  RAYCELL_CHECK_LT(l.a, l.b);
  RAYCELL_CHECK_LT(kRootNode, l.a);
  RAYCELL_CHECK_LT(l.b.index(), tree.size());
  RAYCELL_CHECK_EQ(tree.cell(l.a), tree.cell(l.b));
}

// Union-find with path halving; the representative of a class is not its smallest node.
struct UnionFind {
  std::vector<NodeId> up;
  explicit UnionFind(std::size_t n) : up(n) {
    for (std::size_t i = 0; i < n; ++i) up[i] = NodeId(static_cast<std::uint32_t>(i));
  }
  NodeId Find(NodeId x) {
    while (up[x.index()] != x) x = up[x.index()] = up[up[x.index()].index()];
    return x;
  }
  void Unite(NodeId x, NodeId y) { up[Find(x).index()] = Find(y); }
};

}  // namespace

Contraction ContractLinks(const CellTree& tree, const std::vector<Link>& links) {
  UnionFind uf(tree.size());
  for (const Link& l : links) CheckLink(tree, l), uf.Unite(l.a, l.b);
  std::vector<std::uint32_t> class_of(tree.size(), Contraction::kNoClass);
  std::vector<std::uint32_t> class_of_root(tree.size(), Contraction::kNoClass);
  std::vector<CellId> class_cell;
  for (NodeId n : tree.nodes()) {
    std::uint32_t& k = class_of_root[uf.Find(n).index()];
    if (k == Contraction::kNoClass) {
      k = static_cast<std::uint32_t>(class_cell.size());
      class_cell.push_back(tree.cell(n));
    }
    class_of[n.index()] = k;
  }
  std::vector<std::uint32_t> partition = class_of;
  if (!partition.empty()) partition[kRootNode.index()] = 0;  // ignored by QuotientGraph
  // Built in place: copying an adjacency_list trips GCC 12's -Wmaybe-uninitialized in Boost.
  return Contraction{QuotientGraph(tree, partition, class_cell.size()), std::move(class_of),
                     std::move(class_cell)};
}

bool LinksFeasible(const CellTree& tree, const std::vector<Link>& links) {
  return IsAcyclic(ContractLinks(tree, links).graph);
}

std::optional<std::vector<CellId>> ScheduleFromLinks(const CellTree& tree,
                                                     const std::vector<Link>& links) {
  const Contraction k = ContractLinks(tree, links);
  const auto order = TopologicalOrder(k.graph);
  if (!order) return std::nullopt;
  std::vector<CellId> schedule;
  schedule.reserve(order->size());
  for (DependencyVertex v : *order) schedule.push_back(k.class_cell[v]);
  return schedule;
}

bool Conflict(const CellTree& tree, const Link& l1, const Link& l2) {
  return !LinksFeasible(tree, {l1, l2});
}

// ---------------------------------------------------------------------------- candidates

namespace {

// ancestors[n]: bit m - 1 set for every proper ancestor m != root of n. Needs <= 64 nodes;
// parent(n) < n, so one pass in id order suffices.
std::vector<std::uint64_t> AncestorBits(const CellTree& tree) {
  std::vector<std::uint64_t> anc(tree.size(), 0);
  for (NodeId n : tree.nodes()) {
    const NodeId p = tree.parent(n);
    if (p != kRootNode) anc[n.index()] = anc[p.index()] | (std::uint64_t{1} << (p.index() - 1));
  }
  return anc;
}

bool IsAncestor(const std::vector<std::uint64_t>& anc, NodeId u, NodeId v) {
  return (anc[v.index()] >> (u.index() - 1)) & 1u;
}

bool Related(const std::vector<std::uint64_t>& anc, NodeId u, NodeId v) {
  return IsAncestor(anc, u, v) || IsAncestor(anc, v, u);
}

// Conflict of two distinct candidate links (each feasible alone: no ancestor pair inside).
// A cycle of the contraction must pass through a merged class, since the tree is acyclic.
// Sharing an end, the links make one class {x, y, z}; a cycle in it is a tree path between
// two members, and only the pair of the two unshared ends can be related. Disjoint, classes
// X and Y: a cycle through only one of them is again an ancestor pair inside a link, so it
// must run X ~> Y ~> X along tree paths, i.e. some x is an ancestor of some y and some y of
// some x; conversely such paths close a walk X -> ... -> Y -> ... -> X, which holds a cycle.
bool CandidatesConflict(const std::vector<std::uint64_t>& anc, const Link& l1, const Link& l2) {
  const std::array<NodeId, 2> x{l1.a, l1.b}, y{l2.a, l2.b};
  for (NodeId s : x) {
    for (NodeId t : y) {
      if (s != t) continue;
      return Related(anc, s == l1.a ? l1.b : l1.a, t == l2.a ? l2.b : l2.a);
    }
  }
  bool down = false, up = false;
  for (NodeId s : x) {
    for (NodeId t : y) down |= IsAncestor(anc, s, t), up |= IsAncestor(anc, t, s);
  }
  return down && up;
}

}  // namespace

std::string LinkCandidates::ToString() const {
  return std::to_string(links.size()) + " candidate links, " + std::to_string(conflicts.size()) +
         " conflicts";
}

LinkCandidates CandidateLinks(const CellTree& tree) {
  if (tree.node_count() > kMaxCandidateNodes) {
    throw InputError("CandidateLinks: the tree has " + std::to_string(tree.node_count()) +
                     " nodes; at most " + std::to_string(kMaxCandidateNodes) +
                     " are supported (every pair of candidate links is compared)");
  }
  const std::vector<std::uint64_t> anc = AncestorBits(tree);
  LinkCandidates out;
  for (NodeId a : tree.nodes()) {
    for (NodeId b(a.index() + 1); b.index() < tree.size(); b = NodeId(b.index() + 1)) {
      if (tree.cell(a) == tree.cell(b) && !Related(anc, a, b)) out.links.push_back({a, b});
    }
  }
  for (std::size_t i = 0; i < out.links.size(); ++i) {
    for (std::size_t j = i + 1; j < out.links.size(); ++j) {
      if (CandidatesConflict(anc, out.links[i], out.links[j])) out.conflicts.emplace_back(i, j);
    }
  }
  return out;
}

// -------------------------------------------------------------------------------- dot

namespace {

struct DotEdge {
  bool link = false;
};
using DotGraph =
    boost::adjacency_list<boost::vecS, boost::vecS, boost::directedS, boost::no_property, DotEdge>;

// Colorbrewer "Set3" (12 pastel colours, readable black text).
constexpr std::array<const char*, 12> kPalette = {"#8dd3c7", "#ffffb3", "#bebada", "#fb8072",
                                                  "#80b1d3", "#fdb462", "#b3de69", "#fccde5",
                                                  "#d9d9d9", "#bc80bd", "#ccebc5", "#ffed6f"};

struct VertexWriter {
  const CellTree* tree;
  void operator()(std::ostream& out, DependencyVertex v) const {
    const NodeId n = NodeOf(v);
    out << "[label=\"cell" << tree->cell(n) << " g" << tree->generation(n) << " e" << tree->enter(n)
        << "\", fillcolor=\"" << kPalette[tree->cell(n).value() % kPalette.size()] << "\"]";
  }
};

struct EdgeWriter {
  const DotGraph* graph;
  void operator()(std::ostream& out, DotGraph::edge_descriptor e) const {
    out << ((*graph)[e].link ? "[style=dashed, dir=none, constraint=false]" : "[style=solid]");
  }
};

struct GraphWriter {
  void operator()(std::ostream& out) const { out << "node [style=filled, shape=box];\n"; }
};

}  // namespace

// GCC 12 reports a false -Wmaybe-uninitialized in Boost 1.74's edge iterator (a
// boost::optional) once write_graphviz is inlined here.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
void WriteDot(std::ostream& out, const CellTree& tree, const std::vector<Link>& links) {
  DotGraph g(tree.node_count());
  for (NodeId n : tree.nodes()) {
    if (tree.parent(n) != kRootNode) boost::add_edge(VertexOf(tree.parent(n)), VertexOf(n), g);
  }
  for (const Link& l : links) {
    CheckLink(tree, l);
    boost::add_edge(VertexOf(l.a), VertexOf(l.b), DotEdge{true}, g);
  }
  std::vector<std::uint32_t> ids(tree.node_count());  // vertex v is node v + 1 (VertexOf)
  std::iota(ids.begin(), ids.end(), 1u);
  const auto id_map = boost::make_iterator_property_map(ids.begin(), get(boost::vertex_index, g));
  boost::write_graphviz(out, g, VertexWriter{&tree}, EdgeWriter{&g}, GraphWriter{}, id_map);
}
#pragma GCC diagnostic pop

}  // namespace raycell
