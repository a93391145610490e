#include "runner/timeline.h"

#include <ostream>

#include "base/check.h"
#include "base/checked.h"
#include "base/format.h"

namespace raycell {

const char* const kTimelineSchema = "raycell-timeline/1";

namespace {

constexpr int kPid = 1;

// Picoseconds as the file's microseconds, rounded to the nearest nanosecond (half up):
// "12.345" (12 345 ns).
std::string Micros(std::uint64_t ns) {
  std::string frac = std::to_string(ns % 1000);
  return std::to_string(ns / 1000) + "." + std::string(3 - frac.size(), '0') + frac;
}

std::uint64_t Nanos(std::uint64_t ps) { return ps / 1000 + (ps % 1000 >= 500 ? 1 : 0); }

std::string CellName(CellId c) { return "cell " + std::to_string(c.value()); }

std::string Meta(const char* name, std::uint32_t tid, const std::string& args) {
  return "{\"ph\":\"M\",\"pid\":" + std::to_string(kPid) + ",\"tid\":" + std::to_string(tid) +
         ",\"name\":\"" + name + "\",\"args\":{" + args + "}}";
}

}  // namespace

TimelineWriter::TimelineWriter(std::ostream& out, const ReplayConfig& config,
                               const std::vector<std::uint64_t>& footprints,
                               TimelineOptions options)
    : out_(out),
      config_(config),
      footprints_(footprints),
      options_(std::move(options)),
      processors_(config.processors.count),
      shown_(footprints.size(), 0) {
  // Track ids: processors 1..P, then the caches' links (one per processor), then the other
  // levels'; the sort index keeps that order in chrome://tracing (Perfetto orders on its own).
  std::string head =
      "{\"traceEvents\":[\n" + Meta("process_name", 0, "\"name\":" + JsonQuote("raycell replay"));
  const std::uint32_t procs = config_.processors.count;
  const auto track = [&](std::uint32_t tid, const std::string& name) {
    head += ",\n" + Meta("thread_name", tid, "\"name\":" + JsonQuote(name));
    head += ",\n" + Meta("thread_sort_index", tid, "\"sort_index\":" + std::to_string(tid));
  };
  for (std::uint32_t p = 0; p < procs; ++p) track(1 + p, "processor " + std::to_string(p));
  for (std::size_t i = 0; i < config_.levels.size(); ++i) {
    const std::string into = "transfers into " + config_.levels[i].name;
    if (i > 0) {
      track(LevelTid(i, 0), into);
      continue;
    }
    for (std::uint32_t p = 0; p < procs; ++p) {
      track(LevelTid(0, p), into + " of processor " + std::to_string(p));
    }
  }
  Append(head);
  Commit();  // the metadata, so that a rerun of the first frame cannot forget it
}

std::uint32_t TimelineWriter::LevelTid(std::size_t level, std::uint32_t copy) const {
  const std::uint32_t procs = config_.processors.count;
  return level == 0 ? 1 + procs + copy : 2 * procs + std::uint32_t(level);
}

void TimelineWriter::CheckLimit(std::uint64_t more) const {
  if (written_ + pending_.size() + more > options_.limit_bytes) {
    std::string fit = frames_done_ == 0 ? "no frame fits"
                                        : "frames " + std::to_string(first_frame_) + ".." +
                                              std::to_string(last_frame_) + " fit";
    throw InputError(options_.what + ": the timeline would exceed " +
                     std::to_string(options_.limit_bytes) + " bytes (" + fit +
                     "); replay fewer frames with --frames A..B");
  }
}

void TimelineWriter::Append(const std::string& event) {
  const bool separate = !pending_.empty() || written_ > 0;
  CheckLimit(event.size() + (separate ? 2 : 0));
  if (separate) pending_ += ",\n";
  pending_ += event;
}

void TimelineWriter::Commit() {
  out_ << pending_;
  written_ += pending_.size();
  pending_.clear();
  if (!have_frame_) return;
  const std::int32_t n = options_.frame_numbers[frame_index_];
  if (frames_done_++ == 0) first_frame_ = n;
  last_frame_ = n;
  offset_ = CheckedAdd(offset_, run_end_);
  have_frame_ = false;
}

std::string TimelineWriter::FrameArg() const {
  return "\"frame\":" + std::to_string(options_.frame_numbers[frame_index_]);
}

void TimelineWriter::BeginRun(std::size_t frame_index,
                              const std::vector<std::uint64_t>& queued_rays) {
  RAYCELL_CHECK_LT(frame_index, options_.frame_numbers.size());
  RAYCELL_CHECK_EQ(queued_rays.size(), footprints_.size());
  if (have_frame_ && frame_index == frame_index_) {
    pending_.clear();  // a rerun (MIN): the earlier run is forgotten
    // Every run ends with empty queues, so the counters shown are as at the frame's start.
  } else {
    Commit();
  }
  have_frame_ = true;
  run_ended_ = false;
  frame_index_ = frame_index;
  queued_ = &queued_rays;
  processors_.assign(processors_.size(), ProcessorState{});
  const std::int32_t n = options_.frame_numbers[frame_index];
  Append("{\"ph\":\"i\",\"s\":\"g\",\"pid\":" + std::to_string(kPid) +
         ",\"tid\":0,\"ts\":" + Micros(Nanos(offset_)) + ",\"name\":\"frame " + std::to_string(n) +
         "\",\"args\":{" + FrameArg() + ",\"ps\":" + std::to_string(offset_) + "}}");
  shown_total_ = UINT64_MAX;  // the total is shown at every frame's start
  Counters(0);
}

void TimelineWriter::Slice(std::uint32_t tid, const char* cat, const std::string& name,
                           std::uint64_t start, std::uint64_t end, const std::string& args) {
  RAYCELL_CHECK_LE(start, end);
  const std::uint64_t s = CheckedAdd(offset_, start), e = CheckedAdd(offset_, end);
  Append("{\"ph\":\"X\",\"pid\":" + std::to_string(kPid) + ",\"tid\":" + std::to_string(tid) +
         ",\"ts\":" + Micros(Nanos(s)) + ",\"dur\":" + Micros(Nanos(e) - Nanos(s)) + ",\"cat\":\"" +
         cat + "\",\"name\":" + JsonQuote(name) + ",\"args\":{" + args + (args.empty() ? "" : ",") +
         FrameArg() + ",\"ps\":" + std::to_string(s) + ",\"dur_ps\":" + std::to_string(e - s) +
         "}}");
}

void TimelineWriter::Idle(std::uint32_t p, std::uint64_t until) {
  ProcessorState& ps = processors_[p];
  RAYCELL_CHECK_LE(ps.last_end, until);
  if (until > ps.last_end) Slice(1 + p, "idle", "idle", ps.last_end, until, "");
  ps.last_end = until;
}

// The queued rays of the cells whose count changed since last shown, and their total.
void TimelineWriter::Counters(std::uint64_t now) {
  const std::string ts = Micros(Nanos(CheckedAdd(offset_, now)));
  const auto counter = [&](const std::string& name, std::uint64_t rays) {
    Append("{\"ph\":\"C\",\"pid\":" + std::to_string(kPid) + ",\"ts\":" + ts +
           ",\"name\":" + JsonQuote(name) + ",\"args\":{\"rays\":" + std::to_string(rays) + "}}");
  };
  std::uint64_t total = 0;
  for (CellId c : CellRange(shown_.size())) {
    const std::uint64_t q = (*queued_)[c.value()];
    total += q;
    if (q == shown_[c.value()]) continue;
    shown_[c.value()] = q;
    counter("queue: " + CellName(c), q);
  }
  if (total != shown_total_) counter("queue: all cells", total);
  shown_total_ = total;
}

void TimelineWriter::Fetch(std::uint32_t p, CellId cell, SimTime request, SimTime ready, bool miss,
                           const std::string& reason) {
  Idle(p, request.picoseconds());
  Counters(request.picoseconds());
  ProcessorState& ps = processors_[p];
  if (miss || ready > request) {
    Slice(1 + p, "fetch", "fetch " + CellName(cell), request.picoseconds(), ready.picoseconds(),
          "\"cell\":" + std::to_string(cell.value()) + ",\"bytes\":" +
              std::to_string(footprints_[cell.value()]) + ",\"miss\":" + (miss ? "true" : "false"));
  }
  ps.last_end = ready.picoseconds();
  ps.batch_start = ready.picoseconds();
  ps.batch_rays = 0;
  ps.reason = reason;
}

void TimelineWriter::QueueTaken(std::uint32_t p, CellId, std::uint64_t rays, SimTime now) {
  processors_[p].batch_rays += rays;
  Counters(now.picoseconds());
}

void TimelineWriter::BatchEnd(std::uint32_t p, CellId cell, SimTime now) {
  ProcessorState& ps = processors_[p];
  const std::uint64_t end = now.picoseconds(),
                      tps = config_.processors.time_per_sample.picoseconds();
  // The batch is worked without a break: its length is its samples' work.
  RAYCELL_CHECK_EQ((end - ps.batch_start) % tps, 0u);
  std::string args = "\"cell\":" + std::to_string(cell.value()) +
                     ",\"rays\":" + std::to_string(ps.batch_rays) +
                     ",\"samples\":" + std::to_string((end - ps.batch_start) / tps) +
                     ",\"bytes\":" + std::to_string(footprints_[cell.value()]);
  if (!ps.reason.empty()) args += ",\"reason\":" + JsonQuote(ps.reason);
  Slice(1 + p, "work", CellName(cell), ps.batch_start, end, args);
  ps.last_end = end;
  Counters(end);
}

void TimelineWriter::Transfer(std::size_t level, std::uint32_t copy, CellId cell,
                              std::uint64_t bytes, SimTime start, SimTime end,
                              std::uint32_t processor, bool prefetch) {
  Slice(LevelTid(level, copy), "transfer", CellName(cell), start.picoseconds(), end.picoseconds(),
        "\"cell\":" + std::to_string(cell.value()) + ",\"bytes\":" + std::to_string(bytes) +
            ",\"processor\":" + std::to_string(processor) +
            ",\"prefetch\":" + (prefetch ? "true" : "false"));
}

void TimelineWriter::EndRun(SimTime end) {
  for (std::uint32_t p = 0; p < processors_.size(); ++p) Idle(p, end.picoseconds());
  Counters(end.picoseconds());
  run_end_ = end.picoseconds();
  run_ended_ = true;
  queued_ = nullptr;
}

void TimelineWriter::Finish() {
  RAYCELL_CHECK(!have_frame_ || run_ended_);
  Commit();
  std::string levels;
  for (const LevelConfig& l : config_.levels)
    levels += (levels.empty() ? "" : ",") + JsonQuote(l.name);
  const std::string tail =
      "\n],\n\"otherData\":{\"schema\":" + JsonQuote(kTimelineSchema) +
      ",\"trace\":" + JsonQuote(options_.trace) +
      ",\"scheduler\":" + JsonQuote(config_.scheduler_name()) +
      ",\"granularity\":" + JsonQuote(std::string(ToString(EffectiveGranularity(config_)))) +
      ",\"processors\":" + std::to_string(config_.processors.count) + ",\"levels\":[" + levels +
      "],\"frames\":" + std::to_string(frames_done_) + ",\"time_ps\":" + std::to_string(offset_) +
      "}}\n";
  CheckLimit(tail.size());
  out_ << tail;
  written_ += tail.size();
}

}  // namespace raycell
