#include "graph/dependency_graph.h"

#include <algorithm>
#include <boost/graph/topological_sort.hpp>
#include <iterator>
#include <numeric>
#include <utility>

#include "base/check.h"

namespace raycell {

DependencyGraph BuildDependencyGraph(const CellTree& tree) {
  std::vector<std::uint32_t> identity(tree.size(), 0);
  std::iota(identity.begin() + (tree.size() > 0 ? 1 : 0), identity.end(), 0u);
  return QuotientGraph(tree, identity, tree.node_count());
}

DependencyGraph QuotientGraph(const CellTree& tree, const std::vector<std::uint32_t>& class_of,
                              std::size_t classes) {
  RAYCELL_CHECK_EQ(class_of.size(), tree.size());
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
  for (NodeId n : tree.nodes()) {
    RAYCELL_CHECK_LT(class_of[n.index()], classes);
    const NodeId p = tree.parent(n);
    if (p != kRootNode && class_of[p.index()] != class_of[n.index()])
      edges.emplace_back(class_of[p.index()], class_of[n.index()]);
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  DependencyGraph g(classes);
  for (const auto& [from, to] : edges) boost::add_edge(from, to, g);
  return g;
}

std::optional<std::vector<DependencyVertex>> TopologicalOrder(const DependencyGraph& g) {
  std::vector<DependencyVertex> reversed;
  reversed.reserve(boost::num_vertices(g));
  try {
    boost::topological_sort(g, std::back_inserter(reversed));
  } catch (const boost::not_a_dag&) {
    return std::nullopt;
  }
  std::reverse(reversed.begin(), reversed.end());
  return reversed;
}

}  // namespace raycell
