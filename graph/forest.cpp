#include "graph/forest.h"

#include <algorithm>
#include <sstream>
#include <utility>

#include "base/check.h"

// Why ScheduleTimes answers feasibility questions about modified schedules.
//
// Prefix. The run of entries 0..i-1 is the run of the whole schedule cut at i, so it has
// processed exactly the nodes with earliest[n] < i.
//
// Latest entries. Give each node of a subtree an entry of its cell, each strictly after its
// parent's: call that a placement. Assigning, from the leaves up, each node the last entry
// of its cell before all its children's entries gives every node the latest entry it has in
// any placement of its subtree (induction on height: a child's entry in any placement is at
// most its latest, so the node's entry, before all of them, is at most the last entry of its
// cell before the children's latest entries). That is latest[n].
//
// Suffix. Let R_j = {n : latest[n] < j} (nodes without a latest entry included). If X is
// downward closed and contains R_j, the suffix from j processes every other node n by entry
// latest[n] >= j: by induction from the top, n's parent is in X or processed by
// latest[parent] < latest[n], so at entry latest[n] (of cell(n)) n is ready if not processed
// yet. Conversely, if some n of R_j is not in X, the suffix must process n's subtree at
// entries >= j, a placement with n at an entry >= j, so latest[n] >= j: a contradiction.
//
// Replacement. So prefix + w + suffix is feasible if and only if X_i·w contains R_j, where
// X_i = {earliest < i}. The nodes of R_j not in X_i are D = {i <= earliest, latest < j}; a
// node of D has its parent in X_i or in D (R_j is downward closed), so D is a forest whose
// roots hang below processed nodes, and the run of w from X_i processes D's nodes exactly as
// the run of w on the forest D does (nodes outside D never make a node of D ready). Hence
// the condition is: w is a feasible schedule of the forest D. Deleting entry p is the case
// w empty, i = p, j = p + 1: feasible iff D is empty, i.e. no node has
// earliest == latest == p (earliest <= latest holds for every node of a feasible schedule,
// by the placement argument applied to the run's own placement).

namespace raycell {

namespace {
const std::vector<CellForest::Index> kNoNodes;
}

CellForest CellForest::FromTree(const CellTree& tree) {
  CellForest f;
  const std::size_t n = tree.node_count();
  f.cell_.resize(n);
  f.parent_.resize(n);
  for (NodeId t : tree.nodes()) {
    f.cell_[t.index() - 1] = tree.cell(t);
    f.parent_[t.index() - 1] = tree.parent(t) == kRootNode ? kNone : tree.parent(t).index() - 1;
  }
  f.Finish();
  return f;
}

CellForest CellForest::Sub(const CellForest& forest, const std::vector<Index>& nodes) {
  CellForest f;
  f.cell_.resize(nodes.size());
  f.parent_.resize(nodes.size());
  // Renumbering: binary search of the parent among `nodes` (increasing).
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    RAYCELL_CHECK(i == 0 || nodes[i - 1] < nodes[i]);
    const Index n = nodes[i], p = forest.parent(n);
    f.cell_[i] = forest.cell(n);
    f.parent_[i] = kNone;
    if (p != kNone) {
      const auto it = std::lower_bound(nodes.begin(), nodes.begin() + i, p);
      if (it != nodes.begin() + i && *it == p) f.parent_[i] = Index(it - nodes.begin());
    }
  }
  f.Finish();
  return f;
}

CellForest CellForest::FromArrays(const std::vector<Index>& parent,
                                  const std::vector<CellId>& cell) {
  RAYCELL_CHECK_EQ(parent.size(), cell.size());
  CellForest f;
  f.parent_ = parent;
  f.cell_ = cell;
  for (std::size_t i = 0; i < parent.size(); ++i) {
    RAYCELL_CHECK(parent[i] == kNone || parent[i] < i);
  }
  f.Finish();
  return f;
}

const std::vector<CellForest::Index>& CellForest::nodes_of(CellId c) const {
  return c.value() < nodes_of_.size() ? nodes_of_[c.value()] : kNoNodes;
}

void CellForest::Finish() {
  const std::size_t n = cell_.size();
  cell_count_ = 0;
  for (CellId c : cell_) cell_count_ = std::max(cell_count_, c.value() + 1);
  nodes_of_.assign(cell_count_, {});
  same_cell_above_.assign(n, kNone);
  generation_.assign(n, 1);
  child_start_.assign(n + 2, 0);
  for (Index i = 0; i < n; ++i) {
    nodes_of_[cell_[i].value()].push_back(i);
    if (parent_[i] == kNone) continue;
    ++child_start_[parent_[i] + 2];
    Index a = parent_[i];
    while (a != kNone && cell_[a] != cell_[i]) a = parent_[a];  // O(depth)
    same_cell_above_[i] = a;
    if (a != kNone) generation_[i] = generation_[a] + 1;
  }
  for (std::size_t i = 2; i < child_start_.size(); ++i) child_start_[i] += child_start_[i - 1];
  children_.resize(child_start_[n + 1]);
  for (Index i = 0; i < n; ++i) {
    if (parent_[i] != kNone) children_[child_start_[parent_[i] + 1]++] = i;
  }
  child_start_.pop_back();  // child_start_[p] .. child_start_[p + 1]
  height_.assign(n, 1);
  for (Index i = Index(n); i-- > 0;) {
    if (parent_[i] != kNone) height_[parent_[i]] = std::max(height_[parent_[i]], height_[i] + 1);
  }
  cells_.clear();
  max_gen_.assign(cell_count_, 0);
  bound_ = 0;
  for (CellId c : CellRange(cell_count_)) {
    for (Index i : nodes_of_[c.value()])
      max_gen_[c.value()] = std::max(max_gen_[c.value()], generation_[i]);
    if (!nodes_of_[c.value()].empty()) cells_.push_back(c);
    bound_ += max_gen_[c.value()];
  }
}

std::string CellForest::ToString() const {
  std::ostringstream s;
  s << "forest of " << size() << " nodes, " << cells_.size() << " cells, bound " << bound_;
  return s.str();
}

ScheduleTimer::ScheduleTimer(const CellForest& forest)
    : f_(forest), pending_(forest.cell_count()), children_left_(forest.size()) {}

bool ScheduleTimer::ComputeEarliest(const std::vector<CellId>& schedule) {
  times_.earliest.assign(f_.size(), -1);
  for (auto& p : pending_) p.clear();
  for (CellForest::Index n = 0; n < f_.size(); ++n) {
    if (f_.parent(n) == CellForest::kNone) pending_[f_.cell(n).value()].push_back(n);
  }
  std::size_t processed = 0;
  for (std::size_t i = 0; i < schedule.size(); ++i) {
    const CellId c = schedule[i];
    if (c.value() >= pending_.size() || pending_[c.value()].empty()) continue;
    batch_.clear();
    std::swap(batch_, pending_[c.value()]);
    processed += batch_.size();
    for (CellForest::Index n : batch_) {
      times_.earliest[n] = std::int32_t(i);
      for (auto* k = f_.child_begin(n); k != f_.child_end(n); ++k) {
        pending_[f_.cell(*k).value()].push_back(*k);
      }
    }
  }
  times_.feasible = processed == f_.size();
  return times_.feasible;
}

void ScheduleTimer::ComputeLatest(const std::vector<CellId>& schedule) {
  times_.latest.assign(f_.size(), -1);
  for (auto& p : pending_) p.clear();
  for (CellForest::Index n = 0; n < f_.size(); ++n) {
    children_left_[n] = std::uint32_t(f_.child_count(n));
    if (children_left_[n] == 0) pending_[f_.cell(n).value()].push_back(n);
  }
  for (std::size_t i = schedule.size(); i-- > 0;) {
    const CellId c = schedule[i];
    if (c.value() >= pending_.size() || pending_[c.value()].empty()) continue;
    batch_.clear();
    std::swap(batch_, pending_[c.value()]);
    for (CellForest::Index n : batch_) {
      times_.latest[n] = std::int32_t(i);
      const CellForest::Index p = f_.parent(n);
      if (p != CellForest::kNone && --children_left_[p] == 0)
        pending_[f_.cell(p).value()].push_back(p);
    }
  }
}

const ScheduleTimes& ScheduleTimer::Compute(const std::vector<CellId>& schedule) {
  ComputeEarliest(schedule);
  ComputeLatest(schedule);
  return times_;
}

bool IsFeasible(const CellForest& forest, const std::vector<CellId>& schedule) {
  ScheduleTimer timer(forest);
  return timer.ComputeEarliest(schedule);
}

}  // namespace raycell
