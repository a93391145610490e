// Every command at 16x16x16 cells processes every ray, segment and sample of the trace exactly
// once (issue 43): record, analyze, replay (per node and per ray segment, 1 and 8 processors,
// a scheduler that reads no earlier frame, one that reads the previous frame's tree, the
// oracle that reads the frame's own), sweep and trace regroup. Their reported counts are compared
// with counts taken here from the trace's own rays, column by column (not through the Cell Tree,
// the work graphs or the regrouper the commands use). 4096 cells on a 48x48 image: most nodes
// hold one ray, so a frame's trees and work are as large as its rays, the regime where the
// commands now drop what they do not need (docs/design.md §2 "What a replay holds").
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tests/replay/random_frame.h"
#include "tests/test_util.h"
#include "tests/tools/cli_util.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

using testing::CliDir;
using testing::Raycell;

struct Counts {
  std::uint64_t rays = 0;         // every ray of the frame
  std::uint64_t worked_rays = 0;  // rays with at least one visit (what a replay counts)
  std::uint64_t segments = 0, samples = 0;
  bool operator==(const Counts& o) const {
    return rays == o.rays && worked_rays == o.worked_rays && segments == o.segments &&
           samples == o.samples;
  }
};

// Per frame, from the rays as the reader delivers them.
std::vector<Counts> CountFrames(const TraceReader& reader) {
  std::vector<Counts> out;
  for (std::size_t f = 0; f < reader.frames().size(); ++f) {
    Counts c;
    reader.ForEachBatch(f, [&](const RayBatch& b) {
      const testing::RayCounts k = testing::CountRays(b);
      c.rays += b.size();
      c.worked_rays += k.rays;
      c.segments += k.segments;
      c.samples += k.samples;
    });
    out.push_back(c);
  }
  return out;
}

Counts Sum(const std::vector<Counts>& frames) {
  Counts t;
  for (const Counts& c : frames) {
    t.rays += c.rays;
    t.worked_rays += c.worked_rays;
    t.segments += c.segments;
    t.samples += c.samples;
  }
  return t;
}

std::uint64_t Field(const std::vector<std::vector<std::string>>& rows, std::size_t row,
                    const std::string& name) {
  for (std::size_t k = 0; k < rows[0].size(); ++k) {
    if (rows[0][k] == name) return std::stoull(rows.at(row).at(k));
  }
  ADD_FAILURE() << "no column " << name;
  return 0;
}

// The replay's rows (frames, then the total) carry each frame's worked rays, segments and
// samples.
void ExpectReplayCounts(const std::string& trace, const std::vector<Counts>& frames,
                        const std::string& options) {
  const testing::Result r = Raycell("replay " + trace + " --format csv --quiet " + options, false);
  ASSERT_EQ(r.code, 0) << options;
  const auto rows = testing::CsvText(r.out);
  ASSERT_EQ(rows.size(), frames.size() + 2) << options;  // header, frames, total
  for (std::size_t f = 0; f <= frames.size(); ++f) {
    const Counts c = f < frames.size() ? frames[f] : Sum(frames);
    EXPECT_EQ(Field(rows, f + 1, "rays"), c.worked_rays) << options << " row " << f;
    EXPECT_EQ(Field(rows, f + 1, "segments"), c.segments) << options << " row " << f;
    EXPECT_EQ(Field(rows, f + 1, "samples"), c.samples) << options << " row " << f;
  }
}

TEST(EveryRayOnce, EveryCommandAt4096CellsCountsTheTracesRaysSegmentsAndSamples) {
  const std::filesystem::path dir = CliDir("every_ray_once");
  const std::string trace = (dir / "c.rct").string();
  const testing::Result rec = Raycell("record --res 48x48 --orbit 2:10 --cells 16x16x16 " +
                                      std::string("--no-images --quiet --out ") + trace);
  ASSERT_EQ(rec.code, 0) << rec.out;
  const TraceReader reader = TraceReader::Open(trace);
  ASSERT_EQ(reader.header().cell_count(), 4096u);
  const std::vector<Counts> frames = CountFrames(reader);
  ASSERT_EQ(frames.size(), 2u);
  for (const Counts& c : frames) {
    ASSERT_GT(c.rays, 1000u);  // a frame worth the name
    EXPECT_LT(c.worked_rays, c.rays + 1);
  }

  // record: "frame F: R rays (...), V visits, S samples, T s" per frame.
  {
    std::istringstream in(rec.out);
    std::size_t f = 0;
    for (std::string line; std::getline(in, line);) {
      if (line.rfind("frame ", 0) != 0) continue;
      ASSERT_LT(f, frames.size());
      unsigned long long rays = 0, visits = 0, samples = 0;
      const std::size_t colon = line.find(':');
      rays = std::stoull(line.substr(colon + 1));
      visits = std::stoull(line.substr(line.find("), ") + 3));
      samples = std::stoull(line.substr(line.find(" visits, ") + 9));
      EXPECT_EQ(rays, frames[f].rays) << line;
      EXPECT_EQ(visits, frames[f].segments) << line;
      EXPECT_EQ(samples, frames[f].samples) << line;
      ++f;
    }
    EXPECT_EQ(f, frames.size());
  }

  // analyze: every ray of each frame goes into its Cell Tree.
  {
    const testing::Result r = Raycell("analyze " + trace + " --format csv --quiet", false);
    ASSERT_EQ(r.code, 0);
    const auto rows = testing::CsvText(r.out);
    ASSERT_EQ(rows.size(), frames.size() + 1);
    for (std::size_t f = 0; f < frames.size(); ++f) {
      EXPECT_EQ(Field(rows, f + 1, "rays"), frames[f].rays);
      EXPECT_GT(Field(rows, f + 1, "nodes"), 0u);
    }
  }

  // replay: per node and per segment, schedulers with and without earlier frames' trees.
  for (const char* options :
       {"--scheduler maxwork", "--scheduler maxwork --set processors.count=8",
        "--scheduler maxwork --granularity ray", "--scheduler celltree",
        "--scheduler celltree --set processors.count=8", "--scheduler peel --granularity ray"}) {
    ExpectReplayCounts(trace, frames, options);
  }

  // sweep: every combination's row holds the whole trace's counts.
  {
    const std::string out = (dir / "sweep.csv").string();
    const testing::Result r = Raycell("sweep " + trace +
                                      " --vary processors.count=1,8 --vary "
                                      "scheduler=maxwork,celltree --jobs 2 "
                                      "--quiet --out " +
                                      out);
    ASSERT_EQ(r.code, 0) << r.out;
    const auto rows = testing::CsvText(testing::ReadBytes(out));
    ASSERT_EQ(rows.size(), 5u);
    const Counts t = Sum(frames);
    for (std::size_t row = 1; row < rows.size(); ++row) {
      EXPECT_EQ(Field(rows, row, "rays"), t.worked_rays) << "row " << row;
      EXPECT_EQ(Field(rows, row, "segments"), t.segments) << "row " << row;
      EXPECT_EQ(Field(rows, row, "samples"), t.samples) << "row " << row;
    }
  }

  // trace regroup: a regroupable capture at 16x16x16 into 8x8x8 keeps every sample, and
  // every ray but the primary rays (never parents) that cross only empty coarse cells (a
  // coarse cell is empty when its 2x2x2 fine cells all are); the regrouped trace then
  // replays with its own counts.
  {
    const std::string fine = (dir / "fine.rct").string(), coarse = (dir / "coarse.rct").string();
    ASSERT_EQ(Raycell("record --res 48x48 --orbit 2:10 --cells 16x16x16 --regroupable "
                      "--no-images --quiet --out " +
                      fine)
                  .code,
              0);
    ASSERT_EQ(Raycell("trace regroup " + fine + " --cells 8x8x8 --out " + coarse).code, 0);
    const TraceReader stored = TraceReader::OpenStored(fine);
    const TraceReader regrouped = TraceReader::Open(coarse);
    const std::vector<std::uint64_t>& footprints = stored.header().footprints;
    ASSERT_EQ(footprints.size(), 4096u);
    std::vector<bool> coarse_full(512, false);
    for (std::uint32_t c = 0; c < 4096; ++c) {
      const std::uint32_t x = c % 16, y = c / 16 % 16, z = c / 256;
      if (footprints[c] > 0) coarse_full[x / 2 + 8 * (y / 2 + 8 * (z / 2))] = true;
    }
    const auto coarse_full_of = [&](CellId fine) {
      const std::uint32_t c = fine.value(), x = c % 16, y = c / 16 % 16, z = c / 256;
      return bool(coarse_full[x / 2 + 8 * (y / 2 + 8 * (z / 2))]);
    };
    ASSERT_EQ(regrouped.frames().size(), stored.frames().size());
    const std::vector<Counts> after = CountFrames(regrouped);
    for (std::size_t f = 0; f < stored.frames().size(); ++f) {
      std::uint64_t rays = 0, samples = 0;
      stored.ForEachBatch(f, [&](const RayBatch& b) {
        for (std::size_t r = 0; r < b.size(); ++r) {
          bool any = false;
          for (std::size_t v = b.visit_begin(r); v < b.visit_end(r); ++v) {
            any = any || coarse_full_of(b.cells()[v]);
          }
          if (any || !b.ray(r).is_primary()) ++rays;
        }
        for (std::uint32_t s : b.samples()) samples += s;
      });
      EXPECT_EQ(after[f].rays, rays) << "frame " << f;
      EXPECT_EQ(after[f].samples, samples) << "frame " << f;
      EXPECT_GT(after[f].segments, 0u);
    }
    ExpectReplayCounts(coarse, after, "--scheduler celltree --set processors.count=8");
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace raycell
