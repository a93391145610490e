// What a replay did, moment by moment, for whoever wants to watch it (the timeline writer,
// runner/timeline.h). The replay core (replay/replayer.h) and the memory levels
// (replay/memory.h) call a ReplayObserver when one is given; they hold a null pointer
// otherwise, and every call is behind a test of that pointer, so a replay without an
// observer does no observer work, and a replay with one gives the same results byte for byte.
//
// Times are a run's own simulated time: each run of a frame starts at zero. Calls come in the
// replay's event order, so a processor's calls come in time order; transfers may be reported
// before they start (a link still busy with an earlier one), but each link's in time order.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/time.h"
#include "traces/ray_batch.h"

namespace raycell {

class ReplayObserver {
 public:
  virtual ~ReplayObserver() = default;

  // A run of frame `frame_index` (FrameInfo::frame_index) starts. A frame is run more than
  // once with Belady's MIN replacement (see ReplayFrame): a second BeginRun of the same frame
  // means the first run's calls are to be forgotten; only the last run is the result.
  // `queued_rays[c]`: the rays queued at cell c, kept up to date by the core until EndRun
  // (the observer reads it when it wants to, e.g. at the calls below).
  virtual void BeginRun(std::size_t frame_index, const std::vector<std::uint64_t>& queued_rays) = 0;
  // Processor p asked for `cell` at `request` and has it at `ready` (a stall of ready -
  // request, zero on a cache hit). `miss`: the cell was brought into p's cache by this fetch
  // (it counts in levels[0].fetches); false when it was there or on its way (prefetched).
  // `reason`: the scheduler's Reason() for choosing it (may be empty). Its batch of work
  // starts at `ready`.
  virtual void Fetch(std::uint32_t p, CellId cell, SimTime request, SimTime ready, bool miss,
                     const std::string& reason) = 0;
  // Processor p took the queue of its cell, `rays` queued rays, into its batch at `now`.
  virtual void QueueTaken(std::uint32_t p, CellId cell, std::uint64_t rays, SimTime now) = 0;
  // Processor p's batch of work on `cell` ended at `now` (its queue empty, the cell released);
  // it worked without a break since the `ready` of its Fetch.
  virtual void BatchEnd(std::uint32_t p, CellId cell, SimTime now) = 0;
  // A cell crossed the link below memory level `level` (0: the processors' caches) into
  // `copy` of that level (the processor for level 0, else 0), from `start` to `end`, for
  // processor `processor`; `prefetch`: started by a prefetch, not by a fetch. `cell` is the
  // level's unit: a cell of the level's own subdivision when it has one (level.NAME.cells,
  // replay/memory.h LevelUnits), with `bytes` its footprint.
  virtual void Transfer(std::size_t level, std::uint32_t copy, CellId cell, std::uint64_t bytes,
                        SimTime start, SimTime end, std::uint32_t processor, bool prefetch) = 0;
  // The run ended at `end`: every unit done (the result's `time`).
  virtual void EndRun(SimTime end) = 0;
};

}  // namespace raycell
