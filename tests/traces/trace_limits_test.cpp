// The format's limits (traces/format.h) and versions: the largest cell grid round-trips,
// footprints split over several records, the writer refuses what the reader could not read
// (before writing anything), and version 1 files still read.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <random>
#include <string>

#include "tests/test_util.h"
#include "tests/traces/trace_test_util.h"
#include "traces/format.h"
#include "traces/trace_reader.h"
#include "traces/trace_writer.h"

namespace raycell {
namespace {

using testing::ErrorOf;
using testing::RandomFrame;
using testing::TestHeader;

std::string TempPath(const std::string& name) { return testing::TempPath("limits", name); }

bool Exists(const std::string& path) { return std::ifstream(path).good(); }

// Writes `header` and one small random frame; returns the reader of the result.
TraceReader WriteAndRead(const std::string& path, const TraceHeader& header,
                         const TraceWriterOptions& options = {}) {
  std::mt19937_64 rng(5);
  TraceWriter w = TraceWriter::Create(path, header, options);
  w.BeginFrame(1);
  w.Append(RandomFrame(rng, 200, false, header.cell_count()));
  w.EndFrame();
  w.Finish();
  return TraceReader::Open(path);
}

TEST(TraceLimitsTest, LargestCellGridRoundTrips) {
  // 256x256x256 cells, sparse as real scenes are: a ball of occupied cells whose footprints
  // vary, empty cells (footprint 0) around it.
  TraceHeader h = TestHeader({256, 256, 256});
  ASSERT_EQ(TraceCellCount(h.cells), kTraceMaxCells);
  for (std::uint64_t c = 0; c < h.footprints.size(); ++c) {
    const std::int64_t x = c % 256 - 128, y = c / 256 % 256 - 128, z = c / 65536 - 128;
    h.footprints[c] =
        x * x + y * y + z * z < 100 * 100 ? 4096 * (1 + (x * 7 + y * 3 + z + 640) % 5) : 0;
  }
  const std::string path = TempPath("largest.rct");
  const TraceReader reader = WriteAndRead(path, h);
  EXPECT_EQ(reader.warning(), "");
  EXPECT_TRUE(reader.header() == h);
  EXPECT_EQ(reader.LoadFrame(0).size(), 200u);
  std::remove(path.c_str());
}

TEST(TraceLimitsTest, FootprintsSplitOverRecordsRoundTrip) {
  // Footprints that change at every cell, and runs of every length, over records of 1, 2, 5
  // and 1000 runs.
  TraceHeader h = TestHeader({7, 5, 3});
  std::mt19937_64 rng(3);
  for (std::size_t c = 0; c < h.footprints.size();) {
    const std::uint64_t value = rng() % 3 == 0 ? 0 : rng() % 2 ? rng() : 200 + rng() % 100;
    for (std::size_t n = 1 + rng() % 6; n > 0 && c < h.footprints.size(); --n) {
      h.footprints[c++] = value;
    }
  }
  for (std::size_t runs : {1, 2, 5, 1000}) {
    SCOPED_TRACE(runs);
    TraceWriterOptions options;
    options.footprint_runs_per_record = runs;
    const std::string path = TempPath("records.rct");
    const TraceReader reader = WriteAndRead(path, h, options);
    EXPECT_EQ(reader.warning(), "");
    EXPECT_TRUE(reader.header() == h);
    std::remove(path.c_str());
  }
}

TEST(TraceLimitsTest, WriterRefusesBeyondTheLimitsBeforeWriting) {
  const std::string path = TempPath("refused.rct");
  std::remove((path + ".tmp").c_str());
  auto refusal = [&](const TraceHeader& h) {
    const std::string e = ErrorOf([&] { TraceWriter::Create(path, h); });
    EXPECT_FALSE(Exists(path + ".tmp")) << "something was written for: " << e;
    return e;
  };
  TraceHeader h = TestHeader();
  h.cells = {1000, 1000, 1000};  // footprints are never looked at: the grid is refused first
  EXPECT_EQ(refusal(h), path +
                            ": cell grid 1000x1000x1000 = 1000000000 cells exceeds the trace "
                            "format's limit of 16777216 cells (kTraceMaxCells, e.g. 256x256x256)");
  h.cells = {257, 256, 256};
  EXPECT_NE(refusal(h).find("16842752 cells exceeds"), std::string::npos);
  h.cells = {65536, 65536, 65536};  // the product overflows 32 bits
  EXPECT_NE(refusal(h).find("= 281474976710656 cells exceeds"), std::string::npos);
  h.cells = {4, 0, 4};
  EXPECT_NE(refusal(h).find("cell grid 4x0x4: every dimension must be at least 1"),
            std::string::npos);

  h = TestHeader();
  h.cameras.resize(kTraceMaxFrames + 1);
  EXPECT_NE(refusal(h).find("262145 cameras (frames) exceed the trace format's limit of 262144"),
            std::string::npos);
  h = TestHeader();
  h.grids.resize(kTraceMaxGrids + 1);
  EXPECT_NE(refusal(h).find("1025 grids exceed the trace format's limit of 1024"),
            std::string::npos);
  h = TestHeader();
  h.scene.assign(kTraceMaxTextBytes + 1, 's');
  EXPECT_NE(refusal(h).find("the scene has 4097 bytes, more than the trace format's limit of 4096"),
            std::string::npos);
  h = TestHeader();
  h.grids[1].source.assign(kTraceMaxTextBytes + 1, 's');
  EXPECT_NE(refusal(h).find("a grid's name, role or source has 4097 bytes"), std::string::npos);
}

TEST(TraceLimitsTest, CellGridCheckForOptions) {
  EXPECT_EQ(ErrorOf([] { CheckTraceCellGrid({256, 256, 256}, "--cells '256x256x256'"); }), "");
  EXPECT_EQ(ErrorOf([] { CheckTraceCellGrid({4096, 4096, 1}, "--cells"); }), "");
  EXPECT_EQ(ErrorOf([] {
              CheckTraceCellGrid({1000, 1000, 1000}, "--cells '1000x1000x1000'");
            }),
            "--cells '1000x1000x1000': cell grid 1000x1000x1000 = 1000000000 cells exceeds the "
            "trace format's limit of 16777216 cells (kTraceMaxCells, e.g. 256x256x256)");
}

TEST(TraceLimitsTest, HeaderAtEveryLimitAtOnceIsWrittenAndRead) {
  // The most frames' cameras, the most grids with the longest texts: the header message
  // must stay below kTraceMaxMessageBytes (the writer checks it).
  TraceHeader h = TestHeader({2, 2, 2});
  h.cameras.resize(kTraceMaxFrames);
  for (std::size_t f = 0; f < h.cameras.size(); ++f) {
    h.cameras[f].frame = static_cast<std::int32_t>(f);
    h.cameras[f].eye = {1.0 * f, 2, 3};
  }
  const std::string text(kTraceMaxTextBytes, 't');
  h.grids.assign(kTraceMaxGrids, {text, text, text, 0.5, 99});
  h.producer = h.scene = h.footprint_mode = text;
  const std::string path = TempPath("all_limits.rct");
  const TraceReader reader = WriteAndRead(path, h);
  EXPECT_EQ(reader.warning(), "");
  EXPECT_TRUE(reader.header() == h);
  std::remove(path.c_str());
}

TEST(TraceLimitsTest, WriterRefusesAFrameBeyondTheLimit) {
  // With the limit lowered to 3 (writing kTraceMaxFrames frames takes seconds: that case,
  // whose index message must fit too, is measured in BENCHMARKS.md "Trace format limits").
  const std::string path = TempPath("frames.rct");
  TraceWriterOptions options;
  options.max_frames = 3;
  TraceWriter w = TraceWriter::Create(path, TestHeader({2, 1, 1}), options);
  for (std::int32_t f = 0; f < 3; ++f) {
    w.BeginFrame(f);
    w.EndFrame();
  }
  EXPECT_EQ(ErrorOf([&] { w.BeginFrame(3); }),
            path + ": more than 3 frames, the trace format's limit (kTraceMaxFrames)");
  w.Finish();
  EXPECT_EQ(TraceReader::Open(path).frames().size(), 3u);
  std::remove(path.c_str());
}

// tests/traces/data/v1_builtin.rct: written by raycell at commit f5c7e8e (format version 1,
// footprints in the header message) with
//   raycell record --res 12x10 --cells 3x3x3 --orbit 2:30 --store-t --no-images
TEST(TraceLimitsTest, Version1FilesStillRead) {
  const std::string path = std::string(RAYCELL_SOURCE_DIR) + "/tests/traces/data/v1_builtin.rct";
  const TraceReader reader = TraceReader::Open(path);
  EXPECT_EQ(reader.warning(), "");
  const TraceHeader& h = reader.header();
  EXPECT_EQ(h.format_version, 1u);
  EXPECT_EQ(h.scene, "builtin");
  EXPECT_EQ(h.cells, (std::array<std::uint32_t, 3>{3, 3, 3}));
  ASSERT_EQ(h.footprints.size(), 27u);
  EXPECT_EQ(h.footprints[0], 72896u);
  EXPECT_EQ(h.footprints[26], 27872u);
  EXPECT_TRUE(h.settings.store_t);
  ASSERT_EQ(reader.frames().size(), 2u);
  EXPECT_EQ(reader.frames()[0].rays, 388u);
  EXPECT_EQ(reader.frames()[1].rays, 374u);
  // LoadFrame verifies the frame checksums, so the decoded rays are the ones written.
  EXPECT_EQ(reader.LoadFrame(0).visit_count(), 987u);
  EXPECT_EQ(reader.LoadFrame(1).visit_count(), 900u);
}

// tests/traces/data/v4_builtin.rct: written by raycell at commit e03c0fa (format version 4,
// the last before the version 5 encoding) with
//   raycell record --res 24x16 --cells 4x4x4 --orbit 2:30 --no-images
// Its totals are those that raycell's `trace info` printed then.
TEST(TraceLimitsTest, Version4FilesStillReadAndRewriteAsTheCurrentVersion) {
  const std::string path = std::string(RAYCELL_SOURCE_DIR) + "/tests/traces/data/v4_builtin.rct";
  const TraceReader reader = TraceReader::Open(path);
  EXPECT_EQ(reader.warning(), "");
  const TraceHeader& h = reader.header();
  EXPECT_EQ(h.format_version, 4u);
  EXPECT_EQ(h.cells, (std::array<std::uint32_t, 3>{4, 4, 4}));
  ASSERT_EQ(reader.frames().size(), 2u);
  const std::uint64_t rays[] = {1155, 1105}, visits[] = {3432, 3364}, samples[] = {13752, 13094};
  const std::string copy = TempPath("v4_rewritten.rct");
  std::vector<RayBatch> frames;
  {
    TraceWriter w = TraceWriter::Create(copy, h, TraceWriterOptions{});
    for (std::size_t f = 0; f < 2; ++f) {
      EXPECT_EQ(reader.frames()[f].rays, rays[f]);
      EXPECT_EQ(reader.frames()[f].visits, visits[f]);
      EXPECT_EQ(reader.frames()[f].samples, samples[f]);
      // LoadFrame checks the frame's checksum, so the decoded rays are the ones written.
      frames.push_back(reader.LoadFrame(f));
      EXPECT_EQ(frames.back().visit_count(), visits[f]);
      w.BeginFrame(reader.frames()[f].frame);
      w.Append(frames.back());
      // The same rays in the current version: the checksum hashes the decoded rays alike.
      EXPECT_EQ(w.EndFrame().checksum, reader.frames()[f].checksum);
    }
    w.Finish();
  }
  const TraceReader rewritten = TraceReader::Open(copy);
  EXPECT_EQ(rewritten.header().format_version, kTraceDefaultVersion);
  for (std::size_t f = 0; f < 2; ++f) EXPECT_TRUE(rewritten.LoadFrame(f) == frames[f]);
  std::remove(copy.c_str());
}

}  // namespace
}  // namespace raycell
