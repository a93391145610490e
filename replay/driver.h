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
//
// Sampling (sample_every = k > 1) replays only 1 in k ray trees of each frame (a primary ray
// with all its descendants, SampleRayTrees) and scales back what grows with the rays: rays,
// segments, samples and work times k, and the simulated time by the added work spread over
// the processors. Fetches, stall and the bound are those of the sample: the error the
// sampling makes is what tools/bench/accuracy.py measures.
//
// `observer` (may be null) watches every frame's replay (ReplayFrame); it needs
// sample_every = 1, since it would see the sample's times, not the scaled ones.
TraceReplay ReplayTrace(const TraceReader& reader, const std::vector<std::size_t>& frame_indices,
                        const ReplayConfig& config,
                        const std::function<void(double)>& progress = {},
                        std::uint32_t sample_every = 1, ReplayObserver* observer = nullptr);

}  // namespace raycell
