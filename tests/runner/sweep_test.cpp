// Sweeps (issue 4): --vary parsing and combination order, validation before any work, rows
// equal to single replays (ReplayTrace) written out field by field, byte-identical output
// for any --jobs, shards of combinations and of frames merged into the unsharded file,
// resuming after an interruption at any row or frame, and configurations shared only where
// no result can differ.
#include "runner/sweep.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <random>
#include <sstream>

#include "base/check.h"
#include "base/format.h"
#include "base/hash.h"
#include "base/parse.h"
#include "runner/driver.h"
#include "runner/sweep_file.h"
#include "scheduling/scheduler.h"
#include "tests/cell_list.h"
#include "tests/test_util.h"
#include "traces/trace_writer.h"

namespace raycell {
namespace {

using testing::ReadBytes;

// The row a sweep must print for combination `index`, written out field by field in the
// order sweep.h documents (not with SweepRow, the function under test).
std::string ExpectedRow(std::size_t index, const std::vector<std::string>& values,
                        const ReplayResult& r) {
  std::ostringstream s;
  s << index;
  for (const std::string& v : values) s << ',' << v;
  s << ',' << r.fetches << ',' << (r.bound ? std::to_string(*r.bound) : "") << ','
    << r.time.picoseconds() << ',' << r.time_bound.picoseconds() << ',' << r.work.picoseconds()
    << ',' << r.stall.picoseconds() << ',' << r.idle.picoseconds() << ','
    << FormatFixed(r.utilisation, 4) << ',' << r.peak_queued_rays << ',' << r.peak_queued_bytes
    << ',' << r.rays << ',' << r.segments << ',' << r.samples << '\n';
  return s.str();
}

std::string TempPath(const std::string& name) { return testing::TempPath("sweep", name); }

bool Exists(const std::string& path) { return std::ifstream(path).good(); }

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

TraceHeader MakeHeader(int frames) {
  TraceHeader h;
  h.producer = "raycell test";
  h.scene = "builtin:test";
  h.cells = {3, 2, 1};
  for (std::uint32_t c = 0; c < h.cell_count(); ++c) h.footprints.push_back(4096 * (c + 1));
  for (int f = 0; f < frames; ++f)
    h.cameras.push_back({f, {1, 2, 3.0 + f}, {0, 0, 0}, {0, 1, 0}, 40});
  h.settings.store_t = false;
  return h;
}

// Rays through random cells, every third one a shadow ray spawned from the ray before,
// starting in the cell of its spawn visit.
RayBatch RandomFrame(std::mt19937& rng, std::size_t rays, std::uint32_t cells) {
  RayBatch b(false);
  for (std::size_t i = 0; i < rays; ++i) {
    const bool child = i > 0 && i % 3 == 0 && b.ray(i - 1).visit_count > 0;
    const RayId parent = child ? i - 1 : kNoParent;
    const std::uint32_t spawn = child ? rng() % b.ray(i - 1).visit_count : 0;
    b.BeginRay(child ? RayKind::kShadow : RayKind::kPrimary, parent, spawn, 0, 0);
    CellId cell = child ? b.ray(i - 1).cells[spawn] : CellId(rng() % cells);
    for (int v = 0, n = 1 + int(rng() % 4); v < n; ++v) {
      b.AddVisit(cell, 1 + rng() % 20, 0, 0);
      cell = CellId((cell.value() + 1 + rng() % (cells - 1)) % cells);
    }
  }
  return b;
}

// Writes `path`: `h` and one RandomFrame of 40 rays per camera, from `seed`.
std::string WriteFrames(const std::string& path, const TraceHeader& h, std::uint32_t seed) {
  TraceWriter w = TraceWriter::Create(path, h, 3);
  std::mt19937 rng(seed);
  for (std::size_t f = 0; f < h.cameras.size(); ++f) {
    w.BeginFrame(int(f));
    w.Append(RandomFrame(rng, 40, h.cell_count()));
    w.EndFrame();
  }
  w.Finish();
  return path;
}

std::string WriteTrace(int frames) {
  return WriteFrames(TempPath("trace.rct"), MakeHeader(frames), 7);
}

// WriteTrace's frames on the cells of a dynamic subdivision: six boxes of a 6x2x1 fine grid,
// other boxes every frame (six slabs, then 2x1 blocks, then a mix, then the slabs again), so
// that warm memory carries its cells over through the fine cells (design §2).
std::string WriteDynamicTrace(int frames) {
  TraceHeader h = MakeHeader(frames);
  h.cells = {6, 1, 1};
  h.subdivision.spec = "dynamic:6";
  h.subdivision.fine = {6, 2, 1};
  const auto box = [](std::uint32_t x0, std::uint32_t x1, std::uint32_t y0, std::uint32_t y1) {
    return FineBox{{x0, y0, 0}, {x1, y1, 1}};
  };
  const std::vector<std::vector<FineBox>> partitions = {
      {box(0, 1, 0, 2), box(1, 2, 0, 2), box(2, 3, 0, 2), box(3, 4, 0, 2), box(4, 5, 0, 2),
       box(5, 6, 0, 2)},
      {box(0, 2, 0, 1), box(2, 4, 0, 1), box(4, 6, 0, 1), box(0, 2, 1, 2), box(2, 4, 1, 2),
       box(4, 6, 1, 2)},
      {box(0, 1, 0, 2), box(1, 3, 0, 1), box(3, 5, 0, 1), box(5, 6, 0, 2), box(1, 3, 1, 2),
       box(3, 5, 1, 2)}};
  h.footprints.assign(6, 0);
  for (int f = 0; f < frames; ++f) {
    for (const FineBox& b : partitions[std::size_t(f) % partitions.size()]) {
      std::uint64_t bytes = 0;  // fine cell x + 6y holds 1024 x (1 + (x + 6y) % 4) bytes
      for (std::uint32_t fine : FineCellsOf(b, h.subdivision.fine)) bytes += 1024 * (1 + fine % 4);
      const std::size_t c = h.subdivision.boxes.size() % 6;
      h.subdivision.boxes.push_back(b);
      h.subdivision.frame_footprints.push_back(bytes);
      h.footprints[c] = std::max(h.footprints[c], bytes);
    }
  }
  return WriteFrames(TempPath("dynamic.rct"), h, 11);
}

class SweepTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    trace_path_ = new std::string(WriteTrace(4));
    reader_ = new TraceReader(TraceReader::Open(*trace_path_));
  }
  static void TearDownTestSuite() {
    delete reader_;
    std::remove(trace_path_->c_str());
    delete trace_path_;
  }

  // 3 x 2 x 2 = 12 combinations.
  SweepSpec Spec(Shard shard = {}) const {
    SweepSpec spec;
    spec.trace = *trace_path_;
    spec.base = DefaultConfig();
    spec.varies = {Vary::Parse("scheduler=maxwork,roundrobin,peel"),
                   Vary::Parse("processors.count=1,2"),
                   Vary::Parse("level.cache.capacity=1 cell,2 cells")};
    spec.frame_indices = {0, 1, 2, 3};
    spec.shard = shard;
    return spec;
  }

  // The mixed sweep: every scheduler, 1, 2 and 8 processors, caches of 2 and 4 cells,
  // prefetch off and on, two board bandwidths: 5 x 3 x 2 x 2 x 2 = 120 combinations.
  SweepSpec Mixed() const {
    SweepSpec spec = Spec();
    spec.varies = {Vary::Parse("scheduler=maxwork,roundrobin,random,peel,celltree"),
                   Vary::Parse("processors.count=1,2,8"),
                   Vary::Parse("level.cache.capacity=2 cells,4 cells"),
                   Vary::Parse("processors.prefetch=false,true"),
                   Vary::Parse("level.board.bandwidth=133MB/s,1GB/s")};
    spec.frame_indices = {0, 1, 2, 3};
    return spec;
  }

  // `spec` over the frames numbered `range` ("A..B"), as --frames selects them.
  static SweepSpec Frames(SweepSpec spec, const std::string& range) {
    const std::vector<int> f = ParseFrameRange(range);
    spec.frames = range;
    spec.frame_indices.clear();
    for (int i = f.front(); i <= f.back(); ++i) spec.frame_indices.push_back(std::size_t(i));
    return spec;
  }

  // Runs `spec` into a fresh file named `name`; returns its bytes.
  std::string Run(const SweepSpec& spec, const std::string& name, unsigned jobs = 1,
                  std::size_t block = kSweepBlock) {
    const std::string out = Fresh(name);
    SweepOptions options;
    options.jobs = jobs;
    options.block = block;
    const SweepOutcome o = RunSweep(*reader_, spec, out, options);
    EXPECT_TRUE(o.complete);
    EXPECT_FALSE(Exists(out + ".partial"));
    EXPECT_FALSE(Exists(out + ".checkpoint"));
    return ReadBytes(out);
  }

  // The file a sweep must write: comment, header, and each combination's ReplayTrace totals
  // written out field by field.
  std::string Expected(const SweepSpec& spec, const std::string& header) const {
    std::string expected = SweepComment(spec) + header;
    for (std::size_t i : ShardIndices(CombinationCount(spec.varies), spec.shard)) {
      const TraceReplay r =
          ReplayTrace(*reader_, spec.frame_indices, CombinationConfig(spec.base, spec.varies, i));
      EXPECT_GT(r.total.rays, 0u);
      expected += ExpectedRow(i, CombinationValues(spec.varies, i), r.total);
    }
    return expected;
  }

  std::string Fresh(const std::string& name) {
    const std::string path = TempPath(name);
    for (const char* suffix : {"", ".partial", ".checkpoint"}) {
      std::remove((path + suffix).c_str());
    }
    paths_.push_back(path);
    return path;
  }

  void TearDown() override {
    for (const std::string& p : paths_) {
      for (const char* suffix : {"", ".partial", ".checkpoint"}) std::remove((p + suffix).c_str());
    }
  }

  static std::string* trace_path_;
  static TraceReader* reader_;
  std::vector<std::string> paths_;
};

std::string* SweepTest::trace_path_ = nullptr;
TraceReader* SweepTest::reader_ = nullptr;

using testing::ErrorOf;

// The sweep file's config_hash identifies the configuration, not its documentation: it is the
// hash of --print-config's TOML with the comment lines left out (so a better help text changes
// no sweep file and stops no sweep from resuming), and any value changes it.
TEST(ConfigHash, HashesTheValuesAndNotTheComments) {
  const ReplayConfig base = DefaultConfig();
  const std::string toml = ToToml(base);
  ASSERT_NE(toml.find("\n#"), std::string::npos) << "the printed configuration has comments";
  std::string values;
  std::istringstream lines(toml);
  for (std::string line; std::getline(lines, line);) {
    const std::size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] != '#') values += line + "\n";
  }
  Hash64 h;
  h.AddBytes(values.data(), values.size());
  EXPECT_EQ(sweep_file::ConfigHash(base), FormatHex64(h.Finish()));
  ReplayConfig other = base;
  other.seed = base.seed + 1;
  EXPECT_NE(sweep_file::ConfigHash(other), sweep_file::ConfigHash(base));
}

TEST(Vary, ParsesValuesWithSpaces) {
  const Vary v = Vary::Parse("level.cache.capacity=1 cell,2 cells, 64MiB");
  EXPECT_EQ(v.key, "level.cache.capacity");
  EXPECT_EQ(v.values, (std::vector<std::string>{"1 cell", "2 cells", "64MiB"}));
  EXPECT_EQ(v.ToString(), "level.cache.capacity=1 cell,2 cells,64MiB");
}

TEST(Vary, BadTextNamesTheOption) {
  EXPECT_NE(ErrorOf([] { Vary::Parse("scheduler"); }).find("--vary 'scheduler'"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { Vary::Parse("scheduler="); }).find("--vary"), std::string::npos);
  EXPECT_NE(ErrorOf([] { Vary::Parse("scheduler=a,,b"); }).find("empty value"), std::string::npos);
  EXPECT_NE(ErrorOf([] { Vary::Parse("=a"); }).find("key"), std::string::npos);
}

TEST(Vary, CombinationsAreRowMajorLastFastest) {
  const std::vector<Vary> v = {Vary::Parse("a=x,y,z"), Vary::Parse("b=1,2")};
  ASSERT_EQ(CombinationCount(v), 6u);
  const std::vector<std::vector<std::string>> expected = {{"x", "1"}, {"x", "2"}, {"y", "1"},
                                                          {"y", "2"}, {"z", "1"}, {"z", "2"}};
  for (std::size_t i = 0; i < 6; ++i) EXPECT_EQ(CombinationValues(v, i), expected[i]) << i;
  EXPECT_EQ(CombinationCount({}), 1u);
}

TEST(Shard, ParsesAndSelects) {
  const Shard s = Shard::Parse("1/3");
  EXPECT_EQ(ShardIndices(8, s), (std::vector<std::size_t>{1, 4, 7}));
  EXPECT_EQ(s.ToString(), "1/3");
  EXPECT_EQ(Shard{}.ToString(), "all");
  for (const char* bad : {"3/3", "1/0", "a/3", "1", "-1/3", "1/3x"}) {
    EXPECT_NE(ErrorOf([bad] { Shard::Parse(bad); }).find("--shard"), std::string::npos) << bad;
  }
}

TEST_F(SweepTest, BadValuesFailBeforeAnyWork) {
  SweepSpec spec = Spec();
  spec.varies.push_back(Vary::Parse("processors.prefetch=false,maybe"));
  const std::string out = Fresh("bad.csv");
  const std::string error = ErrorOf([&] { RunSweep(*reader_, spec, out); });
  EXPECT_NE(error.find("processors.prefetch"), std::string::npos) << error;
  EXPECT_NE(error.find("maybe"), std::string::npos) << error;
  EXPECT_FALSE(Exists(out + ".partial"));
  spec.varies.back() = Vary::Parse("nonsense.key=1");
  EXPECT_NE(ErrorOf([&] { RunSweep(*reader_, spec, out); }).find("nonsense.key"),
            std::string::npos);
  spec.varies.back() = Vary::Parse("scheduler=maxwork");
  EXPECT_NE(ErrorOf([&] { RunSweep(*reader_, spec, out); }).find("twice"), std::string::npos);
  // Valid alone, not replayable together: prefetch needs a cache of two cells.
  spec.varies.back() = Vary::Parse("processors.prefetch=false,true");
  const std::string prefetch = ErrorOf([&] { RunSweep(*reader_, spec, out); });
  EXPECT_NE(prefetch.find("combination 1: processors.prefetch = true needs a cache that holds "
                          "two cells"),
            std::string::npos)
      << prefetch;
  EXPECT_FALSE(Exists(out + ".partial"));
  // A board of coarser cells needs a regroupable capture: refused before the file is opened.
  spec.varies.back() = Vary::Parse("level.board.cells=same,3x3x3");
  const std::string board = ErrorOf([&] { RunSweep(*reader_, spec, out); });
  EXPECT_NE(board.find("combination 1: level.board.cells: '3x3x3' needs a regroupable capture"),
            std::string::npos)
      << board;
  EXPECT_FALSE(Exists(out + ".partial"));
}

constexpr char kMixedHeader[] =
    "index,scheduler,processors.count,level.cache.capacity,processors.prefetch,"
    "level.board.bandwidth,fetches,bound,time_ps,time_bound_ps,work_ps,stall_ps,idle_ps,"
    "utilisation,peak_queued_rays,peak_queued_bytes,rays,segments,samples\n";

// Every row of the mixed sweep is its combination's ReplayTrace, whatever the jobs and the
// blocks (several blocks of 7 combinations, or one).
TEST_F(SweepTest, MixedSweepRowsEqualSingleReplaysWhateverTheJobs) {
  const SweepSpec spec = Mixed();
  const std::string one = Run(spec, "jobs1.csv", 1);
  EXPECT_EQ(one, Expected(spec, kMixedHeader));
  EXPECT_EQ(Run(spec, "jobs2.csv", 2, 7), one);
  EXPECT_EQ(Run(spec, "jobs3.csv", 3), one);
  EXPECT_EQ(one.rfind("# raycell sweep schema=\"raycell-sweep/1\" trace=", 0), 0u);
  EXPECT_NE(one.find("\n0,maxwork,1,2 cells,false,133MB/s,"), std::string::npos);
  EXPECT_NE(one.find("\n119,celltree,8,4 cells,true,1GB/s,"), std::string::npos);
}

TEST_F(SweepTest, RowsEqualSingleReplaysWithTheBound) {
  const SweepSpec spec = Spec();  // with one processor and one cell: the bound holds
  const std::string rows = Run(spec, "bound.csv", 2);
  EXPECT_EQ(rows, Expected(spec,
                           "index,scheduler,processors.count,level.cache.capacity,fetches,bound,"
                           "time_ps,time_bound_ps,work_ps,stall_ps,idle_ps,utilisation,"
                           "peak_queued_rays,peak_queued_bytes,rays,segments,samples\n"));
  EXPECT_NE(rows.find("\n0,maxwork,1,1 cell,"), std::string::npos);
  EXPECT_NE(rows.find("\n11,peel,2,2 cells,"), std::string::npos);
}

// Combinations that differ in the seed of a scheduler that is not random, the granularity
// auto resolves to (one processor: node), the queue record size, or prefetch under the random
// scheduler (which predicts nothing) are replayed once, and each row still equals its own
// ReplayTrace: 2 x 3 x 2 x 2 x 2 = 48 combinations, 2 + 3 replays (maxwork with and without
// prefetch; random with each seed).
TEST_F(SweepTest, CombinationsShareReplaysOnlyWhereNoResultCanDiffer) {
  SweepSpec spec = Spec();
  spec.varies = {Vary::Parse("scheduler=maxwork,random"), Vary::Parse("seed=1,2,3"),
                 Vary::Parse("processors.prefetch=false,true"),
                 Vary::Parse("processors.queue_record_bytes=16,32"),
                 Vary::Parse("granularity=auto,node")};
  spec.base.levels[0].capacity = 2;
  const std::string out = Fresh("shared.csv");
  const SweepOutcome o = RunSweep(*reader_, spec, out, {});
  EXPECT_EQ(o.distinct, 5u);
  EXPECT_EQ(ReadBytes(out), Expected(spec,
                                     "index,scheduler,seed,processors.prefetch,"
                                     "processors.queue_record_bytes,granularity,fetches,bound,"
                                     "time_ps,time_bound_ps,work_ps,stall_ps,idle_ps,"
                                     "utilisation,peak_queued_rays,peak_queued_bytes,rays,"
                                     "segments,samples\n"));
  // Two processors: granularity auto is ray, which node is not; every combination differs.
  spec.base.processors.count = 2;
  spec.varies = {Vary::Parse("scheduler=maxwork,random"), Vary::Parse("granularity=auto,node")};
  EXPECT_EQ(RunSweep(*reader_, spec, Fresh("unshared.csv"), {}).distinct, 4u);
}

// Plans shared across configurations (docs/design.md §5 "Sharing plans"): every scheduler,
// 1 and 8 processors, caches of 2 and 3 cells, seeds 1 and 2 (176 combinations), with each
// frame's plans made once for all (2 jobs) give the bytes of the same sweep planning per
// combination (each plan searched again, 1 job), and make fewer of them.
TEST_F(SweepTest, SharedPlansGiveTheRowsOfPlanningPerCombination) {
  SweepSpec spec = Spec();
  spec.varies = {Vary::Parse("scheduler=" + SchedulerNameList(",")),
                 Vary::Parse("processors.count=1,8"),
                 Vary::Parse("level.cache.capacity=2 cells,3 cells"), Vary::Parse("seed=1,2")};
  SweepOptions shared;
  shared.jobs = 2;
  const std::string a = Fresh("plans_shared.csv");
  const SweepOutcome with = RunSweep(*reader_, spec, a, shared);
  SweepOptions alone;
  alone.share_plans = false;
  const std::string b = Fresh("plans_alone.csv");
  const SweepOutcome without = RunSweep(*reader_, spec, b, alone);
  EXPECT_EQ(ReadBytes(a), ReadBytes(b));
  const std::string rows = ReadBytes(a);
  EXPECT_EQ(std::count(rows.begin(), rows.end(), '\n'), 2 + 176);
  EXPECT_GT(with.plans, 0u);
  EXPECT_LT(2 * with.plans, without.plans);
}

TEST_F(SweepTest, MergedShardsEqualTheUnshardedFile) {
  const std::string whole = Run(Spec(), "whole.csv", 2);
  std::vector<std::string> shards;
  for (std::size_t i : {2, 0, 1}) {  // any order
    shards.push_back(Fresh("shard" + std::to_string(i) + ".csv"));
    RunSweep(*reader_, Spec({i, 3}), shards.back(), {});
    EXPECT_NE(ReadBytes(shards.back()).find("shard=\"" + std::to_string(i) + "/3\""),
              std::string::npos);
  }
  const std::string merged = Fresh("merged.csv");
  MergeSweepShards(merged, shards);
  EXPECT_EQ(ReadBytes(merged), whole);

  const std::string bad = Fresh("bad_merge.csv");
  const std::string overlap = ErrorOf([&] {
    MergeSweepShards(bad, {shards[0], shards[1], shards[2], shards[1]});
  });
  EXPECT_NE(overlap.find("overlapping"), std::string::npos) << overlap;
  const std::string missing = ErrorOf([&] { MergeSweepShards(bad, {shards[0], shards[2]}); });
  EXPECT_NE(missing.find("in none of the shards"), std::string::npos) << missing;
  EXPECT_FALSE(Exists(bad));
}

// Frame shards (and frame shards of combination shards) add up to the file of the run over
// their whole range: sums, maxima, the bound where it holds, utilisation from the sums.
TEST_F(SweepTest, MergedFrameShardsEqualTheRunOverTheirRange) {
  for (const SweepSpec& base : {Spec(), Mixed()}) {
    const std::string whole = Run(Frames(base, "0..3"), "frames_whole.csv", 2);
    EXPECT_NE(whole.find(" frames=\"0..3\" "), std::string::npos);
    std::vector<std::string> parts;
    for (const char* range : {"2..3", "0..0", "1..1"}) {
      parts.push_back(Fresh(std::string("frames_") + range + ".csv"));
      RunSweep(*reader_, Frames(base, range), parts.back(), {});
    }
    const std::string merged = Fresh("frames_merged.csv");
    MergeSweepShards(merged, parts);
    EXPECT_EQ(ReadBytes(merged), whole);

    std::vector<std::string> both;  // combination shards of frame shards
    for (const char* range : {"0..1", "2..3"}) {
      for (std::size_t i : {0, 1}) {
        SweepSpec spec = Frames(base, range);
        spec.shard = {i, 2};
        both.push_back(Fresh(std::string("both_") + range + std::to_string(i) + ".csv"));
        RunSweep(*reader_, spec, both.back(), {});
      }
    }
    MergeSweepShards(merged, both);
    EXPECT_EQ(ReadBytes(merged), whole);
  }
}

// The same on cells that change every frame: each part replays the frames before it to carry
// its warm memory over, through the fine cells, as the whole run does.
TEST_F(SweepTest, MergedFrameShardsEqualTheRunOverTheirRangeWithCellsThatChange) {
  const std::string path = WriteDynamicTrace(4);
  paths_.push_back(path);
  const TraceReader reader = TraceReader::Open(path);
  ASSERT_TRUE(reader.header().cells_change());
  // The carry matters here: warm memory fetches less over PCI than cold.
  ReplayConfig cold = DefaultConfig();
  cold.memory.across_frames = MemoryConfig::AcrossFrames::kCold;
  EXPECT_LT(ReplayTrace(reader, {0, 1, 2, 3}, DefaultConfig()).total.levels[1].fetches,
            ReplayTrace(reader, {0, 1, 2, 3}, cold).total.levels[1].fetches);
  SweepSpec base = Mixed();
  base.trace = path;
  const auto run = [&](const SweepSpec& spec, const std::string& name, unsigned jobs) {
    const std::string out = Fresh(name);
    SweepOptions options;
    options.jobs = jobs;
    EXPECT_TRUE(RunSweep(reader, spec, out, options).complete);
    return out;
  };
  const std::string whole = ReadBytes(run(Frames(base, "0..3"), "dyn_whole.csv", 2));
  std::vector<std::string> parts;
  for (const char* range : {"2..3", "0..0", "1..1"}) {
    parts.push_back(run(Frames(base, range), std::string("dyn_") + range + ".csv", 1));
  }
  const std::string merged = Fresh("dyn_merged.csv");
  MergeSweepShards(merged, parts);
  EXPECT_EQ(ReadBytes(merged), whole);
}

TEST_F(SweepTest, MergeRefusesOverlappingOrMissingFrames) {
  std::map<std::string, std::string> files;
  for (const char* range : {"0..1", "1..3", "2..3", "3..3"}) {
    files[range] = Fresh(std::string("ranges_") + range + ".csv");
    RunSweep(*reader_, Frames(Spec(), range), files[range], {});
  }
  const std::string all = Fresh("ranges_all.csv");
  RunSweep(*reader_, Spec(), all, {});
  const std::string out = Fresh("ranges_merged.csv");
  const std::string overlap = ErrorOf([&] {
    MergeSweepShards(out, {files["0..1"], files["1..3"]});
  });
  EXPECT_NE(overlap.find("frames 1..1 are in"), std::string::npos) << overlap;
  EXPECT_NE(overlap.find("(overlapping frames)"), std::string::npos) << overlap;
  const std::string gap = ErrorOf([&] { MergeSweepShards(out, {files["0..1"], files["3..3"]}); });
  EXPECT_NE(gap.find("frames 2..2 are in none of the shards (missing frames)"), std::string::npos)
      << gap;
  const std::string mixed = ErrorOf([&] { MergeSweepShards(out, {files["2..3"], all}); });
  EXPECT_NE(mixed.find("frames \"all\" cannot be merged"), std::string::npos) << mixed;
  // Frame shards of another sweep are refused like combination shards.
  SweepSpec other = Frames(Spec(), "2..3");
  other.varies[1] = Vary::Parse("processors.count=1,3");
  const std::string foreign = Fresh("ranges_foreign.csv");
  RunSweep(*reader_, other, foreign, {});
  const std::string error = ErrorOf([&] { MergeSweepShards(out, {files["0..1"], foreign}); });
  EXPECT_NE(error.find("not a shard of the same sweep"), std::string::npos) << error;
  EXPECT_FALSE(Exists(out));
}

TEST_F(SweepTest, MergeRejectsShardsOfAnotherSweep) {
  SweepSpec other = Spec({1, 2});
  other.varies[1] = Vary::Parse("processors.count=1,3");
  const std::string a = Fresh("a.csv"), b = Fresh("b.csv");
  RunSweep(*reader_, Spec({0, 2}), a, {});
  RunSweep(*reader_, other, b, {});
  const std::string error = ErrorOf([&] { MergeSweepShards(Fresh("ab.csv"), {a, b}); });
  EXPECT_NE(error.find("not a shard of the same sweep"), std::string::npos) << error;
}

// Shards written before time_bound_ps was a column (their totals one column short) are
// refused, not misread: frame shards' rows are parsed and added, and their last thirteen
// fields are not this version's totals.
TEST_F(SweepTest, MergeRejectsShardsWithOtherTotalsColumns) {
  std::vector<std::string> old;
  for (const char* range : {"0..1", "2..3"}) {
    old.push_back(Fresh(std::string("old_") + range + ".csv"));
    RunSweep(*reader_, Frames(Spec(), range), old.back(), {});
    std::string text;
    for (const std::string& line : Split(ReadBytes(old.back()), '\n')) {
      if (line.empty() || line[0] == '#') {
        text += line.empty() ? "" : line + "\n";
        continue;
      }
      std::vector<std::string> fields = Split(line, ',');
      fields.erase(fields.end() - 10);  // time_bound_ps, the 4th of 13 totals
      text += Join(fields, ",") + "\n";
    }
    ASSERT_NE(text.find(",time_ps,work_ps,"), std::string::npos) << text;
    WriteText(old.back(), text);
  }
  const std::string error = ErrorOf([&] { MergeSweepShards(Fresh("old.csv"), old); });
  EXPECT_NE(error.find(old[0] + ": line 2: the header does not end with the totals' columns"),
            std::string::npos)
      << error;
}

TEST_F(SweepTest, InterruptedSweepResumes) {
  const SweepSpec spec = Spec();
  const std::string whole = Run(spec, "uninterrupted.csv", 2);
  const std::string out = Fresh("resumed.csv");
  SweepOptions stop_after_2;
  stop_after_2.jobs = 3;
  stop_after_2.stop = [](std::size_t rows) { return rows >= 2; };
  const SweepOutcome first = RunSweep(*reader_, spec, out, stop_after_2);
  EXPECT_FALSE(first.complete);
  EXPECT_EQ(first.ran, 2u);
  EXPECT_FALSE(Exists(out));
  ASSERT_TRUE(Exists(out + ".partial"));

  const SweepOutcome second = RunSweep(*reader_, spec, out, {});
  EXPECT_TRUE(second.complete);
  EXPECT_EQ(second.resumed, 2u);
  EXPECT_EQ(second.ran, 10u);
  EXPECT_EQ(ReadBytes(out), whole);
}

// Stopped after every row in turn and after every frame of every block in turn (blocks of 5
// combinations, so that a checkpoint belongs to the first, middle or last block), then run to
// the end: the same bytes as a sweep never interrupted.
TEST_F(SweepTest, ResumesAfterAnInterruptionAtAnyRowOrFrame) {
  const SweepSpec spec = Spec();
  const std::string whole = Run(spec, "whole_for_resume.csv", 1, 5);
  const std::size_t rows = 12, stops_at_frames = 3 * spec.frame_indices.size();
  for (std::size_t stop = 1; stop <= rows + stops_at_frames; ++stop) {
    SCOPED_TRACE("stop " + std::to_string(stop));
    const std::string out = Fresh("any_stop.csv");
    SweepOptions first;
    first.block = 5;
    first.checkpoint_seconds = 1e9;  // a checkpoint only when stopped
    first.jobs = 1 + stop % 3;
    std::size_t frames_seen = 0;
    if (stop <= rows) {
      first.stop = [stop](std::size_t written) { return written >= stop; };
    } else {
      first.stop_after_frame = [&](std::size_t) { return ++frames_seen == stop - rows; };
    }
    const SweepOutcome a = RunSweep(*reader_, spec, out, first);
    ASSERT_FALSE(a.complete);
    EXPECT_EQ(Exists(out + ".checkpoint"), stop > rows);
    SweepOptions rest;
    rest.block = 5;
    rest.checkpoint_seconds = 0;  // a checkpoint after every frame
    const SweepOutcome b = RunSweep(*reader_, spec, out, rest);
    EXPECT_TRUE(b.complete);
    if (stop > rows) {
      EXPECT_EQ(b.frames_resumed, (stop - rows - 1) % spec.frame_indices.size() + 1);
    }
    EXPECT_EQ(a.ran + b.ran + b.resumed - a.ran, rows);
    EXPECT_EQ(ReadBytes(out), whole);
    EXPECT_FALSE(Exists(out + ".checkpoint"));
  }
}

// Interrupted again and again, after one frame each time: every run resumes the last one's
// checkpoint.
TEST_F(SweepTest, ResumesChainsOfInterruptions) {
  const SweepSpec spec = Mixed();
  const std::string whole = Run(spec, "whole_for_chain.csv", 2, 50);
  const std::string out = Fresh("chain.csv");
  SweepOptions one_frame;
  one_frame.block = 50;
  one_frame.jobs = 2;
  one_frame.stop_after_frame = [](std::size_t) { return true; };
  std::size_t runs = 0;
  while (!RunSweep(*reader_, spec, out, one_frame).complete) ASSERT_LT(++runs, 100u);
  EXPECT_EQ(runs, 3 * spec.frame_indices.size());  // one frame each, then the last rows
  EXPECT_EQ(ReadBytes(out), whole);
}

TEST_F(SweepTest, ARowCutShortIsRunAgain) {
  const SweepSpec spec = Spec({1, 2});
  const std::string out = Fresh("cut.csv");
  RunSweep(*reader_, spec, out, {});
  const std::string whole = ReadBytes(out);
  std::size_t cut = 0;  // in the middle of the fourth row
  for (int line = 0; line < 5; ++line) cut = whole.find('\n', cut) + 1;
  WriteText(out + ".partial", whole.substr(0, cut + 5));
  std::remove(out.c_str());
  const SweepOutcome o = RunSweep(*reader_, spec, out, {});
  EXPECT_EQ(o.resumed, 3u);
  EXPECT_EQ(ReadBytes(out), whole);
}

TEST_F(SweepTest, APartialOfAnotherSweepIsAnError) {
  const SweepSpec spec = Spec();
  const std::string out = Fresh("other.csv");
  SweepOptions stop_after_1;
  stop_after_1.stop = [](std::size_t) { return true; };
  RunSweep(*reader_, spec, out, stop_after_1);
  SweepSpec other = spec;
  other.varies[0] = Vary::Parse("scheduler=maxwork,roundrobin");
  const std::string error = ErrorOf([&] { RunSweep(*reader_, other, out, {}); });
  EXPECT_NE(error.find("different sweep"), std::string::npos) << error;
  // Rows that are not this shard's first rows are refused too.
  const std::string partial = ReadBytes(out + ".partial");
  const std::size_t header_end = partial.find('\n', partial.find('\n') + 1) + 1;
  WriteText(out + ".partial",
            partial.substr(0, header_end) + "5,peel,1,1 cell,1,,1,1,1,1,1,1,1,1,1,1\n");
  const std::string prefix = ErrorOf([&] { RunSweep(*reader_, spec, out, {}); });
  EXPECT_NE(prefix.find("combination 0"), std::string::npos) << prefix;
  EXPECT_FALSE(Exists(out));
}

TEST_F(SweepTest, ACheckpointOfAnotherSweepIsAnErrorAndAStaleOneIgnored) {
  const SweepSpec spec = Spec();
  const std::string whole = Run(spec, "whole_for_checkpoint.csv", 1, 5);
  const std::string out = Fresh("checkpoint.csv");
  SweepOptions stop;
  stop.block = 5;
  stop.stop_after_frame = [](std::size_t frames) { return frames == 2; };
  RunSweep(*reader_, spec, out, stop);
  ASSERT_TRUE(Exists(out + ".checkpoint"));
  const std::string checkpoint = ReadBytes(out + ".checkpoint");
  EXPECT_EQ(checkpoint.rfind("# raycell sweep checkpoint block=0+5 frames_done=2/4\n", 0), 0u);
  // Another sweep's .partial and .checkpoint: refused.
  std::remove((out + ".partial").c_str());
  SweepSpec other = spec;
  other.varies[0] = Vary::Parse("scheduler=maxwork,roundrobin");
  const std::string error = ErrorOf([&] { RunSweep(*reader_, other, out, {}); });
  EXPECT_NE(error.find(".checkpoint: left by a different sweep"), std::string::npos) << error;
  // A checkpoint of a block that is not the next one (here the first block again, after its
  // rows were written): ignored, and the sweep ends with the right bytes.
  std::remove((out + ".partial").c_str());
  SweepOptions five_rows;
  five_rows.block = 5;
  five_rows.stop = [](std::size_t rows) { return rows == 5; };
  RunSweep(*reader_, spec, out, five_rows);
  WriteText(out + ".checkpoint", checkpoint);
  SweepOptions rest;
  rest.block = 5;
  const SweepOutcome o = RunSweep(*reader_, spec, out, rest);
  EXPECT_EQ(o.resumed, 5u);
  EXPECT_EQ(o.frames_resumed, 0u);
  EXPECT_EQ(ReadBytes(out), whole);
}

}  // namespace
}  // namespace raycell
