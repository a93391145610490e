// A plan made for one processor, followed by several (issue 42, a measured prototype): the
// plan's entries as tasks of a DAG. The plan run on the tree it was made for (graph/schedule.h
// RunSchedule) assigns every node to the entry that processes it; entry e is *ready* once the
// parents of all its nodes are finished, so that all its work has arrived. The scheduler watches
// the frame unfold (Scheduler::Arrived, Taken) and matches each queued node to the tree's by
// (matched parent, cell), as celltree-adaptive does; a node is finished once its parent is and
// the work queued in it has been taken and worked (its cell no longer busy). A processor asking
// for a cell takes the first unused entry in plan order that is ready and whose cell is free and
// has queued work; a ready entry whose cell has no work at all is used up unfetched (another
// fetch did its work). No entry ready: Max Work (never waiting). With one processor every
// entry's work has arrived when it comes first, so the replay is the plan followed
// (ScheduleFollower), fetch for fetch.
//  - `celltree-dag-oracle`: the best plan (PlanFor) of the frame's own tree, an oracle (`best`
//    taken as a DAG). Unlike other watching schedulers it is given the frame's tree.
//  - `celltree-dag`: the best plan of frame i-1's tree (frame 0: Max Work); nodes of frame i
//    that frame i-1's tree lacks are unmatched (Max Work's).
// On the suite at 8 processors neither beats Max Work by much: the plans' DAGs are 2-4 entries
// wide on average (entries over the longest chain), so most choices fall to Max Work.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "base/mapped_array.h"
#include "scheduling/scheduler.h"

namespace raycell {

// Its registry entries (SchedulerEntry), defined in dag_scheduler.cpp.
extern const SchedulerEntry kCellTreeDagEntry;
extern const SchedulerEntry kCellTreeDagOracleEntry;

// The plan's useful entries (those that process a node of `tree`), in plan order: each one's
// cell and how many of its nodes have a parent other than the root; and per node of `tree`, the
// entry that processes it (entry_of[0], the root's, and those of nodes the plan leaves
// unprocessed: kNoEntry).
struct PlanDag {
  static constexpr std::uint32_t kNoEntry = ~std::uint32_t{0};
  std::vector<CellId> cells;
  std::vector<std::uint32_t> parented;
  std::vector<std::uint32_t> entry_of;
};
PlanDag MakePlanDag(const CellTree& tree, const std::vector<CellId>& plan);

class DagScheduler : public Scheduler {
 public:
  DagScheduler(std::uint64_t seed, bool oracle);
  void BeginFrame(const FrameInfo& frame) override;
  std::optional<CellId> Next(const QueueView& queues) override;
  std::optional<CellId> Peek(const QueueView& queues) const override;
  std::string Reason() const override;
  DecisionCost Cost() const override { return cost_; }
  bool ReadsEarlierTrees() const override { return tree_ != nullptr; }
  bool Watches() const override { return true; }
  void Arrived(const Arrival& arrival) override;
  void Taken(CellId cell) override;

 private:
  static constexpr std::uint32_t kNone = ~std::uint32_t{0};
  // The first ready entry with work in view from first_ on; kNone when none. Uses up the
  // ready entries passed whose cell has no work at all.
  std::uint32_t Find(const QueueView& queues);
  // Node n's work is done and its parent is finished: no more work will enter it.
  void FinishNode(NodeId n);
  void Use(std::uint32_t e);

  std::uint64_t seed_;
  bool oracle_;
  const CellTree* tree_ = nullptr;  // the tree the plan was made for (null: Max Work)
  PlanDag dag_;
  std::vector<std::uint32_t> waiting_;  // per entry: its nodes whose parent is not finished
  std::vector<std::uint8_t> used_;      // per entry: taken or skipped
  std::uint32_t first_ = 0;             // entries before it are used
  // Per tree node: 0 idle (no work queued or being worked), 1 queued, 2 being worked; finished.
  std::vector<std::uint8_t> work_;
  std::vector<std::uint8_t> finished_;
  MappedArray<NodeId> node_of_;  // per arrival number: its tree node (kNoNode: unmatched)
  std::vector<std::vector<NodeId>> queued_, worked_;  // per cell: nodes queued, being worked
  std::vector<std::uint32_t> working_cells_;          // cells with worked_ not empty
  std::vector<NodeId> stack_;
  std::uint8_t last_how_ = 0;  // 0 none, 1 followed, 2 max work
  DecisionCost cost_;
};

}  // namespace raycell
