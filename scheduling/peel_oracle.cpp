#include "scheduling/peel_oracle.h"

#include "base/check.h"
#include "graph/peel.h"

namespace raycell {

void PeelOracleScheduler::BeginFrame(const FrameInfo& frame) {
  RAYCELL_CHECK(frame.current != nullptr);
  follower_.Reset(Peel(*frame.current).schedule, frame.cells);
}

}  // namespace raycell
