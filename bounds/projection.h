// Projections of a Cell Tree onto a set of cells (docs/design.md §1 "Lower bounds beyond maxGen").
//
// For a set S of cells, every root-to-leaf cell path is projected onto S: its cells that are in
// S are kept, in order, repeats kept. A feasible schedule restricted to S is a common
// supersequence of the projections, so the shortest common supersequence of the projected
// strings (bounds/scs.h) is a lower bound on the fetches of cells of S in any feasible schedule.
// A projected string that is a subsequence of another changes nothing (every supersequence of
// the longer one is one of the shorter), so the projection keeps only the maximal ones.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "graph/cell_tree.h"

namespace raycell {

using CellString = std::vector<CellId>;

// The distinct projections onto `cells` of the root-to-leaf paths of `tree`, without those
// that are a subsequence of another (so also without duplicates), in a deterministic order
// (longest first, then lexicographic). Projections that are empty are dropped: the result is
// empty when no node's cell is in `cells`. Cells of `cells` that are >= tree.cell_count() or
// repeated are allowed (they match nothing / count once).
//
// Cost: O(nodes) to build a trie of the projected paths (each tree node is mapped to a trie
// node; a trie node with a child is a proper prefix of a projection, so only trie leaves are
// kept), then the subsequence test of RemoveDominated on the trie leaves.
std::vector<CellString> ProjectPaths(const CellTree& tree, const std::vector<CellId>& cells);

// The projections of one tree onto many sets of cells (the lower bound's groups): built once
// (O(nodes log nodes): each cell's nodes in preorder), then Project(cells) == ProjectPaths(tree,
// cells) at the cost of those cells' nodes and the projected strings, not of the whole tree or
// of every path through the cells. How: a node's nearest ancestor among the cells' nodes
// (found with a stack over them in preorder) is its parent in a forest of those nodes; a
// path's projection is the chain of its deepest such node, and the chain of a node with a
// child in the forest is a proper prefix (a subsequence) of its child's. So the chains of the
// forest's leaves, without dominated ones, are the projection (RemoveDominated keeps the
// maximal strings of a set, in an order fixed by the strings).
class TreeProjector {
 public:
  explicit TreeProjector(const CellTree& tree);
  std::vector<CellString> Project(const std::vector<CellId>& cells) const;

 private:
  struct Visit {
    std::uint32_t enter = 0, last = 0;  // preorder number, the last one of its subtree
    CellId cell;
  };
  std::vector<std::vector<Visit>> nodes_of_;  // per cell, in preorder
};

// The same projection applied to any strings: each string restricted to `cells`, then
// RemoveDominated. ProjectStrings(TreePaths(tree), cells) == ProjectPaths(tree, cells).
std::vector<CellString> ProjectStrings(const std::vector<CellString>& strings,
                                       const std::vector<CellId>& cells);

// The root-to-leaf paths of `tree` themselves (the projection onto every cell).
std::vector<CellString> TreePaths(const CellTree& tree);

// `strings` without duplicates, empty strings and strings that are a subsequence of another
// one, in the order longest first, then lexicographic. A string is only tested against the
// strictly longer ones kept so far, and a pair is skipped at once when the shorter one holds a
// symbol the longer one lacks (a 64-bit symbol mask); the test itself is the greedy scan,
// O(length of the longer). Worst case O(m^2 L) for m strings of length at most L (on a 27-cell
// frame: 589 strings of at most 16, well under a millisecond).
std::vector<CellString> RemoveDominated(std::vector<CellString> strings);

// True when `a` is a subsequence of `b` (a's symbols appear in b in order, not necessarily
// next to each other).
bool IsSubsequence(const CellString& a, const CellString& b);

}  // namespace raycell
