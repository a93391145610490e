// Adaptive scheduling (issue 24; docs/design.md §5 "Adaptive scheduling"): schedulers that
// plan frame i+1 from earlier frames, as Cell Tree scheduling does, and then watch frame i+1
// unfold (Scheduler::Watches) and correct the plan with what they see.
//
// `celltree-adaptive` predicts the frame, with several processors by the union of frames i-1 and
// i's trees (as `celltree-union`), with one by frame i's tree alone (as `celltree-best`: one
// processor follows the plan exactly, and the tighter plan of the newer frame fetched fewer on
// the suite, docs/design.md §5 "Adaptive scheduling"), and follows the best schedule found for
// it, node by node:
//  - Each node queued in the frame is matched to the predicted node of the same cell path
//    (its parent's match, then the child of the same cell). A node on a path the prediction
//    does not have gets a stand-in: the first predicted node of the same cell whose parent's
//    cell is its parent's, so that its descendants are matched below the stand-in.
//  - Running the plan on the predicted tree gives each predicted node the entry that
//    processes it (its *due* entry). An entry is fetched when its cell has queued work due
//    there or earlier (late work, work on paths with no match, work of unknown node); an entry
//    whose cell has work due only at a later entry of the same cell is skipped, so that the
//    work waits for that entry, which the plan says comes with more of it. An entry whose cell
//    has no work is skipped as by Cell Tree scheduling; with several processors one whose cell
//    another processor works is deferred (ScheduleFollower).
//  - Work in a cell that no entry left in the plan fetches (an *orphan*: rays on a path the
//    earlier frames did not have, arriving after the plan is done with their cell) is fetched
//    first, so that the rays it sends on may still meet the entries left; waiting for the
//    plan's end, they would each need fetches of their own (BENCHMARKS.md "Online against the
//    oracle"). With several processors the orphan cell with the most queued rays; with one the
//    one with the shallowest queued work (then the most rays), so that orphans on a path the
//    prediction lacks are taken in the path's order rather than one fetch per small batch.
//    Orphans go first while they have taken no more of the frame's fetches than the plan (its
//    entries followed or planned again): past that the frame has left the prediction (on the
//    mirrors scene at 256x256 one frame fetched 278 orphans against 79 entries, more than Max
//    Work's whole frame), and the orphans wait for the plan's end, where they are planned again.
//  - When the plan is used up and work remains, the rest is planned again: the forest of the
//    queued nodes matched by path (not through a stand-in, whose subtree is a guess) with their
//    predicted subtrees, by Peel; cells with other work come after it, in cell order. With
//    nothing to plan, Max Work.
// Frame 0, with no earlier frame, takes the shallowest queued work first: the cell whose queued
// nodes include the least depth in the tree (the root's children 1), the most queued rays on
// ties, so that deeper work gathers while the shallower is done (Max Work fetches 19% more
// there: BENCHMARKS.md "Online against the oracle"). Frame 1 predicts from frame 0 alone.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "base/mapped_array.h"
#include "scheduling/plan_cache.h"
#include "scheduling/scheduler.h"

namespace raycell {

// Stand-ins for nodes on paths a predicted tree lacks: per (parent's cell, cell), kNoCell for
// the root's, the first node of the tree with those cells (a map: a grid may have millions of
// cells, and few pairs occur).
using StandIns = std::unordered_map<std::uint64_t, NodeId>;
inline std::uint64_t StandInKey(CellId parent, CellId cell) {
  return std::uint64_t{parent.value()} << 32 | cell.value();
}
StandIns StandInsOf(const CellTree& tree);
// StandInsOf(tree), shared through `cache` (null: made here).
std::shared_ptr<const StandIns> SharedStandIns(PlanCache* cache, const CellTree& tree);
// The node of `tree` matching a queued node of `cell` whose parent matched `parent` (kNoNode:
// no match) in `parent_cell`: the parent's child of that cell, else the stand-in (then
// *stand_in is set), else kNoNode.
NodeId MatchNode(const CellTree& tree, const StandIns& stand_ins, NodeId parent, CellId parent_cell,
                 CellId cell, bool* stand_in);

// Its registry entry (SchedulerEntry), defined in adaptive_scheduler.cpp.
extern const SchedulerEntry kCellTreeAdaptiveEntry;

class AdaptiveScheduler : public Scheduler {
 public:
  explicit AdaptiveScheduler(std::uint64_t seed) : Scheduler(kCellTreeAdaptiveEntry), seed_(seed) {}

  void BeginFrame(const FrameInfo& frame) override;
  std::optional<CellId> Next(const QueueView& queues) override;
  std::optional<CellId> Peek(const QueueView& queues) const override;
  std::string Reason() const override;
  bool Watches() const override { return true; }
  void Arrived(const Arrival& arrival) override;
  void Taken(CellId cell) override;
  DecisionCost Cost() const override;
  // Arrivals are matched in the predicted tree: the previous frame's itself, or the union of
  // the last two, which the scheduler holds.
  bool ReadsEarlierTrees() const override { return reads_previous_; }
  // Several processors with frames i-2 and i-1: their union, from which alone it then plans.
  bool Prepare(const FrameInfo& frame) override;
  std::uint64_t HeldBytes() const override;

  // Plans made this frame after the first (re-plans), for tests and benchmarks.
  std::uint64_t replans() const { return replans_; }

 private:
  // Whether the frame is predicted by the union of frames i-2 and i-1 (several processors, both
  // trees given): what Prepare makes and BeginFrame reads.
  static bool PredictsByUnion(const FrameInfo& frame);

  static constexpr std::uint32_t kNever = ~std::uint32_t{0};

  // The due entry of every predicted node (of `predicted` nodes) that `plan` processes when run
  // on `planned` (null: none; kNever for the others), whose node k + 1 is predicted node
  // (*nodes)[k] (null: the predicted tree itself); *steps counts the entries and nodes visited.
  static std::vector<std::uint32_t> DueOf(const std::vector<CellId>& plan, const CellTree* planned,
                                          const std::vector<NodeId>* nodes, std::size_t predicted,
                                          std::uint32_t cells, std::uint64_t* steps);
  // Sets the plan and the due entries (DueOf).
  void SetPlan(std::vector<CellId> plan, const CellTree* planned, const std::vector<NodeId>* nodes);
  void Install(std::vector<CellId> plan, const std::vector<std::uint32_t>* due);
  // The earliest entry that work queued at `c` is due at (0: due now).
  std::uint32_t DueAt(CellId c) const;
  void RecomputeDue(CellId c);
  // The entry Next would take from the cursor on; plan_.size() when none.
  std::size_t Find(const QueueView& queues) const;
  // Marks entry i used up.
  void Use(std::size_t i);
  // The cell with the most queued rays in view among those no entry left in the plan fetches
  // (lowest number on ties); none when there is none or the plan is used up.
  // With one processor the orphan is ShallowestOrphan's.
  std::optional<CellId> Orphan(const QueueView& queues) const;
  // The cell the plan is done with whose queued work in view is the shallowest (min_depth_),
  // then the most queued rays, then the lowest number: the orphans nearest the root first, so
  // that what they send on gathers with the deeper orphans (none when none has work).
  std::optional<CellId> ShallowestOrphan(const QueueView& queues) const;
  // The cell with the shallowest queued work in view (lowest min_depth_, then the most queued
  // rays, then the lowest number); none when no cell has work.
  std::optional<CellId> Shallowest(const QueueView& queues) const;
  // Plans the queued work again; false when there is nothing to plan.
  bool PlanAgain(const QueueView& queues);
  // The bytes of state StateBytes counts now; CountBytes keeps the largest.
  std::uint64_t StateBytes() const;
  void CountBytes();

  std::uint64_t seed_;
  std::uint32_t cells_ = 0;
  // FrameInfo::processors <= 1: the prediction is frame i-1's tree alone, orphans shallowest
  // first; with several, the union of frames i-2 and i-1, orphans most queued first.
  bool one_processor_ = true;
  // Whether queued nodes' depths are kept: for Shallowest (no prediction) and, with one
  // processor, the shallowest orphan.
  bool KeepsDepths() const { return predicted_ == nullptr || one_processor_; }
  // The union of the last two trees, when planned from it (predicted_ points into it): held
  // here, since the runner frees the frame's plan cache once every configuration began.
  std::shared_ptr<const CellTree> own_;
  const CellTree* predicted_ = nullptr;  // null: no earlier frame (Max Work)
  bool reads_previous_ = false;          // predicted_ is FrameInfo::previous
  // Stand-ins of the predicted tree (shared, FrameInfo::plans).
  std::shared_ptr<const StandIns> stand_in_;

  std::vector<CellId> plan_;
  UnusedEntries used_;
  std::vector<std::uint32_t> remaining_;  // per cell: entries of plan_ not used up
  std::size_t cursor_ = 0;
  // Per predicted node: its entry in plan_, or kNever; the start plan's (shared, as the union)
  // or own_due_ (a re-plan's). null: no prediction.
  const std::vector<std::uint32_t>* due_ = nullptr;
  std::vector<std::uint32_t> own_due_;
  std::shared_ptr<const void> own_start_;  // the start plan and its due (due_ points into it)
  std::uint64_t start_bytes_ = 0;          // the start's bytes (HeldBytes)

  MappedArray<NodeId> match_;  // per queued node (Arrival::node): its prediction
  std::vector<bool> guess_;    // per queued node: matched through a stand-in
  std::vector<std::vector<std::uint32_t>> queued_;  // per cell: nodes queued, not yet taken
  std::size_t kept_room_ = 0;           // the room an emptied queued_ list keeps (base/kept_room.h)
  std::vector<std::uint32_t> min_due_;  // per cell: the least due entry of queued_
  // Per queued node: its depth (the root's children 1); kept only where it is read (KeepsDepths:
  // Shallowest with no prediction, ShallowestOrphan with one processor).
  MappedArray<std::uint32_t> depth_;
  std::vector<std::uint32_t> min_depth_;  // per cell: the least depth of queued_
  // Per depth the cells whose min_depth_ it is, and the least depth whose list may have cells:
  // Shallowest looks at the shallowest lists, not at every cell (issue 43).
  CellLists at_depth_;
  std::uint32_t low_depth_ = 0;
  void SetMinDepth(CellId c, std::uint32_t depth);
  // Cells no entry left in the plan fetches (remaining_ 0), in any order: where Orphan looks
  // when the most queued cell is not one of them.
  std::vector<std::uint32_t> done_cells_;
  // Per cell the rays queued there as told (Arrival::rays since its last Taken): the board's
  // queued rays, which its own view (QueueView::most_of == queued_rays) shows for every free
  // cell (a busy one shows 0).
  std::vector<std::uint64_t> told_;
  // The orphans in order (issue 43): a heap of the done cells with told work, each pushed when
  // it becomes done or work arrives there (once per look: touched_), keyed by (min_depth_ with one
  // processor, else 0; told_; cell). An entry whose key is no longer its cell's is stale and
  // dropped when met (lazy deletion); the heap is rebuilt from done_cells_ when it holds more than
  // twice the cells, so it stays within 2 x cells entries. Orphan reads its top instead of looking
  // at every done cell (a view not the board's own is scanned).
  struct OrphanKey {
    std::uint32_t depth;
    std::uint32_t cell;
    std::uint64_t rays;
  };
  mutable std::vector<OrphanKey> orphans_;
  mutable std::vector<OrphanKey> passed_;  // TopOrphan's scratch
  OrphanKey KeyOf(std::uint32_t c) const {
    return {one_processor_ ? min_depth_[c] : 0, c, told_[c]};
  }
  bool Stale(const OrphanKey& k) const;
  // Done cells whose key may have changed since the heap was last looked at (each once:
  // touched_at_ 1), pushed by the next look rather than at every arrival.
  mutable std::vector<std::uint32_t> touched_;
  mutable std::vector<std::uint8_t> touched_at_;
  void Touch(std::uint32_t c);
  // Pushes cell c's key when it is done and has told work.
  void PushOrphan(std::uint32_t c) const;
  void RebuildOrphans() const;
  // The first orphan by the heap: the least key whose cell has work in view (busy cells, with
  // none in view, are passed over and kept); none when there is none.
  std::optional<CellId> TopOrphan(const QueueView& queues) const;

  std::uint64_t replans_ = 0;
  // This frame's cells chosen from the plan (followed or re-planned) and as orphans: orphans go
  // first only while they are no more (the file's comment says why).
  std::uint64_t plan_fetches_ = 0, orphan_fetches_ = 0;
  bool OrphansFirst() const { return orphan_fetches_ <= plan_fetches_; }
  // 0 none, 1 followed, 2 re-planned, 3 max work, 4 orphan, 5 shallowest (no earlier frame)
  std::uint8_t last_how_ = 0;
  mutable DecisionCost cost_;  // Find counts the entries it scans
};

}  // namespace raycell
