#include "scheduling/dag_scheduler.h"

#include <algorithm>

#include "base/check.h"
#include "graph/schedule.h"
#include "scheduling/best_scheduler.h"

namespace raycell {

constexpr SchedulerEntry kCellTreeDagEntry = [] {
  SchedulerEntry e;
  e.name = "celltree-dag";
  e.meaning =
      "frame i+1 takes the entries of frame i's best plan as a DAG: a free processor takes the "
      "first entry whose nodes' parents are all finished (a prototype), else Max Work";
  e.label = "Cell Tree, plan as a DAG";
  e.make = [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
    return std::make_unique<DagScheduler>(seed, false);
  };
  e.seeded = true;
  e.studied = false;  // a prototype (dag_scheduler.h)
  e.joins = false;    // never a busy cell
  return e;
}();

constexpr SchedulerEntry kCellTreeDagOracleEntry = [] {
  SchedulerEntry e;
  e.name = "celltree-dag-oracle";
  e.meaning = "celltree-dag on the frame's own tree's best plan (an oracle)";
  e.label = "Cell Tree, own plan as a DAG (oracle)";
  e.make = [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
    return std::make_unique<DagScheduler>(seed, true);
  };
  e.history = 0;
  e.seeded = true;
  e.oracle = true;
  e.studied = false;
  e.joins = false;
  return e;
}();

PlanDag MakePlanDag(const CellTree& tree, const std::vector<CellId>& plan) {
  static_assert(PlanDag::kNoEntry == kNoFetch, "an unprocessed node has no entry");
  // The plan's useful fetches are the DAG's entries (RunSchedule numbers them).
  PlanDag dag;
  const ScheduleRun run = RunSchedule(tree, plan, &dag.entry_of);
  dag.cells.assign(run.useful_fetches, kNoCell);
  dag.parented.assign(run.useful_fetches, 0);
  for (const NodeId n : tree.nodes()) {
    const std::uint32_t e = dag.entry_of[n.index()];
    if (e == PlanDag::kNoEntry) continue;
    dag.cells[e] = tree.cell(n);
    dag.parented[e] += tree.parent(n) != kRootNode;
  }
  return dag;
}

DagScheduler::DagScheduler(std::uint64_t seed, bool oracle)
    : Scheduler(oracle ? kCellTreeDagOracleEntry : kCellTreeDagEntry),
      seed_(seed),
      oracle_(oracle) {}

void DagScheduler::BeginFrame(const FrameInfo& frame) {
  tree_ = oracle_ ? frame.current : frame.previous;
  if (oracle_) RAYCELL_CHECK(tree_ != nullptr);
  cost_ = {};
  dag_ =
      tree_ == nullptr ? PlanDag{} : MakePlanDag(*tree_, *SharedPlan(frame.plans, *tree_, seed_));
  const auto n = static_cast<std::uint32_t>(dag_.cells.size());
  const std::size_t nodes = tree_ == nullptr ? 1 : tree_->size();
  if (tree_ == nullptr) dag_.entry_of.assign(1, PlanDag::kNoEntry);
  waiting_ = dag_.parented;
  cost_.steps += nodes;
  used_.assign(n, 0);
  first_ = 0;
  work_.assign(nodes, 0);
  finished_.assign(nodes, 0);
  finished_[0] = 1;
  node_of_.assign(1, tree_ == nullptr ? kNoNode : kRootNode);
  queued_.assign(frame.cells, {});
  worked_.assign(frame.cells, {});
  working_cells_.clear();
  last_how_ = 0;
}

void DagScheduler::Arrived(const Arrival& a) {
  if (a.node >= node_of_.size()) node_of_.resize(std::size_t{a.node} + 1, kNoNode);
  NodeId& n = node_of_[a.node];
  if (n == kNoNode && a.node != 0) {
    const NodeId parent = a.parent < node_of_.size() ? node_of_[a.parent] : kNoNode;
    if (parent != kNoNode) n = tree_->FindChild(parent, a.cell);
    ++cost_.steps;
  }
  if (n == kNoNode || work_[n.index()] == 1) return;
  work_[n.index()] = 1;
  queued_[a.cell.value()].push_back(n);
}

void DagScheduler::Taken(CellId cell) {
  std::vector<NodeId>& q = queued_[cell.value()];
  if (q.empty()) return;
  std::vector<NodeId>& w = worked_[cell.value()];
  if (w.empty()) working_cells_.push_back(cell.value());
  for (NodeId n : q) {
    if (work_[n.index()] != 1) continue;
    work_[n.index()] = 2;
    w.push_back(n);
  }
  q.clear();
}

void DagScheduler::FinishNode(NodeId n) {
  stack_.assign(1, n);
  while (!stack_.empty()) {
    const NodeId x = stack_.back();
    stack_.pop_back();
    if (finished_[x.index()]) continue;
    finished_[x.index()] = 1;
    for (NodeId c = tree_->first_child(x); c != kNoNode; c = tree_->next_sibling(c)) {
      ++cost_.steps;
      const std::uint32_t e = dag_.entry_of[c.index()];
      if (e != PlanDag::kNoEntry) --waiting_[e];
      if (work_[c.index()] == 0) stack_.push_back(c);  // nothing queued: no work will come
    }
  }
}

void DagScheduler::Use(std::uint32_t e) {
  used_[e] = 1;
  while (first_ < used_.size() && used_[first_]) ++first_;
}

std::uint32_t DagScheduler::Find(const QueueView& queues) {
  for (std::uint32_t e = first_; e < used_.size(); ++e) {
    ++cost_.steps;
    if (used_[e] || waiting_[e] != 0) continue;
    const CellId c = dag_.cells[e];
    if (queues.has_work(c)) return e;
    if (queues.busy(c)) continue;
    if (queues.all_queued != nullptr && queues.all_queued[c.value()] > 0) continue;
    Use(e);  // ready, nothing queued: its work was done by another fetch
  }
  return kNone;
}

std::optional<CellId> DagScheduler::Next(const QueueView& queues) {
  // No work in view: nothing changes (Scheduler::Next); what finished is seen at the next call.
  const std::optional<CellId> most = MostQueuedCell(queues);
  if (!most) return std::nullopt;
  // Cells no longer busy: the work taken there is done (the asking processor's too).
  for (std::size_t i = 0; i < working_cells_.size();) {
    const std::uint32_t c = working_cells_[i];
    ++cost_.steps;
    if (queues.busy(CellId(c))) {
      ++i;
      continue;
    }
    std::vector<NodeId> done;
    std::swap(done, worked_[c]);
    for (NodeId n : done) {
      if (work_[n.index()] != 2) continue;
      work_[n.index()] = 0;
      if (finished_[tree_->parent(n).index()]) FinishNode(n);
    }
    working_cells_[i] = working_cells_.back();
    working_cells_.pop_back();
  }
  const std::uint32_t e = Find(queues);
  if (e != kNone) {
    Use(e);
    last_how_ = 1;
    ++cost_.decisions;
    return dag_.cells[e];
  }
  last_how_ = 2;
  ++cost_.decisions;
  return most;
}

std::optional<CellId> DagScheduler::Peek(const QueueView& queues) const {
  for (std::uint32_t e = first_; e < used_.size(); ++e) {
    if (used_[e] || waiting_[e] != 0) continue;
    if (queues.has_work(dag_.cells[e])) return dag_.cells[e];
  }
  return MostQueuedCell(queues);
}

std::string DagScheduler::Reason() const {
  return last_how_ == 1 ? "dag entry" : last_how_ == 2 ? "max work" : "";
}

}  // namespace raycell
