// The dependency graph of a Cell Tree in Boost.Graph (docs/design.md §1 "Cache-saving links and
// conflicts"): one vertex per tree node except the virtual root, one edge parent -> child
// per tree edge (edges from the root are dropped: the root is always done). A node's work
// can be done only after its parent's, so any order of work is a topological order.
//
// Vertex v stands for node v + 1 (VertexOf / NodeOf). A quotient graph has one vertex per
// class of a partition of the nodes instead; links.h builds those from cache-saving links.
#pragma once

#include <boost/graph/adjacency_list.hpp>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "graph/cell_tree.h"

namespace raycell {

using DependencyGraph = boost::adjacency_list<boost::vecS, boost::vecS, boost::directedS>;
using DependencyVertex = DependencyGraph::vertex_descriptor;

inline DependencyVertex VertexOf(NodeId n) { return DependencyVertex{n.index()} - 1; }
inline NodeId NodeOf(DependencyVertex v) { return NodeId(static_cast<std::uint32_t>(v + 1)); }

// The tree's own dependency graph: vertex VertexOf(n) per node n != root, tree edges.
DependencyGraph BuildDependencyGraph(const CellTree& tree);

// The quotient by a partition of the nodes: class_of[n] in [0, classes) for every node
// n != root (class_of[kRootNode] is ignored). One vertex per class, one edge K -> L when
// some tree edge p -> n has p in K, n in L and K != L (self-loops dropped, parallel edges
// merged). Edges are added in increasing (K, L) order, so the graph is deterministic.
DependencyGraph QuotientGraph(const CellTree& tree, const std::vector<std::uint32_t>& class_of,
                              std::size_t classes);

// A topological order of g's vertices (every edge goes forward), or nullopt when g has a
// cycle. Uses boost::topological_sort, which throws boost::not_a_dag on a back edge.
std::optional<std::vector<DependencyVertex>> TopologicalOrder(const DependencyGraph& g);
inline bool IsAcyclic(const DependencyGraph& g) { return TopologicalOrder(g).has_value(); }

}  // namespace raycell
