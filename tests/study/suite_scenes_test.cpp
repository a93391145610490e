// Every scheduler, `auto` included, processes every ray, segment and sample of every scene of
// the shipped suite exactly once (issue 42), at 1, 2 and 8 processors: each scene file
// recorded small (16x16, 2 frames, 3x3x3 cells) and replayed per ray segment, the replay's
// counts against the trace's own totals (its frame index, written by the recorder).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <numeric>
#include <sstream>

#include "record/record_flags.h"
#include "record/recorder.h"
#include "replay/config.h"
#include "runner/driver.h"
#include "scheduling/scheduler.h"
#include "tests/test_util.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

namespace fs = std::filesystem;

TEST(SuiteScenes, EverySchedulerProcessesEveryRaySegmentAndSampleOnce) {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(fs::path(RAYCELL_SOURCE_DIR) / "scenes")) {
    if (e.path().extension() == ".toml") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  ASSERT_GE(files.size(), 10u);
  const auto dir = testing::TempDir("suite_scenes");
  for (const fs::path& file : files) {
    SCOPED_TRACE(file.filename().string());
    RecordFlags flags;
    flags.opt.scene.source = file.string();
    flags.res = "16x16";
    flags.cells = "3x3x3";
    flags.frames = "0..1";
    flags.opt.out = (dir / (file.stem().string() + ".rct")).string();
    flags.no_images = true;
    flags.quiet = true;
    RecordOptions o = ToRecordOptions(flags);
    o.images_dir.clear();
    o.progress = false;
    std::ostringstream log;
    Record(o, log);
    const TraceReader reader = TraceReader::Open(o.out);
    std::uint64_t rays = 0, visits = 0, samples = 0;
    for (const FrameSummary& f : reader.frames()) {
      rays += f.rays, visits += f.visits, samples += f.samples;
    }
    ASSERT_GT(visits, 0u);
    std::vector<std::size_t> frames(reader.frames().size());
    std::iota(frames.begin(), frames.end(), std::size_t{0});
    std::vector<ReplayConfig> configs;
    for (const SchedulerEntry& s : SchedulerRegistry()) {
      for (const char* p : {"1", "2", "8"}) {
        ReplayConfig c = DefaultConfig();
        ApplyOverride(c, "scheduler", s.name, "test");
        ApplyOverride(c, "processors.count", p, "test");
        ApplyOverride(c, "granularity", "ray", "test");
        configs.push_back(c);
      }
    }
    std::vector<ReplayResult> totals(configs.size());
    ReplayFramesOptions opt;
    opt.jobs = 2;
    ReplayFrames(reader, frames, configs, opt,
                 [&](const LoadedFrame&, const std::vector<ReplayResult>& results) {
                   for (std::size_t i = 0; i < results.size(); ++i) {
                     totals[i].rays += results[i].rays;
                     totals[i].segments += results[i].segments;
                     totals[i].samples += results[i].samples;
                   }
                   return true;
                 });
    for (std::size_t i = 0; i < configs.size(); ++i) {
      SCOPED_TRACE(std::string(configs[i].scheduler->name) + " at " +
                   std::to_string(configs[i].processors.count) + " processors");
      EXPECT_EQ(totals[i].rays, rays);
      EXPECT_EQ(totals[i].segments, visits);
      EXPECT_EQ(totals[i].samples, samples);
    }
    if (::testing::Test::HasFailure()) break;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace raycell
