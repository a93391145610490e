// Sweeps (issue 4): --vary parsing and combination order, validation before any work,
// byte-identical output for any --jobs, rows equal to single replays, shards merged into the
// unsharded file, and resuming an interrupted sweep.
#include "replay/sweep.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>

#include "base/check.h"
#include "base/format.h"
#include "replay/driver.h"
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
    << r.time.picoseconds() << ',' << r.work.picoseconds() << ',' << r.stall.picoseconds() << ','
    << r.idle.picoseconds() << ',' << FormatFixed(r.utilisation, 4) << ',' << r.peak_queued_rays
    << ',' << r.peak_queued_bytes << ',' << r.rays << ',' << r.segments << ',' << r.samples << '\n';
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
RayBatch RandomFrame(std::mt19937& rng, std::size_t rays, CellId cells) {
  RayBatch b(false);
  for (std::size_t i = 0; i < rays; ++i) {
    const bool child = i > 0 && i % 3 == 0 && b.ray(i - 1).visit_count > 0;
    const RayId parent = child ? i - 1 : kNoParent;
    const std::uint32_t spawn = child ? rng() % b.ray(i - 1).visit_count : 0;
    b.BeginRay(child ? RayKind::kShadow : RayKind::kPrimary, parent, spawn, 0, 0);
    CellId cell = child ? b.ray(i - 1).cells[spawn] : CellId(rng() % cells);
    for (int v = 0, n = 1 + int(rng() % 4); v < n; ++v) {
      b.AddVisit(cell, 1 + rng() % 20, 0, 0);
      cell = (cell + 1 + rng() % (cells - 1)) % cells;
    }
  }
  return b;
}

std::string WriteTrace(int frames) {
  const std::string path = TempPath("trace.rct");
  const TraceHeader h = MakeHeader(frames);
  TraceWriter w = TraceWriter::Create(path, h, 3);
  std::mt19937 rng(7);
  for (int f = 0; f < frames; ++f) {
    w.BeginFrame(f);
    w.Append(RandomFrame(rng, 40, h.cell_count()));
    w.EndFrame();
  }
  w.Finish();
  return path;
}

class SweepTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    trace_path_ = new std::string(WriteTrace(3));
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
    spec.frame_indices = {0, 1, 2};
    spec.shard = shard;
    return spec;
  }

  // Runs `spec` into a fresh file named `name`; returns its bytes.
  std::string Run(const SweepSpec& spec, const std::string& name, unsigned jobs = 1) {
    const std::string out = Fresh(name);
    SweepOptions options;
    options.jobs = jobs;
    const SweepOutcome o = RunSweep(*reader_, spec, out, options);
    EXPECT_TRUE(o.complete);
    EXPECT_FALSE(Exists(out + ".partial"));
    return ReadBytes(out);
  }

  std::string Fresh(const std::string& name) {
    const std::string path = TempPath(name);
    std::remove(path.c_str());
    std::remove((path + ".partial").c_str());
    paths_.push_back(path);
    return path;
  }

  void TearDown() override {
    for (const std::string& p : paths_) {
      std::remove(p.c_str());
      std::remove((p + ".partial").c_str());
    }
  }

  static std::string* trace_path_;
  static TraceReader* reader_;
  std::vector<std::string> paths_;
};

std::string* SweepTest::trace_path_ = nullptr;
TraceReader* SweepTest::reader_ = nullptr;

using testing::ErrorOf;

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
  EXPECT_FALSE(Exists(out + ".partial"));
}

TEST_F(SweepTest, RowsEqualSingleReplaysWhateverTheJobs) {
  const SweepSpec spec = Spec();
  const std::string one = Run(spec, "jobs1.csv", 1);
  EXPECT_EQ(Run(spec, "jobs3.csv", 3), one);
  std::string expected = SweepComment(spec) +
                         "index,scheduler,processors.count,level.cache.capacity,fetches,bound,"
                         "time_ps,work_ps,stall_ps,idle_ps,utilisation,peak_queued_rays,"
                         "peak_queued_bytes,rays,segments,samples\n";
  for (std::size_t i = 0; i < CombinationCount(spec.varies); ++i) {
    const TraceReplay r =
        ReplayTrace(*reader_, spec.frame_indices, CombinationConfig(spec.base, spec.varies, i));
    EXPECT_GT(r.total.rays, 0u);
    expected += ExpectedRow(i, CombinationValues(spec.varies, i), r.total);
  }
  EXPECT_EQ(one, expected);
  EXPECT_EQ(one.rfind("# raycell sweep schema=\"raycell-sweep/1\" trace=", 0), 0u);
  EXPECT_NE(one.find("\n0,maxwork,1,1 cell,"), std::string::npos);
  EXPECT_NE(one.find("\n11,peel,2,2 cells,"), std::string::npos);
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

TEST_F(SweepTest, MergeRejectsShardsOfAnotherSweep) {
  SweepSpec other = Spec({1, 2});
  other.varies[1] = Vary::Parse("processors.count=1,3");
  const std::string a = Fresh("a.csv"), b = Fresh("b.csv");
  RunSweep(*reader_, Spec({0, 2}), a, {});
  RunSweep(*reader_, other, b, {});
  const std::string error = ErrorOf([&] { MergeSweepShards(Fresh("ab.csv"), {a, b}); });
  EXPECT_NE(error.find("not a shard of the same sweep"), std::string::npos) << error;
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

}  // namespace
}  // namespace raycell
