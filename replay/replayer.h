// The GI-Cube replay of one frame (docs/design.md §2), a discrete-event model: block
// processors ask the scheduler for a cell, fetch it through the memory levels, and work every
// unit queued there (ray segments or Cell Tree nodes, see work.h); finished units release
// their successors into the per-cell queues.
//
// The events (a processor's call for a cell, the end of its fetch, the end of each unit) run
// on the engine's SlotQueue (engine/slot_queue.h), one slot per processor since a processor
// has at most one pending event, in the engine's order: the results are those of the same
// events on the independent oracle, a general event engine (tests/oracle/simulator.h) and the
// reference replayer on it (tests/oracle/reference_replayer.cpp), checked equal field by
// field, `events` included. A cell's queue (a flat array of units, each carrying its samples
// and where its successors are) is handed to the processor whole, to be worked through in its
// own loop: a batch per fetch.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "engine/time.h"
#include "replay/config.h"
#include "replay/memory.h"
#include "replay/observer.h"
#include "replay/work.h"
#include "scheduling/scheduler.h"

namespace raycell {

struct ReplayResult {
  std::int32_t frame = 0;
  std::vector<LevelStats> levels;      // fetches and bytes into each level
  std::uint64_t fetches = 0;           // into the processors' caches (levels[0].fetches)
  std::optional<std::uint64_t> bound;  // maxGen bound, where it holds (1 processor, 1 cell)
  SimTime time;                        // until the last unit is done
  SimTime time_bound;                  // <= time under any scheduler (replay/time_bound.h)
  SimTime work, stall, idle;           // summed over processors; each processor's add up
                                       // to `time`
  double utilisation = 0;              // work / (time * processors)
  std::uint64_t peak_queued_rays = 0, peak_queued_bytes = 0;
  std::uint64_t rays = 0, segments = 0, samples = 0;  // processed; equal the trace's
  std::uint64_t events = 0;                           // engine events handled
  std::uint64_t prefetches = 0;                       // cells prefetched while another was worked
  std::uint64_t prefetch_hits = 0;                    // of them, fetched next from the cache
  // What deciding cost the scheduler (Scheduler::Cost; zeros for one that does not count):
  // cells chosen, elementary steps spent planning and choosing, most bytes of state kept.
  std::uint64_t decisions = 0, decision_steps = 0, scheduler_bytes = 0;
  // Runs of the frame: 1, or more with MIN replacement (see ReplayFrame).
  std::uint32_t passes = 1;
  bool min_converged = true;  // MIN's last run made exactly the requests it was told
};

// What the caller knows of a frame: its index and trees (the leading fields of FrameInfo, in
// the same order). The replay makes the FrameInfo the scheduler is told from it (MakeFrameInfo).
struct FrameTrees {
  std::size_t frame_index = 0;
  const CellTree* current = nullptr;   // this frame's tree
  const CellTree* previous = nullptr;  // the previous frame's tree; null for frame 0
  std::uint32_t cells = 0;             // cells of the grid; every tree's cell_count() <= cells
  const CellTree* before_previous = nullptr;  // frame i-2's tree, for history 2; else null
  PlanCache* plans = nullptr;                 // FrameInfo::plans (null: none shared)
  // Threads the replays of frames seen (FrameInfo::seen) may run on at once, >= 1: work of
  // this configuration's own (auto's check) that no result depends on (SeenFrameReplayer).
  unsigned threads = 1;
};

// The FrameInfo a replay tells `scheduler` (BeginFrame), made here and nowhere else: `frame`'s
// index and trees, `fetch_samples` (FetchSamples; must outlive the result), the processor
// count, the current tree only for an oracle (any other scheduler learns the frame only from
// what is queued, and may begin it before its tree is built: FrameStart), and the board's cells
// from the nearest level of `units` that holds coarser cells (null: none).
FrameInfo MakeFrameInfo(const FrameTrees& frame, const ReplayConfig& config,
                        const std::vector<double>& fetch_samples, const MemoryUnits* units,
                        const Scheduler& scheduler);

// What a replay tells its scheduler at the frame's start, made before the frame's work so that
// it may begin first (issue 43): BeginFrame reads only earlier frames (an oracle excepted), so
// the runner begins every replay of a frame, frees frame i-2's tree, and only then builds the
// frame's tree and work (runner/driver.cpp ReplayFrames; docs/design.md §2 "What a replay
// holds"). It keeps what the scheduler may point into (the fetch costs, the replayer of frames
// seen) until the replay ends. `memory` (null: empty) must not change until then.
class FrameStart {
 public:
  FrameStart(const std::vector<std::uint64_t>& footprints, const ReplayConfig& config,
             const Scheduler& scheduler, const FrameTrees& frame, const MemoryState* memory,
             const MemoryUnits* units, bool seen = true);
  ~FrameStart();
  FrameStart(const FrameStart&) = delete;
  FrameStart& operator=(const FrameStart&) = delete;
  // scheduler.BeginFrame(info()); the replay given this start then tells it nothing more before
  // its board runs (only MIN's later passes begin the frame again).
  void Begin(Scheduler& scheduler);
  bool begun() const { return begun_; }
  const FrameInfo& info() const { return info_; }

 private:
  std::vector<double> fetch_samples_;
  std::unique_ptr<SeenFrameReplayer> seen_;
  FrameInfo info_;
  bool begun_ = false;
};

// Replays one frame; calls scheduler.BeginFrame(MakeFrameInfo(frame, ...)) itself, unless
// `start` (made for the same frame, configuration, memory and units) has begun it. `config` has
// passed CheckReplay for `work.cells` cells. `bound` is the frame's maxGen bound (reported only
// where it holds).
//
// Belady's MIN needs each level's future requests. A level with MIN first runs LRU to learn
// them; the frame is then replayed with MIN on those requests, again on the requests that run
// made, until a run makes exactly the requests it was given (at most levels + 1 runs;
// min_converged says whether it got there). With one processor the order of cell requests
// does not depend on the caches, so MIN on the processors' caches is exact after one rerun.
//
// `observer` (replay/observer.h), when not null, is told what each run does; the result is the
// same with or without one.
//
// `memory`, when not null, is what the levels hold when the frame starts (empty: nothing) and
// is replaced by what they hold when it ends: the caller carries it to the next frame when
// memory is warm (docs/design.md §2 "Memory"). With a warm cell in the cache, the maxGen bound
// reported is one less: a schedule may start with that cell without fetching it.
//
// `units` (null: every level holds the cells) gives the levels that hold coarser cells
// (level.NAME.cells; replay/memory.h LevelUnits), as LevelUnitsOf makes them; the scheduler is
// told the nearest such level's map (FrameInfo::board_cell_of).
//
// `seen`: the scheduler is given FrameInfo::seen, which replays earlier frames' trees per node
// on this frame's board (from what `memory` holds at its start); false within such a replay.
ReplayResult ReplayFrame(const WorkGraph& work, const std::vector<std::uint64_t>& footprints,
                         const ReplayConfig& config, Scheduler& scheduler, const FrameTrees& frame,
                         std::uint64_t bound, ReplayObserver* observer = nullptr,
                         MemoryState* memory = nullptr, const MemoryUnits* units = nullptr,
                         bool seen = true, FrameStart* start = nullptr);

// Per cell, what the schedulers are told a fetch costs (FrameInfo::fetch_samples): the first
// link's latency + footprint / bandwidth, in units of one sample's work.
std::vector<double> FetchSamples(const ReplayConfig& config,
                                 const std::vector<std::uint64_t>& footprints);

// Whether the maxGen bound holds for `config`: one processor whose cache holds one cell.
bool BoundHolds(const ReplayConfig& config);

// InputError when `config` cannot be replayed though it is valid as a configuration:
// prefetch with a cache of fewer than two cells. Part of CheckReplay.
void CheckReplayable(const ReplayConfig& config);

// Largest processors x cells of a replay. The memory model keeps, per processor and cell, an
// arrival time (8 bytes) and a prefetch flag: 1 GiB at this limit (e.g. 8 processors at
// 256x256x256 cells).
inline constexpr std::uint64_t kMaxProcessorCells = std::uint64_t{1} << 27;

// InputError naming processors.count, the cell count and the limit when `config` on a trace
// of `cells` cells exceeds kMaxProcessorCells. Part of CheckReplay.
void CheckModelSize(const ReplayConfig& config, std::uint64_t cells);

// What the model needs of a configuration before it replays a trace of `cells` cells:
// CheckReplayable, then CheckModelSize. The runner calls it once per configuration when it
// opens a trace for replay (runner/driver.h ReplayFrames; a sweep for every combination
// before its first block), before any frame is read; ReplayFrame takes a checked
// configuration and does not repeat it.
void CheckReplay(const ReplayConfig& config, std::uint64_t cells);

}  // namespace raycell
