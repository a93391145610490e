// Replaying the frames of a trace: each frame's rays, its Cell Tree (for the bound and the
// Peel oracle) and the previous frame's (for Cell Tree scheduling).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "replay/config.h"
#include "replay/replayer.h"
#include "traces/trace_reader.h"

namespace raycell {

struct TraceReplay {
  std::vector<ReplayResult> frames;
  ReplayResult total;  // sums; peaks are maxima; bound summed where it holds
};

// Replays the frames at `frame_indices` (indices into reader.frames(), increasing).
// `progress` (may be empty) is told the fraction done.
TraceReplay ReplayTrace(const TraceReader& reader, const std::vector<std::size_t>& frame_indices,
                        const ReplayConfig& config,
                        const std::function<void(double)>& progress = {});

}  // namespace raycell
