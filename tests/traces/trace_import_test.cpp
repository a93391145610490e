// `raycell trace import`: JSON Lines from any tool in, a trace out whose `trace cat` gives the
// same rays back in raycell's order, with the documented header defaults.
#include "traces/trace_import.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>

#include "tests/test_util.h"
#include "tests/traces/random_paths.h"
#include "traces/jsonl.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

using namespace testing;

std::string Temp(const std::string& name) { return testing::TempPath("import", name); }

void Write(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

std::string Cat(const std::string& trace) {
  const TraceReader r = TraceReader::Open(trace);
  std::ostringstream out;
  WriteJsonl(r, std::nullopt, out);
  return out.str();
}

// Many random path sets (random grids, several frames of random ray trees over random cells
// with random samples) written as another tool might: importing then `trace cat` gives the
// rays back exactly as raycell writes them.
TEST(TraceImportTest, ImportThenCatIsTheIdentity) {
  std::mt19937 rng(7);
  const std::string jsonl = Temp("random.jsonl"), trace = Temp("random.rct");
  for (int round = 0; round < 60; ++round) {
    ImportOptions o;
    o.paths = jsonl;
    o.out = trace;
    o.cells = {std::uint32_t(1 + rng() % 4), std::uint32_t(1 + rng() % 3),
               std::uint32_t(1 + rng() % 3)};
    const std::uint32_t cells = o.cells[0] * o.cells[1] * o.cells[2];
    const int frame_count = 1 + rng() % 5;
    std::set<int> numbers;
    while (int(numbers.size()) < frame_count) numbers.insert(int(rng() % 400) - 100);
    std::vector<int> frames(numbers.begin(), numbers.end());
    if (round % 2) std::shuffle(frames.begin(), frames.end(), rng);
    std::string text, expected;
    std::uint32_t max_x = 0, max_y = 0;
    for (int f : frames) {
      const RayBatch b = RandomFrame(rng, cells, 1 + rng() % 50);
      Disguise d;
      d.shuffle = round % 3 != 0;
      text += Join(DisguisedLines(rng, b, f, d));
      expected += CanonicalJsonl(b, frame_count > 1 ? std::optional<int>(f) : std::nullopt);
      for (std::uint32_t x : b.pixel_xs()) max_x = std::max(max_x, x);
      for (std::uint32_t y : b.pixel_ys()) max_y = std::max(max_y, y);
    }
    Write(jsonl, text);
    const ImportSummary s = ImportJsonl(o);
    EXPECT_EQ(s.frames, frames.size());
    ASSERT_EQ(Cat(trace), expected) << text;
    const TraceReader r = TraceReader::Open(trace);
    ASSERT_EQ(r.frames().size(), frames.size());
    for (std::size_t i = 0; i < frames.size(); ++i) {
      EXPECT_EQ(r.frames()[i].frame, frames[i]);
      EXPECT_EQ(r.header().cameras[i].frame, frames[i]);
    }
    EXPECT_EQ(r.header().cells, o.cells);
    EXPECT_EQ(r.header().settings.width, max_x + 1);
    EXPECT_EQ(r.header().settings.height, max_y + 1);
  }
  std::remove(jsonl.c_str());
  std::remove(trace.c_str());
}

TEST(TraceImportTest, HeaderDefaultsAndOptions) {
  const std::string jsonl = Temp("header.jsonl"), trace = Temp("header.rct");
  Write(jsonl, R"({"id":4,"parent":null,"spawn":null,"cells":[3,5],"pixel":[9,2]})"
               "\n");
  ImportOptions o;
  o.paths = jsonl;
  o.out = trace;
  o.cells = {2, 3, 1};
  ImportJsonl(o);
  TraceHeader h = TraceReader::Open(trace).header();
  EXPECT_EQ(h.format_version, kTraceDefaultVersion);
  EXPECT_EQ(h.producer, "raycell 0.1.0 (trace import)");
  EXPECT_EQ(h.scene, "import:" + jsonl);
  EXPECT_TRUE(h.grids.empty());
  EXPECT_EQ(h.box_min, (Vec3d{0, 0, 0}));
  EXPECT_EQ(h.box_max, (Vec3d{2, 3, 1}));
  EXPECT_EQ(h.footprints, std::vector<std::uint64_t>(6, 1u << 20));
  EXPECT_EQ(h.footprint_mode, "uniform");
  ASSERT_EQ(h.cameras.size(), 1u);
  EXPECT_EQ(h.cameras[0], CameraKey{});
  RenderSettings settings;
  settings.width = 10;
  settings.height = 3;
  EXPECT_EQ(h.settings, settings);

  o.footprint = 4096;
  o.box = {{-1, -2, -3}, {1, 2, 3}};
  o.zstd_level = 9;
  ImportJsonl(o);
  h = TraceReader::Open(trace).header();
  EXPECT_EQ(h.footprints, std::vector<std::uint64_t>(6, 4096));
  EXPECT_EQ(h.box_min, (Vec3d{-1, -2, -3}));
  EXPECT_EQ(h.box_max, (Vec3d{1, 2, 3}));
  EXPECT_EQ(h.settings.zstd_level, 9u);
  EXPECT_EQ(
      Cat(trace),
      R"({"id":0,"parent":null,"spawn":null,"kind":"primary","pixel":[9,2],"cells":[3,5],"samples":[1,1]})"
      "\n");
  std::remove(jsonl.c_str());
  std::remove(trace.c_str());
}

// Bad input writes nothing, not even a temporary file, and names the line or the option.
TEST(TraceImportTest, BadInputWritesNothing) {
  const std::string jsonl = Temp("bad.jsonl"), trace = Temp("bad.rct");
  ImportOptions o;
  o.paths = jsonl;
  o.out = trace;
  o.cells = {2, 2, 2};
  const std::string good = R"({"frame":1,"id":0,"parent":null,"spawn":null,"cells":[7]})"
                           "\n";
  Write(jsonl, good + R"({"frame":2,"id":0,"parent":null,"spawn":null,"cells":[3,8]})"
                      "\n");
  EXPECT_EQ(ErrorOf([&] { ImportJsonl(o); }),
            jsonl + ":2: ray 0: cell 8 out of range: --cells 2x2x2 has 8 cells");
  EXPECT_FALSE(std::filesystem::exists(trace));
  EXPECT_FALSE(std::filesystem::exists(trace + ".tmp"));
  Write(jsonl, good);
  o.footprint = 0;
  EXPECT_NE(ErrorOf([&] { ImportJsonl(o); }).find("--footprint"), std::string::npos);
  o.footprint = 1;
  o.cells = {1025, 1, 1};
  EXPECT_EQ(ErrorOf([&] { ImportJsonl(o); }),
            "--cells 1025x1x1: each dimension must be in 1..1024 (the trace format's limit)");
  o.cells = {2, 2, 2};
  o.box = {{0, 0, 0}, {1, 0, 1}};
  EXPECT_NE(ErrorOf([&] { ImportJsonl(o); }).find("--box"), std::string::npos);
  o.box.reset();
  o.zstd_level = 20;
  EXPECT_EQ(ErrorOf([&] { ImportJsonl(o); }), "--zstd-level 20: must be in 1..19");
  o.zstd_level = 3;
  Write(jsonl, "\n");
  EXPECT_EQ(ErrorOf([&] { ImportJsonl(o); }), jsonl + ": no rays");
  o.paths = Temp("missing.jsonl");
  EXPECT_EQ(ErrorOf([&] { ImportJsonl(o); }), o.paths + ": cannot open");
  o.paths = ::testing::TempDir();  // opens, but is not a file
  EXPECT_NE(ErrorOf([&] { ImportJsonl(o); }).find(": not a regular file"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(trace));
  EXPECT_FALSE(std::filesystem::exists(trace + ".tmp"));
  std::remove(jsonl.c_str());
}

}  // namespace
}  // namespace raycell
