// The replay's timeline (runner/timeline.h) against the replay's results: valid JSON; each
// processor's track tiled without gaps or overlaps, its slices adding up exactly to the
// reported work, stall and idle; fetches, transfers, bytes and frames as reported; the results
// the same with and without a timeline.
#include "runner/timeline.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <sstream>

#include "graph/cell_tree.h"
#include "replay/config.h"
#include "replay/replayer.h"
#include "replay/work.h"
#include "runner/result_table.h"
#include "scheduling/scheduler.h"
#include "tests/graph/test_trees.h"
#include "tests/replay/random_frame.h"
#include "tests/test_util.h"
#include "tests/tools/json_value.h"

namespace raycell {
namespace {

using testing::Json;

struct Frames {
  std::uint32_t cells = 0;
  std::vector<std::uint64_t> footprints;
  std::vector<RayBatch> rays;
  std::vector<CellTree> trees;
};

Frames RandomFrames(std::uint32_t seed, int count, std::uint32_t cells) {
  std::mt19937 rng(seed);
  Frames f;
  f.cells = cells;
  for (std::uint32_t c = 0; c < cells; ++c) f.footprints.push_back(1 + rng() % 300'000);
  for (int i = 0; i < count; ++i) {
    f.rays.push_back(testing::RandomReplayFrame(rng, cells, 80));
    f.trees.push_back(testing::TreeOf(f.rays.back()));
  }
  return f;
}

WorkGraph WorkOf(const Frames& f, std::size_t i, const ReplayConfig& config) {
  return EffectiveGranularity(config) == ReplayConfig::Granularity::kRay
             ? RaySegmentWork(f.rays[i], f.cells)
             : NodeWork(f.trees[i], f.cells);
}

// Every field of a result, as `replay --format json` prints it, plus what it leaves out.
std::string Describe(const ReplayResult& r) {
  std::ostringstream s;
  PrintJsonLine(ToStatsTable(r, kReplayJsonColumns), s);
  s << " events " << r.events << " passes " << r.passes;
  return s.str();
}

struct Replayed {
  std::string json;
  std::vector<ReplayResult> results;
  std::uint64_t queued_rays = 0;  // sum over the frames' units of the rays they queue
};

// Frames numbered 100, 101, ...
std::vector<std::int32_t> FrameNumbers(std::size_t n) {
  std::vector<std::int32_t> numbers;
  for (std::size_t i = 0; i < n; ++i) numbers.push_back(std::int32_t(100 + i));
  return numbers;
}

// Replays every frame of `f` with a timeline, and again without: the results must be equal.
Replayed Replay(const Frames& f, const ReplayConfig& config) {
  Replayed out;
  std::ostringstream json;
  TimelineWriter writer(json, config, f.footprints, {"t.rct", FrameNumbers(f.rays.size())});
  auto watched = MakeScheduler(*config.scheduler, config.seed);
  auto plain = MakeScheduler(*config.scheduler, config.seed);
  for (std::size_t i = 0; i < f.rays.size(); ++i) {
    const FrameTrees info{i, &f.trees[i], i > 0 ? &f.trees[i - 1] : nullptr, f.cells};
    const WorkGraph w = WorkOf(f, i, config);
    for (std::uint64_t q : w.queued_rays) out.queued_rays += q;
    const std::uint64_t bound = Bound(f.trees[i]);
    out.results.push_back(ReplayFrame(w, f.footprints, config, *watched, info, bound, &writer));
    EXPECT_EQ(Describe(out.results.back()),
              Describe(ReplayFrame(w, f.footprints, config, *plain, info, bound)))
        << "frame " << i;
  }
  writer.Finish();
  out.json = json.str();
  EXPECT_EQ(writer.bytes_written(), out.json.size());
  return out;
}

// A slice as the file gives it: exact picoseconds from args, nanoseconds from ts and dur.
struct Slice {
  std::uint64_t ps, dur_ps, ts_ns, dur_ns;
  std::string cat;
  const Json* event;
};

// "12.345" microseconds as nanoseconds; the writer prints exactly three decimals.
std::uint64_t Nanoseconds(const Json& v) {
  EXPECT_EQ(v.type, Json::Type::kNumber) << v.text;
  const std::size_t dot = v.text.find('.');
  EXPECT_EQ(v.text.size() - dot, 4u) << v.text;
  return std::stoull(v.text.substr(0, dot)) * 1000 + std::stoull(v.text.substr(dot + 1));
}

std::uint64_t Integer(const Json& v) {
  EXPECT_EQ(v.type, Json::Type::kInteger) << v.text;
  return std::stoull(v.text);
}

// In time order; a slice of duration 0 before one that starts at the same time.
bool Earlier(const Slice& a, const Slice& b) {
  return a.ps != b.ps ? a.ps < b.ps : a.dur_ps < b.dur_ps;
}

std::uint64_t RoundToNs(std::uint64_t ps) { return (ps + 500) / 1000; }

// The timeline `r.json` against the results it was written with.
void CheckTimeline(const Replayed& r, const ReplayConfig& config) {
  const Json doc = Json::Parse(r.json);
  ASSERT_EQ(doc.type, Json::Type::kObject);
  const Json& other = doc["otherData"];
  EXPECT_EQ(other["schema"].text, "raycell-timeline/1");
  EXPECT_EQ(Integer(other["frames"]), r.results.size());

  ReplayResult total;
  total.levels.resize(config.levels.size());
  for (const ReplayResult& f : r.results) {
    total.time = total.time + f.time;
    total.work = total.work + f.work;
    total.stall = total.stall + f.stall;
    total.idle = total.idle + f.idle;
    total.samples += f.samples;
    total.peak_queued_rays = std::max(total.peak_queued_rays, f.peak_queued_rays);
    for (std::size_t i = 0; i < f.levels.size(); ++i) {
      total.levels[i].fetches += f.levels[i].fetches;
      total.levels[i].bytes += f.levels[i].bytes;
    }
  }

  const std::uint32_t procs = config.processors.count;
  std::map<std::uint64_t, std::vector<Slice>> tracks;  // by tid
  std::map<std::string, std::uint64_t> time_by_cat, rays_by_cat;
  std::uint64_t samples = 0, misses = 0, fetch_slices = 0, prefetch_transfers = 0;
  std::vector<std::uint64_t> frame_starts;
  std::map<std::string, std::vector<std::uint64_t>> counters;
  for (const Json& e : doc["traceEvents"].items) {
    const std::string ph = e["ph"].text;
    EXPECT_EQ(Integer(e["pid"]), 1u);
    if (ph == "X") {
      const Json& args = e["args"];
      const Slice s{Integer(args["ps"]),   Integer(args["dur_ps"]), Nanoseconds(e["ts"]),
                    Nanoseconds(e["dur"]), e["cat"].text,           &e};
      // ts and dur: each boundary rounded once to the nanosecond.
      EXPECT_EQ(s.ts_ns, RoundToNs(s.ps));
      EXPECT_EQ(s.ts_ns + s.dur_ns, RoundToNs(s.ps + s.dur_ps));
      tracks[Integer(e["tid"])].push_back(s);
      time_by_cat[s.cat] += s.dur_ps;
      if (s.cat == "work") {
        samples += Integer(args["samples"]);
        rays_by_cat["work"] += Integer(args["rays"]);
        EXPECT_EQ(e["name"].text, "cell " + args["cell"].text);
        EXPECT_EQ(s.dur_ps,
                  Integer(args["samples"]) * config.processors.time_per_sample.picoseconds());
      }
      if (s.cat == "fetch") {
        ++fetch_slices;
        misses += args["miss"].boolean;
        EXPECT_EQ(e["name"].text, "fetch cell " + args["cell"].text);
      }
      const std::uint64_t tid = Integer(e["tid"]);  // level 0: tids procs + 1 .. 2 procs
      if (s.cat == "transfer" && tid > procs && tid <= 2 * procs) {
        prefetch_transfers += args["prefetch"].boolean;
      }
    } else if (ph == "i") {
      EXPECT_EQ(e["s"].text, "g");
      EXPECT_EQ(e["name"].text, "frame " + e["args"]["frame"].text);
      frame_starts.push_back(Integer(e["args"]["ps"]));
    } else if (ph == "C") {
      counters[e["name"].text].push_back(Integer(e["args"]["rays"]));
    } else {
      EXPECT_EQ(ph, "M");
    }
  }

  // Per processor: the slices tile [0, end of the last frame] exactly, in picoseconds and in
  // the nanoseconds viewers read; no overlap, no gap.
  for (std::uint32_t p = 0; p < procs; ++p) {
    std::vector<Slice>& s = tracks[1 + p];
    std::sort(s.begin(), s.end(), Earlier);
    std::uint64_t at = 0, at_ns = 0;
    for (const Slice& x : s) {
      EXPECT_TRUE(x.cat == "work" || x.cat == "fetch" || x.cat == "idle") << x.cat;
      EXPECT_EQ(x.ps, at) << "processor " << p;
      EXPECT_EQ(x.ts_ns, at_ns) << "processor " << p;
      at = x.ps + x.dur_ps;
      at_ns = x.ts_ns + x.dur_ns;
    }
    EXPECT_EQ(at, total.time.picoseconds()) << "processor " << p;
  }
  EXPECT_EQ(time_by_cat["work"], total.work.picoseconds());
  EXPECT_EQ(time_by_cat["fetch"], total.stall.picoseconds());
  EXPECT_EQ(time_by_cat["idle"], total.idle.picoseconds());
  EXPECT_EQ(samples, total.samples);
  EXPECT_EQ(rays_by_cat["work"], r.queued_rays);

  // Fetches: each processor fetch that missed, plus each prefetch, is a fetch into the caches.
  EXPECT_EQ(misses + prefetch_transfers, total.levels[0].fetches);
  if (!config.processors.prefetch) {
    EXPECT_EQ(fetch_slices, total.levels[0].fetches);
  }
  // Each level's transfers: its fetches and bytes; one at a time on each link.
  for (std::size_t level = 0; level < config.levels.size(); ++level) {
    const std::uint32_t copies = level == 0 ? procs : 1;
    std::uint64_t transfers = 0, bytes = 0;
    for (std::uint32_t k = 0; k < copies; ++k) {
      const std::uint64_t tid = level == 0 ? 1 + procs + k : 2 * procs + level;
      std::vector<Slice>& s = tracks[tid];
      std::sort(s.begin(), s.end(), Earlier);
      std::uint64_t free = 0, free_ns = 0;
      for (const Slice& x : s) {
        EXPECT_EQ(x.cat, "transfer");
        EXPECT_GE(x.ps, free);
        EXPECT_GE(x.ts_ns, free_ns);
        free = x.ps + x.dur_ps;
        free_ns = x.ts_ns + x.dur_ns;
        bytes += Integer((*x.event)["args"]["bytes"]);
        if (level == 0) {
          EXPECT_EQ(Integer((*x.event)["args"]["processor"]), k);
        }
      }
      transfers += s.size();
    }
    EXPECT_EQ(transfers, total.levels[level].fetches) << "level " << level;
    EXPECT_EQ(bytes, total.levels[level].bytes) << "level " << level;
  }
  for (const auto& [tid, slices] : tracks) {  // nothing outside the processor and level tracks
    EXPECT_GE(tid, 1u);
    EXPECT_LE(tid, 2 * procs + config.levels.size() - 1);
  }

  // One frame instant per frame, at the frame's start.
  ASSERT_EQ(frame_starts.size(), r.results.size());
  std::uint64_t start = 0;
  for (std::size_t i = 0; i < r.results.size(); ++i) {
    EXPECT_EQ(frame_starts[i], start);
    start += r.results[i].time.picoseconds();
  }
  // Queue counters: all empty at the end; never above the peak.
  ASSERT_TRUE(counters.count("queue: all cells"));
  for (const auto& [name, values] : counters) {
    EXPECT_EQ(values.back(), 0u) << name;
    EXPECT_LE(*std::max_element(values.begin(), values.end()), total.peak_queued_rays) << name;
  }
}

ReplayConfig Config(std::uint32_t processors, ReplayConfig::Granularity g, bool prefetch,
                    std::uint64_t cache_cells, const char* scheduler) {
  ReplayConfig c = DefaultConfig();
  c.processors.count = processors;
  c.granularity = g;
  c.processors.prefetch = prefetch;
  c.levels[0].capacity = cache_cells;
  c.scheduler = &SchedulerByName(scheduler, "test");
  return c;
}

using G = ReplayConfig::Granularity;

TEST(Timeline, AddsUpToTheReplayOneProcessorPerNode) {
  const Frames f = RandomFrames(1, 4, 8);
  const ReplayConfig c = Config(1, G::kNode, false, 1, "celltree");
  CheckTimeline(Replay(f, c), c);
}

TEST(Timeline, AddsUpToTheReplayOneProcessorPerSegmentWithPrefetch) {
  const Frames f = RandomFrames(2, 3, 6);
  const ReplayConfig c = Config(1, G::kRay, true, 2, "peel");
  CheckTimeline(Replay(f, c), c);
}

TEST(Timeline, AddsUpToTheReplaySeveralProcessorsPerSegment) {
  const Frames f = RandomFrames(3, 3, 8);
  for (bool prefetch : {false, true}) {
    for (const char* scheduler : {"maxwork", "celltree", "roundrobin"}) {
      const ReplayConfig c = Config(3, G::kRay, prefetch, 2, scheduler);
      SCOPED_TRACE(std::string(scheduler) + (prefetch ? " prefetch" : ""));
      CheckTimeline(Replay(f, c), c);
    }
  }
}

TEST(Timeline, AddsUpToTheReplaySeveralProcessorsPerNode) {
  const Frames f = RandomFrames(4, 3, 5);
  const ReplayConfig c = Config(4, G::kNode, true, 3, "random");
  CheckTimeline(Replay(f, c), c);
}

// Belady's MIN runs a frame several times: only the last run is the timeline.
TEST(Timeline, OnlyTheLastRunOfAFrameWithMinReplacement) {
  const Frames f = RandomFrames(5, 3, 8);
  ReplayConfig c = Config(2, G::kRay, false, 2, "maxwork");
  c.levels[0].replacement = &kMinReplacement;
  c.levels[1].capacity_unit = LevelConfig::CapacityUnit::kCells;
  c.levels[1].capacity = 3;
  c.levels[1].replacement = &kMinReplacement;
  const Replayed r = Replay(f, c);
  EXPECT_GT(r.results[0].passes, 1u);
  CheckTimeline(r, c);
}

// Several levels, a cache in bytes, unlimited bandwidth and no latency (fetches that stall
// nothing are still fetch slices, of duration 0), ties in time.
TEST(Timeline, AddsUpToTheReplayWithFreeFetchesAndThreeLevels) {
  const Frames f = RandomFrames(6, 3, 6);
  ReplayConfig c = Config(3, G::kRay, false, 1, "maxwork");
  c.levels.push_back(c.levels[1]);
  c.levels[2].name = "far";
  c.levels[0].bandwidth_below = ParseBandwidth("unlimited", "test");
  c.levels[0].latency_below = SimTime::Zero();
  c.levels[1].capacity = 600'000;
  c.processors.time_per_sample = SimTime::Picoseconds(7);
  CheckTimeline(Replay(f, c), c);
}

TEST(Timeline, ReasonsOfTheFollowingSchedulers) {
  const Frames f = RandomFrames(7, 2, 8);
  const ReplayConfig c = Config(1, G::kNode, false, 1, "celltree");
  const Json doc = Json::Parse(Replay(f, c).json);
  std::map<std::string, int> reasons;
  for (const Json& e : doc["traceEvents"].items) {
    if (e["ph"].text == "X" && e["cat"].text == "work") {
      reasons[e["args"]["frame"].text + " " + e["args"]["reason"].text.substr(0, 8)]++;
    }
  }
  // Frame 0 has no previous tree: Max Work throughout; frame 1 follows frame 0's Peel.
  EXPECT_GT(reasons["100 max work"], 0);
  EXPECT_EQ(reasons["100 followed"], 0);
  EXPECT_GT(reasons["101 followed"], 0);
}

TEST(Timeline, RefusesToGrowPastItsLimit) {
  const Frames f = RandomFrames(8, 3, 8);
  const ReplayConfig c = Config(1, G::kNode, false, 1, "maxwork");
  const std::string whole = Replay(f, c).json;
  for (std::uint64_t limit :
       {std::uint64_t(100), std::uint64_t(whole.size() / 2), std::uint64_t(whole.size() - 1)}) {
    std::ostringstream out;
    const std::string error = testing::ErrorOf([&] {
      TimelineWriter writer(out, c, f.footprints,
                            {"t.rct", FrameNumbers(f.rays.size()), limit, "--timeline x.json"});
      auto s = MakeScheduler(*c.scheduler, c.seed);
      for (std::size_t i = 0; i < f.rays.size(); ++i) {
        const FrameTrees info{i, &f.trees[i], i > 0 ? &f.trees[i - 1] : nullptr, f.cells};
        ReplayFrame(WorkOf(f, i, c), f.footprints, c, *s, info, 0, &writer);
      }
      writer.Finish();
    });
    EXPECT_NE(error.find("--timeline x.json: the timeline would exceed " + std::to_string(limit) +
                         " bytes"),
              std::string::npos)
        << error;
    EXPECT_NE(error.find("--frames A..B"), std::string::npos) << error;
    EXPECT_LE(out.str().size(), limit);
  }
  std::ostringstream out;  // exactly the size it needs: written
  TimelineWriter writer(out, c, f.footprints,
                        {"t.rct", FrameNumbers(f.rays.size()), whole.size(), "--timeline"});
  auto s = MakeScheduler(*c.scheduler, c.seed);
  for (std::size_t i = 0; i < f.rays.size(); ++i) {
    const FrameTrees info{i, &f.trees[i], i > 0 ? &f.trees[i - 1] : nullptr, f.cells};
    ReplayFrame(WorkOf(f, i, c), f.footprints, c, *s, info, Bound(f.trees[i]), &writer);
  }
  writer.Finish();
  EXPECT_EQ(out.str(), whole);
}

}  // namespace
}  // namespace raycell
