#include "bounds/projection.h"

#include <algorithm>
#include <cstdint>
#include <unordered_map>
#include <utility>

namespace raycell {

bool IsSubsequence(const CellString& a, const CellString& b) {
  if (a.size() > b.size()) return false;
  std::size_t i = 0;
  for (std::size_t j = 0; j < b.size() && i < a.size(); ++j) {
    if (a[i] == b[j]) ++i;
  }
  return i == a.size();
}

namespace {

std::uint64_t SymbolMask(const CellString& s) {
  std::uint64_t m = 0;
  for (CellId c : s) m |= std::uint64_t{1} << (c.value() % 64);
  return m;
}

// A trie of projected paths: node 0 is the empty string.
class ProjectionTrie {
 public:
  ProjectionTrie() : parent_{0}, symbol_{kNoCell}, has_child_{false} {}

  std::uint32_t Child(std::uint32_t node, CellId cell) {
    const std::uint64_t key = (std::uint64_t{node} << 32) | cell.value();
    const auto [it, inserted] = children_.emplace(key, static_cast<std::uint32_t>(size()));
    if (inserted) {
      parent_.push_back(node);
      symbol_.push_back(cell);
      has_child_.push_back(false);
      has_child_[node] = true;
    }
    return it->second;
  }
  std::size_t size() const { return parent_.size(); }
  // The strings of the trie's leaves (other than the empty root).
  std::vector<CellString> LeafStrings() const {
    std::vector<CellString> out;
    for (std::uint32_t n = 1; n < size(); ++n) {
      if (has_child_[n]) continue;
      CellString s;
      for (std::uint32_t a = n; a != 0; a = parent_[a]) s.push_back(symbol_[a]);
      std::reverse(s.begin(), s.end());
      out.push_back(std::move(s));
    }
    return out;
  }

 private:
  std::vector<std::uint32_t> parent_;
  std::vector<CellId> symbol_;
  std::vector<bool> has_child_;
  std::unordered_map<std::uint64_t, std::uint32_t> children_;
};

}  // namespace

std::vector<CellString> RemoveDominated(std::vector<CellString> strings) {
  strings.erase(
      std::remove_if(strings.begin(), strings.end(), [](const CellString& s) { return s.empty(); }),
      strings.end());
  std::sort(strings.begin(), strings.end(), [](const CellString& a, const CellString& b) {
    return a.size() != b.size() ? a.size() > b.size() : a < b;
  });
  strings.erase(std::unique(strings.begin(), strings.end()), strings.end());
  std::vector<CellString> kept;
  std::vector<std::uint64_t> masks;
  for (CellString& s : strings) {
    const std::uint64_t mask = SymbolMask(s);
    bool dominated = false;
    // Kept strings come longest first; a string of the same length is either equal (removed
    // above) or not a supersequence.
    for (std::size_t k = 0; k < kept.size() && kept[k].size() > s.size() && !dominated; ++k) {
      dominated = (mask & ~masks[k]) == 0 && IsSubsequence(s, kept[k]);
    }
    if (!dominated) {
      masks.push_back(mask);
      kept.push_back(std::move(s));
    }
  }
  return kept;
}

std::vector<CellString> ProjectPaths(const CellTree& tree, const std::vector<CellId>& cells) {
  std::vector<bool> in(tree.cell_count(), false);
  for (CellId c : cells) {
    if (c.value() < tree.cell_count()) in[c.value()] = true;
  }
  // Parents come before children (parent(n) < n), so one pass maps every node.
  ProjectionTrie trie;
  std::vector<std::uint32_t> trie_node(tree.size(), 0);
  for (NodeId n : tree.nodes()) {
    const std::uint32_t up = trie_node[tree.parent(n).index()];
    trie_node[n.index()] = in[tree.cell(n).value()] ? trie.Child(up, tree.cell(n)) : up;
  }
  // Every trie node was made for some tree node, under which some leaf's projection extends
  // it; so a trie node with a child is a proper prefix (a subsequence) of a projection, and
  // every trie leaf is the projection of a tree leaf.
  return RemoveDominated(trie.LeafStrings());
}

TreeProjector::TreeProjector(const CellTree& tree) : nodes_of_(tree.cell_count()) {
  // Preorder numbers by an explicit stack (children in order); node n's subtree is the range
  // [enter(n), last(n)].
  std::vector<std::uint32_t> enter(tree.size(), 0), last(tree.size(), 0);
  std::uint32_t next = 0;
  std::vector<std::pair<NodeId, bool>> stack{{kRootNode, false}};
  while (!stack.empty()) {
    const auto [n, done] = stack.back();
    stack.pop_back();
    if (done) {
      last[n.index()] = next - 1;
      continue;
    }
    enter[n.index()] = next++;
    stack.push_back({n, true});
    const std::size_t first = stack.size();
    for (NodeId c = tree.first_child(n); c != kNoNode; c = tree.next_sibling(c)) {
      stack.push_back({c, false});
    }
    std::reverse(stack.begin() + first, stack.end());
  }
  for (NodeId n : tree.nodes()) {
    nodes_of_[tree.cell(n).value()].push_back({enter[n.index()], last[n.index()], tree.cell(n)});
  }
  for (auto& v : nodes_of_) {
    std::sort(v.begin(), v.end(), [](const Visit& a, const Visit& b) { return a.enter < b.enter; });
  }
}

std::vector<CellString> TreeProjector::Project(const std::vector<CellId>& cells) const {
  std::vector<CellId> distinct = cells;
  std::sort(distinct.begin(), distinct.end());
  distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
  std::vector<Visit> visits;
  for (CellId c : distinct) {
    if (c.value() >= nodes_of_.size()) continue;
    const auto& v = nodes_of_[c.value()];
    const std::size_t middle = visits.size();
    visits.insert(visits.end(), v.begin(), v.end());
    std::inplace_merge(visits.begin(), visits.begin() + middle, visits.end(),
                       [](const Visit& a, const Visit& b) { return a.enter < b.enter; });
  }
  constexpr std::uint32_t kNone = ~std::uint32_t{0};
  std::vector<std::uint32_t> parent(visits.size(), kNone), open;
  std::vector<char> has_child(visits.size(), 0);
  for (std::uint32_t i = 0; i < visits.size(); ++i) {
    while (!open.empty() && visits[open.back()].last < visits[i].enter) open.pop_back();
    if (!open.empty()) parent[i] = open.back(), has_child[open.back()] = 1;
    open.push_back(i);
  }
  std::vector<CellString> strings;
  for (std::uint32_t i = 0; i < visits.size(); ++i) {
    if (has_child[i]) continue;
    CellString s;
    for (std::uint32_t a = i; a != kNone; a = parent[a]) s.push_back(visits[a].cell);
    std::reverse(s.begin(), s.end());
    strings.push_back(std::move(s));
  }
  return RemoveDominated(std::move(strings));
}

std::vector<CellString> ProjectStrings(const std::vector<CellString>& strings,
                                       const std::vector<CellId>& cells) {
  std::vector<CellId> in = cells;
  std::sort(in.begin(), in.end());
  std::vector<CellString> out;
  for (const CellString& s : strings) {
    CellString p;
    for (CellId c : s) {
      if (std::binary_search(in.begin(), in.end(), c)) p.push_back(c);
    }
    out.push_back(std::move(p));
  }
  return RemoveDominated(std::move(out));
}

std::vector<CellString> TreePaths(const CellTree& tree) {
  std::vector<CellString> out;
  for (NodeId n : tree.nodes()) {
    if (!tree.is_leaf(n)) continue;
    CellString s;
    for (NodeId a = n; a != kRootNode; a = tree.parent(a)) s.push_back(tree.cell(a));
    std::reverse(s.begin(), s.end());
    out.push_back(std::move(s));
  }
  return out;
}

}  // namespace raycell
