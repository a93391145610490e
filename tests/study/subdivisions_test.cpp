// The study's subdivision section measures what `raycell record`, `trace regroup` and
// `raycell replay` give on their own: checked here against those, run independently.
#include "study/subdivisions.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <numeric>
#include <sstream>

#include "record/recorder.h"
#include "replay/config.h"
#include "replay/replayer.h"
#include "runner/driver.h"
#include "tests/test_util.h"
#include "traces/trace_reader.h"
#include "traces/trace_regroup.h"

namespace raycell {
namespace {

TEST(SubdivisionStudy, RowsAreWhatRecordRegroupAndReplayGiveOnTheirOwn) {
  const auto dir = testing::TempDir("subdivision_study");
  SubdivisionOptions o;
  o.res = "32x32";
  o.frames = 2;
  o.fine = "6x6x6";
  o.out = (dir / "sub").string();
  const SubdivisionStudy s = MeasureSubdivisions(o);
  ASSERT_TRUE(s.measured);
  ASSERT_EQ(s.rows.size(), 18u);  // 9 SPECs, 2 schedulers

  // The cache: the median footprint of a capture recorded directly on 3x3x3 cells.
  RecordOptions direct;
  direct.settings.width = direct.settings.height = 32;
  direct.cells = {3, 3, 3};
  direct.out = (dir / "direct3.rct").string();
  direct.images_dir.clear();
  direct.progress = false;
  std::ostringstream log;
  Record(direct, log);
  std::vector<std::uint64_t> f;
  const TraceReader direct_reader = TraceReader::Open(direct.out);
  for (std::uint64_t b : direct_reader.header().footprints) {
    if (b != 0) f.push_back(b);
  }
  std::sort(f.begin(), f.end());
  EXPECT_EQ(s.cache_bytes, f[(f.size() - 1) / 2]);

  const std::vector<std::string> specs = SubdivisionSpecs(s.cache_bytes);
  for (std::size_t i = 0; i < s.rows.size(); ++i) {
    const SubdivisionRow& row = s.rows[i];
    SCOPED_TRACE(row.spec + " " + row.scheduler);
    EXPECT_EQ(row.spec, specs[i / 2]);
    EXPECT_EQ(row.scheduler, i % 2 == 0 ? "maxwork" : "celltree");
    EXPECT_LE(row.footprint_min, row.footprint_median);
    EXPECT_LE(row.footprint_median, row.footprint_max);
    // The same replay of the file `trace regroup` writes.
    const std::string file = (dir / ("r" + std::to_string(i) + ".rct")).string();
    RegroupTrace(o.out + "/fine.rct", row.spec, file);
    const TraceReader reader = TraceReader::Open(file);
    ReplayConfig config = DefaultConfig();
    ApplyOverride(config, "scheduler", row.scheduler, "test");
    ApplyOverride(config, "level.cache.capacity", std::to_string(s.cache_bytes) + "B", "test");
    std::vector<std::size_t> frames(reader.frames().size());
    std::iota(frames.begin(), frames.end(), std::size_t{0});
    const ReplayResult t = ReplayTrace(reader, frames, config, {}, 1).total;
    EXPECT_GT(t.fetches, 0u);
    EXPECT_EQ(row.fetches, t.fetches);
    EXPECT_EQ(row.cache_bytes, t.levels[0].bytes);
    EXPECT_EQ(row.board_bytes, t.levels[1].bytes);
    EXPECT_EQ(row.stall_ps, t.stall.picoseconds());
    EXPECT_EQ(row.time_ps, t.time.picoseconds());
  }
  // The uniform grid's row: the direct capture's non-empty cells.
  EXPECT_EQ(s.rows[0].cells, f.size());
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace raycell
