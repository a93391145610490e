#include "graph/peel.h"

#include <algorithm>
#include <functional>
#include <optional>
#include <sstream>
#include <utility>

#include "base/check.h"

namespace raycell {

const char* ToString(PeelKind kind) {
  return kind == PeelKind::kCompletion ? "completion" : "split";
}

std::string PeelResult::ToString() const {
  std::ostringstream s;
  s << "schedule";
  for (CellId c : schedule) s << " " << c;
  s << " (" << schedule.size() << " entries, " << split_peels << " split peels)";
  return s.str();
}

namespace {

// The state of the tree being peeled, with the per-cell counts that make each step cheap.
//
// Cost. Every node becomes a leaf once and is removed once, each time with O(1) count
// updates and at most one push onto each of the two heaps (O(log cells) each: the leaf heap is
// rebuilt from the cells, O(cells), when it holds more than twice them, the ready heap holds
// each cell at most once); the leaf heap gets its pushes only when a split step asks it, one
// per cell whose count changed since, so completions (most steps) push nothing there. Each step
// removes at least one node, so there are at most `nodes` steps, and choosing a cell pops the
// entries gone stale since (each pushed once). top_[c] (maxGen of c over the remaining nodes) only
// decreases, by at most maxGen(c) in total, and the sum of maxGen is at most `nodes`. Total:
// O(nodes log cells), O(nodes) memory (the per-(cell, generation) counts have sum-of-maxGen <=
// nodes entries).
//
// The two orders were std::sets (a tree node allocated and freed at every change of a cell's
// leaf count: 26M allocations in a replay at 4096 cells); as heaps with lazy deletion each
// change is a push onto an array, and the cell chosen is the same: the set's first.
class Peeler {
 public:
  explicit Peeler(const CellTree& tree) : t_(tree), cells_(tree.cell_count()) {
    InitCounts();
    for (NodeId n : t_.nodes()) {
      if (t_.is_leaf(n)) AddLeaf(n);
    }
    for (CellId c : CellRange(cells_)) UpdateReady(c);
  }

  PeelResult Run() {
    PeelResult out;
    for (;;) {
      const std::optional<CellId> ready = FirstReady();
      const std::optional<CellId> chosen = ready ? ready : MostLeaves();
      if (!chosen) break;
      const bool completion = ready.has_value();
      RemoveLeavesOf(*chosen);
      out.schedule.push_back(*chosen);
      out.kinds.push_back(completion ? PeelKind::kCompletion : PeelKind::kSplit);
      out.split_peels += completion ? 0 : 1;
    }
    std::reverse(out.schedule.begin(), out.schedule.end());
    std::reverse(out.kinds.begin(), out.kinds.end());
    return out;
  }

 private:
  // A cell's leaf count when pushed: most leaves first, lowest cell on ties (the heap's top is
  // the greatest under LeafLess).
  struct LeafKey {
    std::uint32_t leaves;
    std::uint32_t cell;
  };
  static bool LeafLess(const LeafKey& a, const LeafKey& b) {
    return a.leaves != b.leaves ? a.leaves < b.leaves : a.cell > b.cell;
  }
  static bool CellAfter(std::uint32_t a, std::uint32_t b) { return a > b; }
  std::size_t Slot(NodeId n) const { return base_[t_.cell(n).value()] + t_.generation(n) - 1; }

  void InitCounts() {
    top_ = MaxGenerations(t_);
    base_.assign(cells_, 0);
    std::size_t total = 0;
    for (std::uint32_t c = 0; c < cells_; ++c) base_[c] = std::exchange(total, total + top_[c]);
    count_.assign(total, 0);
    leaf_count_.assign(total, 0);
    children_.assign(t_.size(), 0);
    for (NodeId n : t_.nodes()) {
      ++count_[Slot(n)];
      if (t_.parent(n) != kRootNode) ++children_[t_.parent(n).index()];
    }
    non_leaf_top_.assign(cells_, 0);
    for (std::uint32_t c = 0; c < cells_; ++c) {
      non_leaf_top_[c] = top_[c] ? count_[base_[c] + top_[c] - 1] : 0;
    }
    leaves_.resize(cells_);
    in_heap_.assign(cells_, 0);
    dirty_.assign(cells_, 0);
  }

  void AddLeaf(NodeId n) {
    const CellId c = t_.cell(n);
    leaves_[c.value()].push_back(n);
    // Its count changed: pushed onto the leaf heap when a split asks for it (MostLeaves), not
    // at every leaf (most steps are completions, which never read that heap).
    if (dirty_[c.value()] == 0) {
      dirty_[c.value()] = 1;
      dirty_list_.push_back(c.value());
    }
    ++leaf_count_[Slot(n)];
    if (t_.generation(n) == top_[c.value()]) --non_leaf_top_[c.value()];
  }

  // The cell with the most leaves now (lowest number on ties); none when no cell has a leaf.
  // Entries whose count is no longer their cell's are dropped as met.
  std::optional<CellId> MostLeaves() {
    // Every cell whose count changed since it was last pushed gets an entry with its count, so
    // that every cell with leaves has one up to date, as if each change had been pushed.
    for (const std::uint32_t c : dirty_list_) {
      dirty_[c] = 0;
      if (!leaves_[c].empty()) PushLeaves(c);
    }
    dirty_list_.clear();
    while (!by_leaves_.empty()) {
      const LeafKey k = by_leaves_.front();
      if (k.leaves != 0 && k.leaves == leaves_[k.cell].size()) return CellId(k.cell);
      std::pop_heap(by_leaves_.begin(), by_leaves_.end(), LeafLess);
      by_leaves_.pop_back();
    }
    return std::nullopt;
  }
  void PushLeaves(std::uint32_t c) {
    if (by_leaves_.size() >= 2 * std::size_t{cells_} + 64) {  // mostly stale: rebuilt
      by_leaves_.clear();
      for (std::uint32_t x = 0; x < cells_; ++x) {
        if (!leaves_[x].empty()) by_leaves_.push_back({std::uint32_t(leaves_[x].size()), x});
      }
      std::make_heap(by_leaves_.begin(), by_leaves_.end(), LeafLess);
      return;
    }
    by_leaves_.push_back({std::uint32_t(leaves_[c].size()), c});
    std::push_heap(by_leaves_.begin(), by_leaves_.end(), LeafLess);
  }

  // The lowest ready cell; none when none is. Entries of cells no longer ready are dropped.
  std::optional<CellId> FirstReady() {
    while (!ready_heap_.empty()) {
      const std::uint32_t c = ready_heap_.front();
      if (Ready(c)) return CellId(c);
      std::pop_heap(ready_heap_.begin(), ready_heap_.end(), CellAfter);
      ready_heap_.pop_back();
      in_heap_[c] = 0;
    }
    return std::nullopt;
  }

  // Completion: c has nodes left and no non-leaf at its top generation.
  bool Ready(std::uint32_t c) const { return top_[c] > 0 && non_leaf_top_[c] == 0; }

  // Called wherever c's counts may have made it ready. A cell not ready keeps its entry, stale,
  // until it is met; ready again meanwhile, it needs no other.
  void UpdateReady(CellId c) {
    const std::uint32_t x = c.value();
    if (!Ready(x) || in_heap_[x] != 0) return;
    in_heap_[x] = 1;
    ready_heap_.push_back(x);
    std::push_heap(ready_heap_.begin(), ready_heap_.end(), CellAfter);
  }

  // Removes the leaves of c present now. Their parents are of other cells (a child never
  // has its parent's cell), so no leaf of c appears while they are removed.
  void RemoveLeavesOf(CellId c) {
    scratch_.clear();
    scratch_.swap(leaves_[c.value()]);  // c's list keeps the scratch's room
    RAYCELL_CHECK(!scratch_.empty());   // progress: every step removes a node
    for (NodeId n : scratch_) RemoveLeaf(n);
    RAYCELL_CHECK(leaves_[c.value()].empty());
    LowerTop(c);
    UpdateReady(c);
  }

  void RemoveLeaf(NodeId n) {
    --count_[Slot(n)];
    --leaf_count_[Slot(n)];
    const NodeId p = t_.parent(n);
    if (p == kRootNode || --children_[p.index()] > 0) return;
    AddLeaf(p);
    UpdateReady(t_.cell(p));
  }

  // Moves top_[c] down past emptied generations and recounts its non-leaves there.
  void LowerTop(CellId c) {
    const std::uint32_t old_top = top_[c.value()];
    while (top_[c.value()] > 0 && count_[base_[c.value()] + top_[c.value()] - 1] == 0)
      --top_[c.value()];
    if (top_[c.value()] == old_top || top_[c.value()] == 0) return;
    const std::size_t slot = base_[c.value()] + top_[c.value()] - 1;
    non_leaf_top_[c.value()] = count_[slot] - leaf_count_[slot];
  }

  const CellTree& t_;
  const std::uint32_t cells_;
  std::vector<std::uint32_t> top_;           // per cell: maxGen over the remaining nodes
  std::vector<std::size_t> base_;            // per cell: first slot of its generations
  std::vector<std::uint32_t> count_;         // per (cell, gen): remaining nodes
  std::vector<std::uint32_t> leaf_count_;    // per (cell, gen): remaining leaves
  std::vector<std::uint32_t> non_leaf_top_;  // per cell: non-leaves at generation top_
  std::vector<std::uint32_t> children_;      // per node: remaining children
  std::vector<std::vector<NodeId>> leaves_;  // per cell: current leaves
  std::vector<NodeId> scratch_;              // RemoveLeavesOf's
  // A min-heap of cells, each at most once (in_heap_), holding every ready one.
  std::vector<std::uint8_t> in_heap_;
  std::vector<std::uint32_t> ready_heap_;
  std::vector<LeafKey> by_leaves_;  // max-heap of (leaf count, cell) as pushed (LeafLess)
  // The cells whose leaf count grew since they were last pushed onto by_leaves_ (dirty_: 1).
  std::vector<std::uint8_t> dirty_;
  std::vector<std::uint32_t> dirty_list_;
};

}  // namespace

PeelResult Peel(const CellTree& tree) { return Peeler(tree).Run(); }

namespace {

// The run of docs/design.md §1: at each entry of `schedule`, every node of its cell whose
// parent is done (the root: always). Calls step(cell, nodes) for each entry that processes
// some nodes. In a tree (a SubTree too) a child never has its parent's cell, so nothing an
// entry makes ready is processed by the same entry. O(nodes + entries).
template <typename Step>
void RunGreedy(const CellTree& tree, const std::vector<CellId>& schedule, Step step) {
  std::vector<std::vector<NodeId>> ready(tree.cell_count());
  for (NodeId c = tree.first_child(kRootNode); c != kNoNode; c = tree.next_sibling(c)) {
    ready[tree.cell(c).value()].push_back(c);
  }
  std::vector<NodeId> now;
  for (const CellId cell : schedule) {
    if (cell.value() >= ready.size() || ready[cell.value()].empty()) continue;
    now.clear();
    now.swap(ready[cell.value()]);
    for (const NodeId n : now) {
      for (NodeId c = tree.first_child(n); c != kNoNode; c = tree.next_sibling(c)) {
        ready[tree.cell(c).value()].push_back(c);
      }
    }
    step(cell, now);
  }
}

}  // namespace

std::vector<CellId> TwoLevelPeel(const CellTree& tree, const std::vector<CellId>& coarse_of) {
  const TreePlanner peel = [](const CellTree& t) { return Peel(t).schedule; };
  return TwoLevelSchedule(tree, coarse_of, peel, peel);
}

std::vector<CellId> TwoLevelSchedule(const CellTree& tree, const std::vector<CellId>& coarse_of,
                                     const TreePlanner& coarse_plan, const TreePlanner& fine_plan) {
  std::vector<NodeId> image;
  const CellTree coarse = ContractTree(tree, coarse_of, &image);
  // Per coarse node m, the tree's nodes it stands for, in increasing order: members[first[m]]
  // up to members[first[m + 1]] (one array, not a vector per coarse node: with the board's
  // cells the replay's, the coarse tree is as large as the tree).
  std::vector<std::uint32_t> first(coarse.size() + 1, 0);
  for (NodeId n : tree.nodes()) ++first[image[n.index()].index() + 1];
  for (std::size_t m = 0; m < coarse.size(); ++m) first[m + 1] += first[m];
  std::vector<NodeId> members(first.back());
  {
    std::vector<std::uint32_t> next(first.begin(), first.end() - 1);
    for (NodeId n : tree.nodes()) members[next[image[n.index()].index()]++] = n;
  }
  std::vector<CellId> out;
  std::vector<NodeId> forest;
  RunGreedy(coarse, coarse_plan(coarse), [&](CellId, const std::vector<NodeId>& step) {
    forest.clear();
    for (const NodeId m : step) {
      forest.insert(forest.end(), members.begin() + first[m.index()],
                    members.begin() + first[m.index() + 1]);
    }
    std::sort(forest.begin(), forest.end());
    // Entries that process nothing in the run (Peel builds backwards) are left out.
    const CellTree inner = SubTree(tree, forest);
    RunGreedy(inner, fine_plan(inner),
              [&](CellId cell, const std::vector<NodeId>&) { out.push_back(cell); });
  });
  return out;
}

}  // namespace raycell
