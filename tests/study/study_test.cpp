// The study as a library: RunStudy on a tiny setting, with assertions on the data it returns
// (every knob measured, the exact settings exact, every scheduler replaying the whole
// capture, the bracket ordered); the report's texts on hand-made results; the image error
// against values numpy computed.
#include "study/study.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "graph/frame_tree.h"
#include "record/image.h"
#include "replay/config.h"
#include "runner/driver.h"
#include "scheduling/scheduler.h"
#include "study/accuracy.h"
#include "study/depth.h"
#include "study/image_error.h"
#include "study/report.h"
#include "tests/test_util.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

// The folder of this process's study, removed when the tests end.
std::filesystem::path StudyDir() {
  static const std::filesystem::path dir = testing::TempDir("study");
  return dir;
}

class RemoveStudyDir : public ::testing::Environment {
 public:
  void TearDown() override { std::filesystem::remove_all(StudyDir()); }
};
const auto* const kRemoveStudyDir = ::testing::AddGlobalTestEnvironment(new RemoveStudyDir);

// One study for the tests below: the built-in scene, 3 frames at 24x24 in 2x2x2 and 1x2x1
// cells, run time against error on 2 frames at 16x16 (Cell Tree scheduling follows frame 0's
// tree in frame 1).
const StudyResult& TinyStudy() {
  static const StudyResult result = [] {
    StudyOptions o;
    o.res = "24x24";
    o.frames = "3";
    o.cells = "2x2x2,1x2x1";
    o.accuracy_frames = 2;
    o.accuracy_res = "16x16";
    o.quiet = true;
    o.out = (StudyDir() / "study").string();
    return RunStudy(o);
  }();
  return result;
}

const AccuracyRow& RowOf(const std::vector<AccuracyRow>& rows, const std::string& knob,
                         const std::string& value) {
  for (const AccuracyRow& r : rows) {
    if (r.knob == knob && r.value == value) return r;
  }
  ADD_FAILURE() << "no row " << knob << " " << value;
  return rows.front();
}

TEST(Study, MeasuresEveryKnobTheLibraryDeclares) {
  const AccuracyStudy& a = TinyStudy().accuracy;
  ASSERT_TRUE(a.measured) << a.not_measured;
  const std::vector<AccuracyKnob>& knobs = AccuracyKnobs();
  ASSERT_EQ(a.rows.size(), knobs.size());
  for (std::size_t i = 0; i < knobs.size(); ++i) {
    const AccuracyRow& r = a.rows[i];
    EXPECT_EQ(r.knob, knobs[i].knob) << i;
    EXPECT_EQ(r.value, knobs[i].value) << i;
    EXPECT_EQ(r.is_default, knobs[i].is_default) << r.knob << " " << r.value;
    EXPECT_TRUE(std::isfinite(r.error) && r.error >= 0)
        << r.knob << " " << r.value << " " << r.error;
    EXPECT_TRUE(std::isfinite(r.fetch_change)) << r.knob << " " << r.value;
    EXPECT_TRUE(r.seconds > 0 && std::isfinite(r.time_ratio) && r.time_ratio > 0)
        << r.knob << " " << r.value << " " << r.seconds << " " << r.time_ratio;
  }
  // One default per knob that has one: step 1, node granularity, no sampling.
  EXPECT_EQ(RowOf(a.rows, "renderer step", "1").is_default, true);
  const AccuracyRow& reference = a.rows.front();
  EXPECT_EQ(reference.error_kind, "reference");
  EXPECT_EQ(reference.error, 0.0);
  EXPECT_EQ(reference.time_ratio, 1.0);
  EXPECT_EQ(reference.fetch_change, 0.0);
  // A renderer setting other than the reference renders other images.
  EXPECT_GT(RowOf(a.rows, "renderer step", "4").error, 0.0);
  // With one processor, replay per Cell Tree node is exact, and sampling 1 in 1 is no sampling.
  const AccuracyRow& node = RowOf(a.rows, "replay granularity", "node");
  EXPECT_EQ(node.error, 0.0);
  EXPECT_EQ(node.fetch_change, 0.0);
  const AccuracyRow& all = RowOf(a.rows, "replay sampling 1 in k (per ray)", "1");
  EXPECT_EQ(all.error, 0.0);
  EXPECT_EQ(all.fetch_change, 0.0);
  EXPECT_EQ(RowOf(a.rows, "replay granularity", "ray").time_ratio, 1.0);
  // Max depth: measured against max depth 5, record's default (3, `raycell record --help`)
  // marked; depth 0 drops the mirror's and the glass's rays, so its images differ.
  const AccuracyRow& deepest = RowOf(a.rows, "max depth", "5");
  EXPECT_EQ(deepest.error_kind, "image RMSE vs max depth 5");
  EXPECT_EQ(deepest.error, 0.0);
  EXPECT_EQ(deepest.time_ratio, 1.0);
  EXPECT_EQ(deepest.fetch_change, 0.0);
  for (const char* depth : {"0", "1", "2", "3", "4"}) {
    const AccuracyRow& r = RowOf(a.rows, "max depth", depth);
    EXPECT_EQ(r.is_default, std::string(depth) == "3") << depth;
    EXPECT_EQ(r.error_kind, "image RMSE vs max depth 5") << depth;
  }
  EXPECT_GT(RowOf(a.rows, "max depth", "0").error, 0.0);
  // The captures measured are where the study says.
  for (const AccuracyKnob& k : knobs) {
    if (k.folder.empty()) continue;
    EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(a.options.out) / k.folder / "c.rct"))
        << k.folder;
  }
}

// The rays of every frame of a capture by kind, counted from its decoded batches (not from the
// index's summaries, which the depth section reads).
std::array<std::uint64_t, kRayKindCount> DecodedRaysByKind(const TraceReader& reader) {
  std::array<std::uint64_t, kRayKindCount> kinds{};
  for (std::size_t f = 0; f < reader.frames().size(); ++f) {
    reader.ForEachBatch(f, [&](const RayBatch& b) {
      for (const RayKind k : b.kinds()) ++kinds[static_cast<int>(k)];
    });
  }
  return kinds;
}

// The depth section of the tiny study: one row per max depth 0..5, each read from the run
// time against error section's capture of that depth, and checked here against that capture
// decoded, its trees built and replayed per ray segment independently of the section.
TEST(Study, TheDepthSectionMeasuresTheMaxDepthCaptures) {
  const StudyResult& s = TinyStudy();
  const DepthStudy& d = s.depth;
  ASSERT_TRUE(d.measured) << d.not_measured;
  ASSERT_EQ(d.rows.size(), 6u);
  const std::vector<std::size_t> all = {0, 1};  // the accuracy section's two frames
  for (std::uint32_t depth = 0; depth < 6; ++depth) {
    const DepthRow& r = d.rows[depth];
    const std::string what = "max depth " + std::to_string(depth);
    ASSERT_EQ(r.max_depth, depth);
    EXPECT_EQ(r.is_default, depth == 3) << what;
    const TraceReader reader = TraceReader::Open((std::filesystem::path(s.accuracy.options.out) /
                                                  ("max-depth-" + std::to_string(depth)) / "c.rct")
                                                     .string());
    ASSERT_EQ(reader.frames().size(), 2u) << what;
    EXPECT_EQ(reader.header().settings.max_depth, depth) << what;
    const std::array<std::uint64_t, kRayKindCount> kinds = DecodedRaysByKind(reader);
    EXPECT_EQ(r.rays_by_kind, kinds) << what;
    EXPECT_EQ(r.rays, kinds[0] + kinds[1] + kinds[2] + kinds[3]) << what;
    EXPECT_EQ(r.nodes,
              BuildFrameTree(reader, 0).node_count() + BuildFrameTree(reader, 1).node_count())
        << what;
    for (const char* name : {"maxwork", "celltree"}) {
      ReplayConfig config = DefaultConfig();
      config.scheduler = &SchedulerByName(name, "test");
      config.granularity = ReplayConfig::Granularity::kRay;
      const ReplayResult alone = ReplayTrace(reader, all, config).total;
      const bool mw = std::string(name) == "maxwork";
      EXPECT_EQ(mw ? r.fetches_maxwork : r.fetches_celltree, alone.fetches) << what << " " << name;
      EXPECT_EQ(mw ? r.time_maxwork : r.time_celltree, alone.time) << what << " " << name;
    }
    // The image error is the run time against error row's, and what the images give.
    EXPECT_EQ(r.rmse, RowOf(s.accuracy.rows, "max depth", std::to_string(depth)).error) << what;
    const auto frames = [&](std::uint32_t dep) {
      std::vector<Rgb8Image> images;
      for (const char* name : {"frame_0000.png", "frame_0001.png"}) {
        images.push_back(ReadPng8((std::filesystem::path(s.accuracy.options.out) /
                                   ("max-depth-" + std::to_string(dep)) / name)
                                      .string()));
      }
      return images;
    };
    EXPECT_EQ(r.rmse, ImageRmse(frames(depth), frames(5))) << what;
  }
  // Max depth 0: no reflection or refraction ray, but shadow rays (cast at every depth); the
  // built-in scene's mirror and glass spawn rays at depth 1, and its images differ from depth 5.
  EXPECT_EQ(d.rows[0].rays_by_kind[1] + d.rows[0].rays_by_kind[2], 0u);
  EXPECT_GT(d.rows[0].rays_by_kind[3], 0u);
  EXPECT_GT(d.rows[1].rays_by_kind[1] + d.rows[1].rays_by_kind[2], 0u);
  EXPECT_GT(d.rows[0].rmse, 0.0);
  EXPECT_EQ(d.rows[5].rmse, 0.0);
  // A deeper limit only adds rays: the primary rays are the same, nothing decreases.
  for (std::size_t i = 1; i < d.rows.size(); ++i) {
    EXPECT_EQ(d.rows[i].rays_by_kind[0], d.rows[0].rays_by_kind[0]) << i;
    EXPECT_GE(d.rows[i].rays, d.rows[i - 1].rays) << i;
    EXPECT_GE(d.rows[i].spawned(), d.rows[i - 1].spawned()) << i;
    EXPECT_GE(d.rows[i].nodes, d.rows[i - 1].nodes) << i;
  }
  EXPECT_GT(d.rows[5].rays, d.rows[0].rays);
  EXPECT_GT(d.rows[5].nodes, d.rows[0].nodes);
  // Frame 1 follows frame 0's Peel schedule instead of Max Work's choices: at depth 5 the two
  // differ here (which tells the schedulers' columns apart).
  EXPECT_NE(d.rows[5].fetches_maxwork, d.rows[5].fetches_celltree);
  // The max depth rows' fetch change is Cell Tree scheduling's against max depth 5.
  for (const DepthRow& r : d.rows) {
    const double change = (double(r.fetches_celltree) - double(d.rows[5].fetches_celltree)) /
                          double(d.rows[5].fetches_celltree);
    EXPECT_EQ(RowOf(s.accuracy.rows, "max depth", std::to_string(r.max_depth)).fetch_change, change)
        << r.max_depth;
  }
  const std::string report = StudyReport(s);
  EXPECT_NE(report.find(DepthReport(d)), std::string::npos) << report;
  EXPECT_EQ(DepthReport(d).rfind("## Limited depth recursion\n\n", 0), 0u) << DepthReport(d);
}

// Without the run time against error section there are no max depth captures: the section
// says why instead of making its own.
TEST(Study, TheDepthSectionSaysWhyItIsAbsent) {
  AccuracyStudy skipped;  // --accuracy-frames 0
  skipped.options.frames = 0;
  const DepthStudy d = MeasureDepth(skipped);
  EXPECT_FALSE(d.measured);
  EXPECT_TRUE(d.rows.empty());
  EXPECT_EQ(DepthReport(d),
            "## Limited depth recursion\n\nNot measured: it reads the run time against error "
            "section's captures, which `--accuracy-frames 0` skipped.\n");
  AccuracyStudy elsewhere;
  elsewhere.not_measured = "the scene `x.vdb` cannot be loaded here (no such file)";
  EXPECT_EQ(DepthReport(MeasureDepth(elsewhere)),
            "## Limited depth recursion\n\nNot measured: the scene `x.vdb` cannot be loaded here "
            "(no such file).\n");
  StudyResult r;
  r.accuracy = skipped;
  r.depth = d;
  EXPECT_NE(StudyReport(r).find("## Limited depth recursion\n\nNot measured: "), std::string::npos);
  EXPECT_EQ(DepthReport(DepthStudy{}), "");  // a result never measured: no section
}

// depth.csv and the table on rows given here, the values worked by hand.
TEST(Study, DepthCsvAndTableHoldTheRows) {
  DepthStudy d;
  d.measured = true;
  d.options.frames = 2, d.options.res = "64x64";
  DepthRow a;
  a.max_depth = 0, a.rays_by_kind = {100, 0, 0, 50}, a.rays = 150, a.nodes = 10;
  a.fetches_maxwork = 40, a.fetches_celltree = 30;
  a.time_maxwork = SimTime::Picoseconds(2500000000), a.time_celltree = SimTime::Picoseconds(7);
  a.rmse = 0.1;
  DepthRow b = a;
  b.max_depth = 3, b.is_default = true, b.rays_by_kind = {100, 20, 10, 70}, b.rays = 200;
  b.fetches_celltree = 41, b.rmse = 0.0;
  d.rows = {a, b};
  EXPECT_EQ(DepthCsv(d),
            "max_depth,default,rays,primary_rays,reflection_rays,refraction_rays,shadow_rays,nodes,"
            "fetches_maxwork,fetches_celltree,time_maxwork_ps,time_celltree_ps,rmse\n"
            "0,0,150,100,0,0,50,10,40,30,2500000000,7,0.1\n"
            "3,1,200,100,20,10,70,10,40,41,2500000000,7,0.0\n");
  const std::string report = DepthReport(d);
  // 150 rays over 10 nodes; 30 fetches against 40 is 25% fewer, 41 is 2.5% more; 2.5 ms.
  EXPECT_NE(report.find("| 0 | 150 | 0 / 0 / 50 | 10 | 15.0 | 40 | 30 | -25.0% | 2.50 | 0.00 | "
                        "0.1000 |  |\n"),
            std::string::npos)
      << report;
  EXPECT_NE(report.find("| 3 | 200 | 20 / 10 / 70 | 10 | 20.0 | 40 | 41 | +2.5% | 2.50 | 0.00 | "
                        "0.0000 | yes |\n"),
            std::string::npos)
      << report;
  EXPECT_NE(report.find("(2 frame(s) of the same scene at 64x64 in 3x3x3 cells"), std::string::npos)
      << report;
}

TEST(Study, EverySchedulerReplaysTheWholeCaptureOfEachGrid) {
  const StudyResult& s = TinyStudy();
  ASSERT_EQ(s.grids.size(), 2u);
  EXPECT_EQ(s.frame_numbers, (std::vector<int>{0, 1, 2}));
  const std::vector<const SchedulerEntry*> schedulers = StudySchedulers();
  for (const GridStudy& g : s.grids) {
    const TraceReader reader =
        TraceReader::Open((std::filesystem::path(s.options.out) / g.capture).string());
    std::uint64_t rays = 0, visits = 0, samples = 0;
    for (const FrameSummary& f : reader.frames()) {
      rays += f.rays, visits += f.visits, samples += f.samples;
    }
    ASSERT_EQ(g.trees.size(), 3u) << g.cells;
    ASSERT_EQ(g.replays.size(), schedulers.size()) << g.cells;
    for (std::size_t k = 0; k < schedulers.size(); ++k) {
      const SchedulerReplay& r = g.replays[k];
      EXPECT_EQ(r.scheduler, schedulers[k]) << g.cells;
      EXPECT_EQ(&g.replay(*r.scheduler), &r.replay);
      ASSERT_EQ(r.replay.frames.size(), reader.frames().size())
          << g.cells << " " << r.scheduler->name;
      EXPECT_EQ(r.replay.total.rays, rays) << g.cells << " " << r.scheduler->name;
      EXPECT_EQ(r.replay.total.segments, visits) << g.cells << " " << r.scheduler->name;
      EXPECT_EQ(r.replay.total.samples, samples) << g.cells << " " << r.scheduler->name;
      for (std::size_t i = 0; i < g.trees.size(); ++i) {
        EXPECT_EQ(r.replay.frames[i].frame, g.trees[i].frame) << g.cells;
        EXPECT_EQ(r.replay.frames[i].rays, reader.frames()[i].rays) << g.cells;
      }
    }
    for (const FrameAnalysis& t : g.trees) {
      ASSERT_TRUE(t.lower_bound && t.best_length) << g.cells << " frame " << t.frame;
      EXPECT_LE(t.bound, *t.lower_bound) << g.cells << " frame " << t.frame;
      EXPECT_LE(*t.lower_bound, *t.best_length) << g.cells << " frame " << t.frame;
      EXPECT_LE(*t.best_length, t.peel_length()) << g.cells << " frame " << t.frame;
    }
  }
}

// The finest grid (the last, 1x2x1) replayed on 1 to 16 processors under Max Work, Cell Tree
// scheduling and balanced: every row processes the whole capture, stays above its time bound,
// and equals a replay of its configuration alone (ReplayTrace, the configuration built here).
TEST(Study, TheFinestGridIsReplayedOnSeveralProcessors) {
  const StudyResult& s = TinyStudy();
  ASSERT_EQ(s.grids.size(), 2u);
  EXPECT_TRUE(s.grids[0].processors.empty());
  const GridStudy& g = s.grids[1];
  ASSERT_EQ(g.cells, "1x2x1");
  const TraceReader reader =
      TraceReader::Open((std::filesystem::path(s.options.out) / g.capture).string());
  std::uint64_t rays = 0, visits = 0, samples = 0;
  std::vector<std::size_t> all;
  for (const FrameSummary& f : reader.frames()) {
    rays += f.rays, visits += f.visits, samples += f.samples;
    all.push_back(all.size());
  }
  const std::vector<std::string> names = {"maxwork", "celltree", "balanced"};
  const std::vector<std::uint32_t> counts = {1, 2, 4, 8, 16};
  ASSERT_EQ(g.processors.size(), names.size() * counts.size());
  for (std::size_t i = 0; i < g.processors.size(); ++i) {
    const ProcessorsReplay& r = g.processors[i];
    const std::string name = names[i / counts.size()];
    const std::uint32_t p = counts[i % counts.size()];
    const std::string what = name + " on " + std::to_string(p);
    ASSERT_EQ(r.scheduler->name, name) << i;
    ASSERT_EQ(r.processors, p) << name;
    const ReplayResult& t = r.total;
    EXPECT_EQ(t.rays, rays) << what;
    EXPECT_EQ(t.segments, visits) << what;
    EXPECT_EQ(t.samples, samples) << what;
    EXPECT_LE(t.time_bound, t.time) << what;
    EXPECT_EQ(t.work + t.stall + t.idle, t.time * p) << what;
    ReplayConfig config = DefaultConfig();
    config.scheduler = &SchedulerByName(name, "test");
    config.processors.count = p;
    EXPECT_EQ(t.work, config.processors.time_per_sample * samples) << what;
    const ReplayResult alone = ReplayTrace(reader, all, config).total;
    EXPECT_EQ(t.fetches, alone.fetches) << what;
    ASSERT_FALSE(t.levels.empty()) << what;
    EXPECT_EQ(t.fetches, t.levels[0].fetches) << what;
    EXPECT_EQ(t.levels[0].fetches, alone.levels[0].fetches) << what;
    EXPECT_EQ(t.time, alone.time) << what;
    EXPECT_EQ(t.time_bound, alone.time_bound) << what;
    EXPECT_EQ(t.work, alone.work) << what;
    EXPECT_EQ(t.stall, alone.stall) << what;
    EXPECT_EQ(t.idle, alone.idle) << what;
    EXPECT_EQ(t.utilisation, alone.utilisation) << what;
    // With one processor the default granularity is per node, as the study's own replays.
    if (p == 1 && name != "balanced") {
      EXPECT_EQ(t.fetches, g.replay(*r.scheduler).total.fetches) << what;
      EXPECT_EQ(t.time, g.replay(*r.scheduler).total.time) << what;
    }
  }
}

TEST(Study, TheReportTellsWhatTheResultHolds) {
  const StudyResult& s = TinyStudy();
  const std::string report = StudyReport(s);
  EXPECT_NE(report.find("Scene `builtin`, 3 frames orbiting 90 degrees, 24x24. "),
            std::string::npos)
      << report;
  for (const GridStudy& g : s.grids) EXPECT_NE(report.find(GridReport(g)), std::string::npos);
  EXPECT_EQ(ProcessorsReport(s.grids[0]), "");
  EXPECT_NE(report.find("## Several processors (1x2x1 cells)\n"), std::string::npos) << report;
  EXPECT_NE(report.find(ProcessorsReport(s.grids[1])), std::string::npos) << report;
  EXPECT_EQ(report.find("## Several processors (2x2x2 cells)"), std::string::npos) << report;
  EXPECT_NE(report.find(AccuracyTable(s.accuracy.rows)), std::string::npos) << report;
  // The CSV: a header, then each row with the library's knob, value and default.
  const std::string csv = AccuracyCsv(s.accuracy.rows);
  std::vector<std::string> lines;
  for (std::size_t at = 0, end; (end = csv.find("\r\n", at)) != std::string::npos; at = end + 2) {
    lines.push_back(csv.substr(at, end - at));
  }
  ASSERT_EQ(lines.size(), 1 + AccuracyKnobs().size()) << csv;
  EXPECT_EQ(lines[0], "knob,value,seconds,time_ratio,error,error_kind,fetch_change,default");
  for (std::size_t i = 0; i < AccuracyKnobs().size(); ++i) {
    const AccuracyKnob& k = AccuracyKnobs()[i];
    EXPECT_EQ(lines[i + 1].rfind(k.knob + "," + k.value + ",", 0), 0u) << lines[i + 1];
    EXPECT_NE(lines[i + 1].find(k.is_default ? ",True" : ",False"), std::string::npos);
  }
}

TEST(Study, ProcessorCountsAscendWithinOneToSixtyFour) {
  EXPECT_EQ(ParseProcessorCounts("1,2,4,8,16"), StudyProcessorCounts());
  EXPECT_EQ(ParseProcessorCounts("1,8,64"), (std::vector<std::uint32_t>{1, 8, 64}));
  for (const char* bad : {"0,2", "1,65", "4,2", "2,2", "x", ""}) {
    EXPECT_THROW(ParseProcessorCounts(bad), InputError) << bad;
  }
  EXPECT_NE(testing::ErrorOf([] { ParseProcessorCounts("1,65"); }).find("--processors '1,65'"),
            std::string::npos);
}

TEST(Study, OnTheSuiteQuotesTheSuitesHeadlinesOrSaysWhereTheyWouldBe) {
  StudyResult r;
  r.options.suite = "somewhere/suite";
  const std::string none = SuiteHeadlinesReport(r);
  EXPECT_NE(none.find("no results of it in `somewhere/suite`"), std::string::npos) << none;
  r.suite_scenes = 13;
  r.suite_headlines = {"first (geometric mean; worst +1.0% on x; builtin -2.0%)", "second"};
  const std::string two = SuiteHeadlinesReport(r);
  EXPECT_NE(two.find("from the 13 scenes' results of `raycell suite` in `somewhere/suite`"),
            std::string::npos)
      << two;
  EXPECT_NE(two.find(":\n- first (geometric mean; worst +1.0% on x; builtin -2.0%)\n- second\n\n"),
            std::string::npos)
      << two;
  r.suite_error = "bad.csv: line 3: not a number";
  EXPECT_NE(SuiteHeadlinesReport(r).find("could not be read: bad.csv: line 3: not a number."),
            std::string::npos);
  EXPECT_NE(StudyReport(TinyStudy()).find("## On the suite\n\n"), std::string::npos);
}

// A grid whose numbers are given: Peel meets the lower bound on every frame, or not.
GridStudy HandMadeGrid(std::uint64_t peel, std::uint64_t lower, std::uint64_t best) {
  GridStudy g;
  g.cells = "1x2x1";
  g.heading = "1x2x1 cells";
  g.capture = "capture_1x2x1.rct";
  FrameAnalysis t;
  t.rays = 10, t.nodes = 4, t.bound = lower;
  t.peel_schedule.assign(peel, CellId{0});
  t.lower_bound = lower, t.best_length = best;
  g.trees = {t, t};
  for (const SchedulerEntry* s : StudySchedulers()) {
    SchedulerReplay r{s, {}};
    r.replay.total.fetches = 2 * peel;
    g.replays.push_back(r);
  }
  return g;
}

TEST(Study, NothingToCloseWhenPeelMeetsTheLowerBound) {
  const std::string row =
      "| share of Peel's distance to the lower bound closed by the best schedule |";
  // In the tiny study, Peel is optimal on every frame with two cells, not with eight.
  for (const GridStudy& g : TinyStudy().grids) {
    std::uint64_t peel = 0, lower = 0;
    for (const FrameAnalysis& t : g.trees) peel += t.peel_length(), lower += *t.lower_bound;
    EXPECT_EQ(peel == lower, g.cells == "1x2x1")
        << g.cells << ": Peel " << peel << ", lower " << lower;
    EXPECT_EQ(GridReport(g).find(row + " - |") != std::string::npos, peel == lower)
        << GridReport(g);
  }
  const std::string met = GridReport(HandMadeGrid(3, 3, 3));
  EXPECT_NE(met.find(row + " - |"), std::string::npos) << met;
  const std::string open = GridReport(HandMadeGrid(5, 3, 4));
  EXPECT_NE(open.find(row + " 50.0% |"), std::string::npos) << open;
}

// A grid on several processors whose totals are given: per scheduler and count, fetches and
// time (ms) as listed, a bound of 96 ms / count, utilisation 0.5; at 16 processors balanced's
// bound is 5 ms instead of 6 when `differ`.
GridStudy HandMadeProcessors(bool differ) {
  GridStudy g;
  g.heading = "3x3x3 cells";
  const std::vector<std::pair<const char*, std::vector<std::pair<std::uint64_t, std::uint64_t>>>>
      rows = {{"maxwork", {{40, 300}, {42, 160}, {44, 90}, {200, 80}, {400, 70}}},
              {"celltree", {{30, 280}, {33, 150}, {36, 85}, {180, 78}, {380, 69}}},
              {"balanced", {{28, 270}, {31, 145}, {35, 84}, {50, 60}, {120, 40}}}};
  for (const auto& [name, values] : rows) {
    const std::vector<std::uint32_t> counts = {1, 2, 4, 8, 16};
    for (std::size_t i = 0; i < counts.size(); ++i) {
      ProcessorsReplay r;
      r.scheduler = &SchedulerByName(name, "test");
      r.processors = counts[i];
      r.total.fetches = values[i].first;
      r.total.time = SimTime::Milliseconds(values[i].second);
      r.total.time_bound = SimTime::Picoseconds(96000000000 / counts[i]);
      if (differ && counts[i] == 16 && std::string(name) == "balanced") {
        r.total.time_bound = SimTime::Milliseconds(5);
      }
      r.total.work = SimTime::Picoseconds(123), r.total.stall = SimTime::Picoseconds(45);
      r.total.idle = SimTime::Picoseconds(6);
      r.total.utilisation = 0.5;
      g.processors.push_back(r);
    }
  }
  return g;
}

TEST(Study, TheProcessorsSectionPrintsTheBoundOnceAndComparesAtEight) {
  const std::string same = ProcessorsReport(HandMadeProcessors(false));
  EXPECT_EQ(same.rfind("## Several processors (3x3x3 cells)\n\n", 0), 0u) << same;
  // 1 processor: the fastest is balanced, 270 ms over a bound of 96 ms.
  EXPECT_NE(same.find("| 1 | 40 | 30 | 28 | 300.0 | 280.0 | 270.0 | 0.50 | 0.50 | 0.50 | 96.0 | "
                      "2.81 (`balanced`) |\n"),
            std::string::npos)
      << same;
  EXPECT_NE(same.find("| 16 | 400 | 380 | 120 | 70.0 | 69.0 | 40.0 | 0.50 | 0.50 | 0.50 | 6.0 | "
                      "6.67 (`balanced`) |\n"),
            std::string::npos)
      << same;
  // At 8: 50 fetches against 200 is 75% fewer; 60 ms against 80 is 25% less.
  EXPECT_NE(same.find("At 8 processors `balanced` fetches 75.0% fewer cells than Max Work (50 "
                      "against 200) and takes 25.0% less time (60.0 against 80.0 ms)."),
            std::string::npos)
      << same;
  EXPECT_NE(same.find("![time and fetches against processors](processors.png)"), std::string::npos);
  EXPECT_EQ(same.find("bounds differ"), std::string::npos) << same;
  // Bounds that differ are each printed; the fastest's time is over its own bound (40 / 5).
  const std::string differ = ProcessorsReport(HandMadeProcessors(true));
  EXPECT_NE(differ.find("| 6.0 / 6.0 / 5.0 | 8.00 (`balanced`) |\n"), std::string::npos) << differ;
  EXPECT_NE(differ.find("bounds differ"), std::string::npos) << differ;
  const std::string csv = ProcessorsCsv(HandMadeProcessors(false));
  EXPECT_EQ(csv.rfind("scheduler,processors,fetches,time_ps,time_bound_ps,work_ps,stall_ps,"
                      "idle_ps,utilisation\nmaxwork,1,40,300000000000,96000000000,123,45,6,0.5000\n"
                      "maxwork,2,42,160000000000,48000000000,123,45,6,0.5000\n",
                      0),
            0u)
      << csv;
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 16) << csv;
}

TEST(Study, AStillCameraIsSaidSo) {
  StudyResult r;
  r.options.orbit = 0;
  r.options.orbit_given = true;
  r.options.res = "16x16";
  r.frame_numbers = {0, 1, 2, 3};
  EXPECT_NE(StudyReport(r).find("Scene `builtin`, 4 frames with a still camera, 16x16. "),
            std::string::npos)
      << StudyReport(r);
  r.options.orbit = 45;
  EXPECT_NE(StudyReport(r).find("Scene `builtin`, 4 frames orbiting 45 degrees, 16x16. "),
            std::string::npos)
      << StudyReport(r);
}

TEST(Study, AccuracyCsvIsWhatPythonsCsvWrites) {
  AccuracyRow r{"replay granularity", "node",  0.05001592899998286,
                0.6370030497380503,   1.5e-05, "simulated time, relative",
                -0.12202380952380952, true};
  EXPECT_EQ(AccuracyCsv({r}),
            "knob,value,seconds,time_ratio,error,error_kind,fetch_change,default\r\n"
            "replay granularity,node,0.05001592899998286,0.6370030497380503,1.5e-05,"
            "\"simulated time, relative\",-0.12202380952380952,True\r\n");
  EXPECT_EQ(AccuracyTable({r}),
            "| knob | value | time (ratio to most accurate) | error | fetch change | default |\n"
            "|---|---:|---:|---:|---:|---|\n"
            "| replay granularity | node | 0.05 s (0.64) | 0.0000 (simulated time, relative) | "
            "-12.2% | yes |\n");
}

// Expected values: numpy 1.24 (np.add.reduce, and the RMSE as the study's Python computed it).
TEST(ImageError, SumsAsNumpyDoes) {
  const auto values = [](std::size_t n) {
    std::vector<double> v(n);
    for (std::size_t i = 0; i < n; ++i) v[i] = 1.0 / double(i + 1) + double(i % 7) * 0.1;
    return v;
  };
  EXPECT_EQ(NumpySum(values(5).data(), 5), 3.2833333333333337);
  EXPECT_EQ(NumpySum(values(100).data(), 100), 34.687377517639625);  // pairwise, not in turn
  EXPECT_EQ(NumpySum(values(1000).data(), 1000), 307.18547086055037);
  EXPECT_EQ(NumpySum(values(8193).data(), 8193), 2466.8883121015087);
  EXPECT_EQ(NumpySum(values(20000).data(), 20000), 6010.18072821723);  // in blocks of 8192
  EXPECT_EQ(NumpyMean(values(30000)), 0.30034620616640406);
}

TEST(ImageError, RmseAsMatplotlibAndNumpyGiveIt) {
  // 64x48 frames of values from a linear congruential generator (9216 values a frame: more
  // than a block of numpy's sums).
  const auto image = [](std::uint64_t x) {
    Rgb8Image im{64, 48, std::vector<std::uint8_t>(64 * 48 * 3)};
    for (std::uint8_t& v : im.rgb) {
      x = (x * 1103515245 + 12345) % (std::uint64_t{1} << 31);
      v = std::uint8_t((x >> 16) & 255);
    }
    return im;
  };
  const std::vector<Rgb8Image> a = {image(1), image(2)}, b = {image(3), image(4)};
  EXPECT_EQ(ImageRmse(a, b), 0.40905463566980016);
  EXPECT_EQ(ImageRmse(a, a), 0.0);
  EXPECT_NE(testing::ErrorOf([&] { ImageRmse(a, {b[0]}); }), "");
}

}  // namespace
}  // namespace raycell
