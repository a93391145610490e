#include "scheduling/cell_tree_scheduler.h"

#include "graph/peel.h"
#include "scheduling/plan_cache.h"

namespace raycell {

constexpr SchedulerEntry kCellTreeEntry = [] {
  SchedulerEntry e;
  e.name = "celltree";
  e.meaning = "the paper's Cell Tree scheduling: frame i+1 follows frame i's Peel schedule";
  e.label = "Cell Tree scheduling (Peel of frame i's tree)";
  e.make = [](std::uint64_t) -> std::unique_ptr<Scheduler> {
    return std::make_unique<CellTreeScheduler>();
  };
  return e;
}();

constexpr SchedulerEntry kCellTree2LevelEntry = [] {
  SchedulerEntry e;
  e.name = "celltree-2level";
  e.meaning =
      "frame i+1 follows a two-level plan of frame i's tree: Peel of the tree contracted to "
      "the board's cells (level.NAME.cells) orders them, Peel orders the cells within each";
  e.label = "Cell Tree, two levels (board cells, then cache cells)";
  e.make = [](std::uint64_t) -> std::unique_ptr<Scheduler> {
    return std::make_unique<TwoLevelScheduler>();
  };
  e.studied = false;
  return e;
}();

void CellTreeScheduler::BeginFrame(const FrameInfo& frame) {
  follower_.Reset(
      frame.previous ? *SharedPeel(frame.plans, *frame.previous) : std::vector<CellId>{},
      frame.cells);
}

void TwoLevelScheduler::BeginFrame(const FrameInfo& frame) {
  std::vector<CellId> plan;
  if (frame.previous != nullptr) {
    const std::vector<CellId> board = BoardCellOf(frame);
    plan = *Shared<std::vector<CellId>>(
        frame.plans, PlanKey(kTwoLevelPeelPlan, {TreeKey(*frame.previous), BoardKey(board)}),
        [&] { return TwoLevelPeel(*frame.previous, board); });
  }
  follower_.Reset(std::move(plan), frame.cells);
}

}  // namespace raycell
