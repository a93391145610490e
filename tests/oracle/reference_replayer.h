// The reference replay of one frame: the event-per-unit Board on the engine's Simulator that
// replay/replayer.cpp had before its batch core, kept (test-only) so that the fast core can
// be checked against it field by field on random frames.
#pragma once

#include "replay/replayer.h"

namespace raycell {

// As ReplayFrame (replay/replayer.h), the same results by the slow road.
ReplayResult ReferenceReplayFrame(const WorkGraph& work,
                                  const std::vector<std::uint64_t>& footprints,
                                  const ReplayConfig& config, Scheduler& scheduler,
                                  const FrameTrees& frame, std::uint64_t bound);

}  // namespace raycell
