// Replaying the frames of a trace: each frame's rays, its Cell Tree (for the bound and the
// Peel oracle) and the previous frame's (for Cell Tree scheduling).
//
// Decode once, replay many: ReplayFrames walks the frames once, decoding each and building
// its trees and work graphs once, and replays every configuration on it (on `jobs` threads)
// before it moves to the next frame. ReplayTrace, sweeps and the study all go through it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "graph/cell_tree.h"
#include "replay/config.h"
#include "replay/level_units.h"
#include "replay/replayer.h"
#include "replay/work.h"
#include "scheduling/plan_cache.h"
#include "traces/trace_reader.h"

namespace raycell {

struct TraceReplay {
  std::vector<ReplayResult> frames;
  ReplayResult total;  // sums; peaks are maxima; bound summed where it holds
};

// Adds frame result `f` to the running total `t` as TraceReplay::total is formed: counts,
// bytes and times summed (time_bound too: each frame starts at time 0), peaks and passes as
// maxima, the bound summed where it holds, min_converged only if every frame's. Utilisation
// is not summed: FinishTotal sets it.
void Accumulate(const ReplayResult& f, ReplayResult* t);
// Sets a total's utilisation from its summed times: work / (time x processors), as a frame's.
void FinishTotal(std::uint32_t processors, ReplayResult* t);

// One frame as the replays need it, built once for all configurations.
struct LoadedFrame {
  std::size_t position = 0;  // in the list of frames asked for (warm-up: of the next one)
  // A frame replayed only for the memory state it leaves (FrameWalker's warm_up), not
  // reported.
  bool warm_up = false;
  std::size_t index = 0;    // into reader.frames()
  std::int32_t number = 0;  // the frame number
  // Null when no replay reads it (FrameWalker's keep_tree). Parked (CellTree::parked) once the
  // frame's replays ran where they began before it was built (ReplayFrames): a caller that
  // reads it then unparks a copy.
  std::unique_ptr<CellTree> tree;
  // Frame index - 1's; null for index 0 or history 0. Parked as `tree` where no replay of the
  // frame reads it once begun (Scheduler::ReadsEarlierTrees).
  std::unique_ptr<CellTree> previous;
  // Frame index - 2's, when a scheduler reads two earlier frames (SchedulerHistory); else null.
  std::unique_ptr<CellTree> before_previous;
  std::uint64_t bound = 0;  // of the frame's tree (0 when it was not built)
  // The cells' footprints in this frame (TraceReader::FrameFootprints: a dynamic
  // subdivision's own, else the header's); the reader's, valid while it is.
  const std::vector<std::uint64_t>* footprints = nullptr;
  std::unique_ptr<WorkGraph> segments;  // per ray segment, when some replay needs it
  std::unique_ptr<WorkGraph> nodes;     // per Cell Tree node, when some replay needs it
};

// Walks the frames at `frame_indices` (indices into reader.frames(), increasing), loading
// each once: its Cell Tree, the previous frame's (kept from the step before, or loaded when
// the indices skip it), and the work graphs asked for. With sample_every = k > 1 the frame is
// 1 in k ray trees (SampleRayTrees), the previous tree too. Rays are dropped once the work
// graphs are built: memory holds one frame.
class FrameWalker {
 public:
  // history: earlier frames' trees to keep (0: none; 1: the previous; 2: also the one before
  // it). keep_tree: whether a replay reads the frame's own tree (an oracle, the maxGen bound
  // where it holds); with neither, LoadedFrame::tree is null, the tree built only when the work
  // per node is made from it (and bound 0), so that a frame holds no tree it does not need.
  // The per-segment work of a frame of more than `compact_above_visits` visits (not sampled)
  // is built in the Compact form (work.h) from the frame's batches, without holding its rays.
  // warm_up: also walk every frame before the last one asked for that is not asked for,
  // marked LoadedFrame::warm_up (warm memory needs the frames before a range replayed).
  FrameWalker(const TraceReader& reader, std::vector<std::size_t> frame_indices, bool need_segments,
              bool need_nodes, std::uint32_t sample_every = 1, std::uint32_t history = 1,
              std::uint64_t compact_above_visits = kCompactAboveVisits, bool warm_up = false,
              bool keep_tree = true);
  // The next frame with its earlier trees (previous, before_previous) but not yet its own
  // tree, work and bound, or nullptr after the last; valid until the next call. The replays
  // may begin it (FrameStart) and frame i-2's tree be released before Build makes the rest
  // (issue 43).
  LoadedFrame* Advance();
  // Builds the frame Advance returned: its tree (where kept), work graphs and bound.
  void Build();
  // The last frame walked keeps no tree for a next frame (none follows, and the caller reads
  // no LoadedFrame::tree): it is built only where a replay reads it (keep_tree) or the work per
  // node is made from it.
  void SkipLastTree() { skip_last_tree_ = true; }
  // Frees the current frame's before_previous (frame i-2's tree) once no replay of the frame
  // will read it again: schedulers read it only in BeginFrame (ReplayFrames calls this after
  // the last replay of the frame began; issue 43). The next frame loads it again if it needs it.
  void ReleaseBeforePrevious() { frame_.before_previous.reset(); }
  // Frames asked for; frames walked (with the warm-up ones).
  std::size_t size() const { return asked_; }
  std::size_t walked() const { return indices_.size(); }

 private:
  const TraceReader& reader_;
  std::vector<std::size_t> indices_;  // walked
  std::vector<bool> asked_for_;       // per walked frame
  std::size_t asked_ = 0, reported_ = 0;
  bool need_segments_, need_nodes_;
  std::uint32_t k_, history_;
  bool own_tree_;  // a replay reads the frame's own tree (keep_tree)
  bool skip_last_tree_ = false;
  std::uint64_t compact_above_;
  std::size_t position_ = 0;
  LoadedFrame frame_;
};

// Replays `frame` under `config` with `scheduler` (made by MakeScheduler for the config and
// kept across frames): ReplayFrame on the frame's work graph of the config's granularity,
// scaled back when the frame is sampled (see ReplayTrace), numbered.
// `memory`: as ReplayFrame takes it (null: cold).
// `units`: the levels' units (LevelUnitsOf; null: every level holds the cells).
// `plans`: where the scheduler's plans for this frame are shared with other configurations
// (FrameInfo::plans; null: none).
// `start`: made by StartLoadedFrame for this frame, configuration, scheduler, memory, units and
// plans, and begun (FrameStart::Begin); null: the replay begins the frame itself.
// `threads`: what the replays of frames seen may run on at once (FrameTrees::threads).
ReplayResult ReplayLoadedFrame(const LoadedFrame& frame, const TraceHeader& header,
                               const ReplayConfig& config, Scheduler& scheduler,
                               std::uint32_t sample_every = 1, ReplayObserver* observer = nullptr,
                               MemoryState* memory = nullptr, const MemoryUnits* units = nullptr,
                               PlanCache* plans = nullptr, FrameStart* start = nullptr,
                               unsigned threads = 1);
// The start of `frame` (its earlier trees; not its own, which an oracle needs: not for one) as
// ReplayLoadedFrame would tell `scheduler` it, for the same arguments.
std::unique_ptr<FrameStart> StartLoadedFrame(const LoadedFrame& frame, const TraceHeader& header,
                                             const ReplayConfig& config, const Scheduler& scheduler,
                                             MemoryState* memory, const MemoryUnits* units,
                                             PlanCache* plans, unsigned threads = 1);

// What a frame's result cannot depend on, removed: granularity resolved (EffectiveGranularity),
// the seed unless the scheduler uses it (SchedulerEntry::seeded: random and the planners),
// prefetch for a scheduler that predicts nothing (SchedulerEntry::predicts: random, whose
// Scheduler::Peek answers nothing, so prefetch never happens), and the queue record size, which
// only scales peak_queued_bytes (ReplayFrames rescales it). Configurations with equal canonical
// forms have equal frame results up to that rescaling, so ReplayFrames replays each canonical form
// once.
ReplayConfig CanonicalConfig(const ReplayConfig& config);

struct ReplayFramesOptions {
  // Threads, >= 1: the configurations of a frame replay on up to `jobs` of them at once, and
  // each replay is given jobs / (those threads) for work of its own whose results do not
  // depend on it (FrameTrees::threads: auto's check, its replays of frames seen).
  unsigned jobs = 1;
  std::uint32_t sample_every = 1;  // 1 in k ray trees (see ReplayTrace)
  // Told the fraction of frames done, after each frame (may be empty).
  std::function<void(double)> progress;
  // Watches the replays (replay/observer.h); only with one configuration, not sampled.
  ReplayObserver* observer = nullptr;
  // Frames of more visits replay per segment from the Compact form (see FrameWalker).
  std::uint64_t compact_above_visits = kCompactAboveVisits;
  // The caller ran CheckReplay on every configuration for this trace (a sweep, for all its
  // combinations before its first block); else ReplayFrames runs it, once per configuration.
  bool checked = false;
  // Whether on_frame reads LoadedFrame::tree (the study's counts of nodes); false: the last
  // frame's tree is not built where no replay reads it, as no next frame plans from it.
  bool caller_reads_trees = true;
  // Plans shared across the configurations (docs/design.md §5 "Sharing plans"): one PlanCache
  // per frame for all of them, planning through the process-wide memo; false: one per
  // configuration and frame, each plan searched again (the results are the same: a test).
  bool share_plans = true;
};

struct ReplayFramesStats {
  std::size_t frames = 0;    // frames walked
  std::size_t distinct = 0;  // canonical configurations replayed per frame
  std::size_t plans = 0;     // values the schedulers' PlanCaches made, over the frames
  unsigned own_threads = 1;  // threads each replay was given for its own work (FrameTrees::threads)
  std::size_t begun_while_built = 0;  // frames whose replays began while the frame was built
};

// Replays every configuration on every frame of `frame_indices`, each frame loaded once (see
// FrameWalker), configurations that share a canonical form once (CanonicalConfig). A
// configuration with warm memory (memory.across_frames) carries each frame's memory state to
// the next; when some has it, the frames before the last one asked for that are not asked for
// are replayed first for it alone (warm-up, not reported), so that every frame starts from
// the state a replay of the whole trace gives it: frame ranges, shards and resumed sweeps
// give the rows of one run. After
// each frame, calls on_frame(frame, results) with the result of every configuration, in
// the order of `configs`, on the calling thread; it returns false to stop there. The
// results are those of ReplayTrace for each configuration alone, whatever `jobs`.
// InputError (CheckReplay, LevelUnitsOf) before any frame is read: the one check of each
// configuration against the trace.
using FrameResults = std::function<bool(const LoadedFrame&, const std::vector<ReplayResult>&)>;
ReplayFramesStats ReplayFrames(const TraceReader& reader,
                               const std::vector<std::size_t>& frame_indices,
                               const std::vector<ReplayConfig>& configs,
                               const ReplayFramesOptions& options, const FrameResults& on_frame);

// Replays the frames at `frame_indices` (indices into reader.frames(), increasing).
// `progress` (may be empty) is told the fraction done.
//
// Sampling (sample_every = k > 1) replays only 1 in k ray trees of each frame (a primary ray
// with all its descendants, SampleRayTrees) and scales back what grows with the rays: rays,
// segments, samples and work times k, and the simulated time and its lower bound
// (time_bound) by the added work spread over the processors (so the bound stays at most the
// time). Fetches, stall and the bound are those of the sample: the error the sampling makes
// is what the study's run time against error measures (study/accuracy.h).
//
// `observer` (may be null) watches every frame's replay (ReplayFrame); it needs
// sample_every = 1, since it would see the sample's times, not the scaled ones.
// `jobs`: threads the replay may use (ReplayFramesOptions::jobs); the results do not depend on it.
TraceReplay ReplayTrace(const TraceReader& reader, const std::vector<std::size_t>& frame_indices,
                        const ReplayConfig& config,
                        const std::function<void(double)>& progress = {},
                        std::uint32_t sample_every = 1, ReplayObserver* observer = nullptr,
                        unsigned jobs = 1);

}  // namespace raycell
