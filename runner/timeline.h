// A replay as a Chrome trace-event file (the JSON object format of the "Trace Event Format"
// that Perfetto's UI and chrome://tracing open): `raycell replay TRACE --timeline FILE.json`.
// Its keys are documented in docs/schemas.md ("raycell replay --timeline").
//
// One process; one thread (track) per block processor and one per memory level's link (per
// processor for level 0, whose caches are per processor). The frames are laid end to end:
// frame k starts where frame k-1 ended, marked by a global instant event "frame N".
//  - A processor's track is tiled with complete events ("ph":"X"), without gaps or overlaps
//    from 0 to the end of the last frame: "fetch cell C" (a fetch stall; a fetch that stalled
//    nothing but brought the cell, e.g. with unlimited bandwidth and no latency, has
//    duration 0), "cell C" (a batch of work: the cell's queue worked without a break, with
//    the rays taken from its queue, the samples, the cell's bytes and the scheduler's
//    reason), and "idle". Their args.dur_ps add up exactly to the result's work, stall and
//    idle.
//  - A level's track holds its transfers: "cell C", bytes, the processor it was for, and
//    whether a prefetch started it.
//  - Counters ("ph":"C"): the rays queued in all cells, and in each cell that ever has some,
//    sampled when a processor asks for a cell, takes a queue or ends a batch, and at each
//    frame's start and end (between those moments queues change at every unit done; that
//    many events would not fit the size limit).
//
// Times: the simulated time is integer picoseconds; the file's unit is the microsecond. "ts"
// and "dur" are rounded to the nanosecond, each boundary once (dur = end rounded - start
// rounded), because Perfetto keeps nanoseconds and rounds ts and dur separately: exact
// picoseconds in ts and dur would make slices that meet overlap by a nanosecond there. The
// exact picoseconds are in every slice's args: "ps" (start) and "dur_ps".
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "replay/config.h"
#include "replay/observer.h"

namespace raycell {

// "raycell-timeline/1", in the file's otherData.schema.
extern const char* const kTimelineSchema;
// The default limit on a timeline's size: about 256 MB (256 MiB).
constexpr std::uint64_t kTimelineLimitBytes = std::uint64_t(256) << 20;

struct TimelineOptions {
  std::string trace;  // the trace file, for otherData
  // Frame numbers by frame index (FrameInfo::frame_index), for names and args.
  std::vector<std::int32_t> frame_numbers;
  // The file may not grow past this many bytes: InputError (suggesting --frames) instead.
  std::uint64_t limit_bytes = kTimelineLimitBytes;
  std::string what = "--timeline";  // names the output in messages
};

// Writes the timeline of the replays it observes to `out`, a frame at a time (a frame's
// events are held until the frame's last run is known, see ReplayObserver::BeginRun). Call
// Finish after the last frame. Before any byte past the limit is written, an InputError names
// the limit and the frames that fit; the caller removes what was written (a temporary file).
class TimelineWriter : public ReplayObserver {
 public:
  TimelineWriter(std::ostream& out, const ReplayConfig& config,
                 const std::vector<std::uint64_t>& footprints, TimelineOptions options);

  void BeginRun(std::size_t frame_index, const std::vector<std::uint64_t>& queued_rays) override;
  void Fetch(std::uint32_t p, CellId cell, SimTime request, SimTime ready, bool miss,
             const std::string& reason) override;
  void QueueTaken(std::uint32_t p, CellId cell, std::uint64_t rays, SimTime now) override;
  void BatchEnd(std::uint32_t p, CellId cell, SimTime now) override;
  void Transfer(std::size_t level, std::uint32_t copy, CellId cell, std::uint64_t bytes,
                SimTime start, SimTime end, std::uint32_t processor, bool prefetch) override;
  void EndRun(SimTime end) override;

  // Writes the last frame and closes the document.
  void Finish();
  std::uint64_t bytes_written() const { return written_; }

 private:
  struct ProcessorState {
    std::uint64_t last_end = 0;  // ps, in the run: where the track's tiling has got to
    std::uint64_t batch_start = 0, batch_rays = 0;
    std::string reason;
  };

  // InputError when `more` bytes would take the file past the limit.
  void CheckLimit(std::uint64_t more) const;
  void Append(const std::string& event);
  void Commit();  // the pending frame's events to `out`
  void Slice(std::uint32_t tid, const char* cat, const std::string& name, std::uint64_t start,
             std::uint64_t end, const std::string& args);
  void Idle(std::uint32_t p, std::uint64_t until);
  void Counters(std::uint64_t now);
  std::uint32_t LevelTid(std::size_t level, std::uint32_t copy) const;
  std::string FrameArg() const;

  std::ostream& out_;
  ReplayConfig config_;
  const std::vector<std::uint64_t>& footprints_;
  TimelineOptions options_;
  std::uint64_t written_ = 0;
  std::string pending_;  // the current frame's events, each preceded by ",\n"
  bool have_frame_ = false, run_ended_ = false;
  std::size_t frame_index_ = 0;
  std::uint64_t offset_ = 0;     // ps: where the current frame starts in the timeline
  std::uint64_t run_end_ = 0;    // ps, in the run: the last run's end
  std::size_t frames_done_ = 0;  // committed
  std::int32_t first_frame_ = 0, last_frame_ = 0;
  std::vector<ProcessorState> processors_;
  const std::vector<std::uint64_t>* queued_ = nullptr;
  std::vector<std::uint64_t> shown_;  // counter values last written, per cell
  std::uint64_t shown_total_ = 0;
};

}  // namespace raycell
