#include "scheduling/peel_oracle.h"

#include "base/check.h"
#include "scheduling/plan_cache.h"

namespace raycell {

constexpr SchedulerEntry kPeelEntry = [] {
  SchedulerEntry e;
  e.name = "peel";
  e.meaning = "the Peel oracle: each frame follows its own tree's Peel schedule";
  e.label = "Peel oracle (the frame's own Peel schedule)";
  e.history = 0;  // reads no earlier frame
  e.make = [](std::uint64_t) -> std::unique_ptr<Scheduler> {
    return std::make_unique<PeelOracleScheduler>();
  };
  e.oracle = true;
  return e;
}();

void PeelOracleScheduler::BeginFrame(const FrameInfo& frame) {
  RAYCELL_CHECK(frame.current != nullptr);
  follower_.Reset(*SharedPeel(frame.plans, *frame.current), frame.cells);
}

}  // namespace raycell
