#include "study/study.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <sstream>

#include "base/check.h"
#include "base/format.h"
#include "base/parallel.h"
#include "base/parse.h"
#include "base/progress.h"
#include "record/cell_grid.h"
#include "record/record_flags.h"
#include "record/recorder.h"
#include "record/scene.h"
#include "replay/config.h"
#include "replay/replayer.h"
#include "scheduling/balanced_scheduler.h"
#include "scheduling/cell_tree_scheduler.h"
#include "scheduling/max_work.h"
#include "study/suite.h"
#include "traces/cell_dims.h"
#include "traces/format.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

namespace fs = std::filesystem;

constexpr int kMinFrames = 2, kMaxFrames = 10000;

// "N": frames 0..N-1 (an orbit of one volume); "A..B" (or "A-B"): frames A to B, as record
// reads them, which a sequence pattern needs (its files are numbered). Cell Tree scheduling
// follows frame i's tree in frame i+1, so a study needs at least two frames.
std::vector<int> StudyFrames(const StudyOptions& a) {
  const bool count =
      !a.frames.empty() && a.frames.find_first_not_of("0123456789") == std::string::npos;
  if (count && a.sequence()) {
    throw InputError("--frames '" + a.frames + "': --scene '" + a.scene +
                     "' is a sequence pattern: give the frame numbers of its files, A..B");
  }
  if (count) {
    const auto n = ParseInt(a.frames, "--frames (a count of frames)", kMinFrames, kMaxFrames);
    return ParseFrameRange("0.." + std::to_string(n - 1));
  }
  const std::vector<int> frames = ParseFrameRange(a.frames);
  if (frames.size() < std::size_t{kMinFrames} || frames.size() > std::size_t{kMaxFrames}) {
    throw InputError("--frames '" + a.frames + "': a study needs " + std::to_string(kMinFrames) +
                     " to " + std::to_string(kMaxFrames) + " frames");
  }
  return frames;
}

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    ParseCellDims(item);  // validates, InputError naming the text
    out.push_back(item);
  }
  if (out.empty()) throw InputError("--cells '" + text + "': expected e.g. 2x2x2,3x3x3");
  return out;
}

TraceReader RecordGrid(const StudyOptions& a, const std::vector<int>& frames,
                       const std::string& cells) {
  // As `raycell record` with these flags records it (RecordFlags): a scene file's camera,
  // lights and materials hold, its path turned by the study's orbit over the frames.
  RecordFlags flags;
  flags.opt.scene.source = a.scene;
  flags.frames = FormatFrameRange(frames.front(), frames.back());
  flags.orbit = FormatReal(a.orbit_degrees());
  flags.cells = cells;
  flags.res = a.res;
  flags.opt.out = (fs::path(a.out) / ("capture_" + cells + ".rct")).string();
  flags.opt.images_dir = (fs::path(a.out) / ("images_" + cells)).string();
  flags.opt.threads = a.threads;
  flags.quiet = a.quiet;
  const RecordOptions o = ToRecordOptions(flags);
  std::ostringstream log;
  const RecordSummary s = Record(o, log);
  std::cerr << "recorded " << s.frames << " frames in " << cells << " cells (" << s.rays
            << " rays) in " << FormatFixed(s.seconds, 1) << " s\n";
  return TraceReader::Open(o.out);
}

std::string Dims(const TraceHeader& h) {
  return std::to_string(h.cells[0]) + "x" + std::to_string(h.cells[1]) + "x" +
         std::to_string(h.cells[2]);
}

// The threads the study's parallel work runs on: the machine's, at most 8.
unsigned StudyThreads() { return std::min(HardwareThreads(), 8u); }

// Brackets the optimum of every tree (AnalyzeTree with --bracket), frames in parallel on the
// study's threads; each frame's result depends only on its tree, so on no thread count.
std::vector<FrameAnalysis> AnalyzeTrees(const std::vector<CellTree>& trees,
                                        const AnalyzeOptions& options, const std::string& label,
                                        bool quiet) {
  std::vector<FrameAnalysis> out(trees.size());
  std::size_t done = 0;
  std::mutex mutex;
  Progress progress(!quiet);
  ParallelFor(trees.size(), StudyThreads(), [&](std::size_t i) {
    out[i] = AnalyzeTree(trees[i], options);
    std::lock_guard<std::mutex> lock(mutex);
    ++done;
    progress.Update(double(done) / double(trees.size()),
                    label + ": bracketing the optimum, " + std::to_string(done) + "/" +
                        std::to_string(trees.size()) + " frames");
  });
  progress.Done();
  return out;
}

// InputError naming `what` (the finest grid's option) when the several processors section's
// largest board on `cells` cells is beyond the memory model's limit (CheckModelSize), before
// any work.
void CheckProcessorsFit(const std::string& what, std::uint64_t cells, std::uint32_t processors) {
  ReplayConfig config = DefaultConfig();
  config.processors.count = processors;
  try {
    CheckModelSize(config, cells);
  } catch (const InputError& e) {
    throw InputError(what + ": too many cells for the several processors section: " + e.what());
  }
}

// Replays every frame under each ProcessorsSchedulers() entry on boards of each
// StudyProcessorCounts() size, the default configuration otherwise, in one pass over the
// frames with the configurations on the study's threads (the totals do not depend on them).
std::vector<ProcessorsReplay> StudyProcessors(const TraceReader& reader, const std::string& label,
                                              const std::vector<std::uint32_t>& counts,
                                              bool quiet) {
  std::vector<ProcessorsReplay> rows;
  std::vector<ReplayConfig> configs;
  for (const SchedulerEntry* s : ProcessorsSchedulers()) {
    for (const std::uint32_t p : counts) {
      ReplayConfig config = DefaultConfig();
      config.scheduler = s;
      config.processors.count = p;
      configs.push_back(config);
      rows.push_back({s, p, {}});
    }
  }
  std::vector<std::size_t> all(reader.frames().size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
  Progress progress(!quiet);
  ReplayFramesOptions options;
  options.jobs = StudyThreads();
  ReplayFrames(reader, all, configs, options,
               [&](const LoadedFrame& frame, const std::vector<ReplayResult>& results) {
                 progress.Update(double(frame.position + 1) / double(all.size()),
                                 label + ": several processors, replayed frame " +
                                     std::to_string(frame.position + 1) + "/" +
                                     std::to_string(all.size()));
                 for (std::size_t k = 0; k < results.size(); ++k) {
                   Accumulate(results[k], &rows[k].total);
                 }
                 return true;
               });
  progress.Done();
  for (ProcessorsReplay& r : rows) FinishTotal(r.processors, &r.total);
  return rows;
}

// Replays the capture under each scheduler in one pass over the frames (ReplayFrames: each
// frame decoded and its tree built once), keeping the trees; then brackets every tree's
// optimum with the study's budget. On the finest grid, then replays several processors.
GridStudy StudyTrace(const TraceReader& reader, GridStudy g, const StudyOptions& a, bool finest) {
  std::vector<std::size_t> all;
  const std::size_t n = reader.frames().size();
  for (std::size_t i = 0; i < n; ++i) all.push_back(i);
  std::vector<ReplayConfig> configs;
  for (const SchedulerEntry* s : StudySchedulers()) {
    ReplayConfig config = DefaultConfig();
    config.scheduler = s;
    config.granularity = ReplayConfig::Granularity::kNode;  // exact with a one-cell cache
    configs.push_back(config);
  }
  std::vector<CellTree> trees;
  std::vector<std::int32_t> numbers;
  {
    Progress progress(!a.quiet);
    std::vector<TraceReplay> replays(configs.size());
    ReplayFrames(reader, all, configs, {},
                 [&](const LoadedFrame& frame, const std::vector<ReplayResult>& results) {
                   progress.Update(double(frame.position + 1) / n,
                                   g.cells + ": replayed frame " +
                                       std::to_string(frame.position + 1) + "/" +
                                       std::to_string(n));
                   trees.push_back(*frame.tree);
                   if (trees.back().parked()) trees.back().Unpark();
                   numbers.push_back(frame.number);
                   for (std::size_t k = 0; k < results.size(); ++k) {
                     Accumulate(results[k], &replays[k].total);
                     replays[k].frames.push_back(results[k]);
                   }
                   return true;
                 });
    for (std::size_t k = 0; k < configs.size(); ++k) {
      FinishTotal(configs[k].processors.count, &replays[k].total);
      g.replays.push_back({configs[k].scheduler, std::move(replays[k])});
    }
  }
  AnalyzeOptions options;
  options.bracket = true;
  options.bracket_options = BracketEffort(a.effort);
  options.bracket_options.lower.grid = reader.header().cells;
  options.bracket_options.best.threads = 1;  // the frames run in parallel instead
  options.bracket_options.overlap = false;
  g.trees = AnalyzeTrees(trees, options, g.cells, a.quiet);
  for (std::size_t i = 0; i < n; ++i) g.trees[i].frame = numbers[i];
  if (finest) {
    g.processors = StudyProcessors(reader, g.cells, ParseProcessorCounts(a.processors), a.quiet);
  }
  return g;
}

GridStudy StudyGrid(const StudyOptions& a, const std::vector<int>& frames, const std::string& cells,
                    bool finest) {
  const TraceReader reader = RecordGrid(a, frames, cells);
  GridStudy g;
  g.cells = cells;
  g.heading = cells + " cells";
  g.capture = "capture_" + cells + ".rct";
  g.images = "images_" + cells + "/";
  return StudyTrace(reader, std::move(g), a, finest);
}

std::string Stem(const std::string& path) { return fs::path(path).stem().string(); }

// The given traces, opened and checked before any work: readable, with frames, and with
// file stems (their labels) that differ, as their CSVs and plots would collide.
std::vector<TraceReader> OpenGivenTraces(const StudyOptions& a) {
  std::vector<TraceReader> readers;
  for (std::size_t i = 0; i < a.traces.size(); ++i) {
    const std::string& path = a.traces[i];
    for (std::size_t j = 0; j < i; ++j) {
      if (Stem(a.traces[j]) == Stem(path)) {
        throw InputError("--trace '" + path + "': another trace is also named '" + Stem(path) +
                         "' (their CSVs and plots would collide)");
      }
    }
    readers.push_back(TraceReader::Open(path));
    if (readers.back().frames().empty()) throw InputError("--trace '" + path + "': no frames");
  }
  return readers;
}

// The given traces, each labelled by its file stem; the last is the finest grid.
std::vector<GridStudy> StudyGivenTraces(const StudyOptions& a,
                                        const std::vector<TraceReader>& readers) {
  std::vector<GridStudy> grids;
  for (std::size_t i = 0; i < readers.size(); ++i) {
    const std::string& path = a.traces[i];
    const TraceReader& reader = readers[i];
    std::cerr << "reusing " << path << ": " << reader.frames().size() << " frames in "
              << Dims(reader.header()) << " cells\n";
    GridStudy g;
    g.cells = Stem(path);
    g.heading = "`" + path + "` (" + Dims(reader.header()) + " cells)";
    g.capture = path;
    grids.push_back(StudyTrace(reader, std::move(g), a, i + 1 == readers.size()));
  }
  return grids;
}

}  // namespace

bool StudyOptions::sequence() const { return IsSequencePattern(scene); }

std::vector<const SchedulerEntry*> StudySchedulers() {
  std::vector<const SchedulerEntry*> out;
  for (const bool oracle : {false, true}) {
    for (const SchedulerEntry& e : SchedulerRegistry()) {
      if (e.studied && e.oracle == oracle) out.push_back(&e);
    }
  }
  return out;
}

std::vector<const SchedulerEntry*> ProcessorsSchedulers() {
  return {&kMaxWorkEntry, &kCellTreeEntry, &kBalancedEntry};
}

const std::vector<std::uint32_t>& StudyProcessorCounts() {
  static const std::vector<std::uint32_t> counts = {1, 2, 4, 8, 16};
  return counts;
}

std::vector<std::uint32_t> ParseProcessorCounts(const std::string& list) {
  std::vector<std::uint32_t> counts;
  std::stringstream in(list);
  for (std::string item; std::getline(in, item, ',');) {
    counts.push_back(
        static_cast<std::uint32_t>(ParseUint(item, "--processors '" + list + "'", 1, 64)));
    if (counts.size() > 1 && counts.back() <= counts[counts.size() - 2]) {
      throw InputError("--processors '" + list + "': the board sizes must ascend");
    }
  }
  if (counts.empty()) throw InputError("--processors: no board size given");
  return counts;
}

const TraceReplay& GridStudy::replay(const SchedulerEntry& scheduler) const {
  for (const SchedulerReplay& r : replays) {
    if (r.scheduler == &scheduler) return r.replay;
  }
  RAYCELL_CHECK(false && "scheduler not studied");
  return replays.front().replay;
}

StudyResult RunStudy(const StudyOptions& a) {
  StudyResult result;
  result.options = a;
  if (a.traces.empty()) result.frame_numbers = StudyFrames(a);
  if (a.accuracy_frames < 0 || a.accuracy_frames > 1000) {
    throw InputError("--accuracy-frames: must be in 0..1000");
  }
  if (a.scale_frames < 0 || a.scale_frames > 1000) {
    throw InputError("--scale-frames: must be in 0..1000");
  }
  if (a.subdivision_frames < 0 || a.subdivision_frames > 1000) {
    throw InputError("--subdivision-frames: must be in 0..1000");
  }
  const auto fine = ParseCellDims(a.subdivision_fine);
  if (fine[0] % 3 || fine[1] % 3 || fine[2] % 3) {
    throw InputError("--subdivision-fine '" + a.subdivision_fine + "': each count must be a " +
                     "multiple of 3, so that the uniform 3x3x3 grid is made of its cells");
  }
  ParseResolution(a.accuracy_res);  // InputError naming it, before any work
  const std::vector<std::uint32_t> processors = ParseProcessorCounts(a.processors);
  BracketEffort(a.effort);  // likewise
  if (!std::isfinite(a.orbit_degrees())) {
    throw InputError("--orbit: must be a finite number of degrees");
  }
  AccuracyOptions accuracy;
  accuracy.res = a.accuracy_res;
  accuracy.frames = a.accuracy_frames;
  accuracy.out = (fs::path(a.out) / "accuracy").string();
  accuracy.quiet = a.quiet;
  if (a.traces.empty()) {
    // A sequence's knobs are measured on the volume of its first frame.
    accuracy.scene = a.sequence() ? FrameFile(a.scene, result.frame_numbers.front()) : a.scene;
    const std::vector<std::string> cells = SplitList(a.cells);
    CheckProcessorsFit("--cells '" + cells.back() + "'",
                       TraceCellCount(ParseCellDims(cells.back())), processors.back());
    fs::create_directories(a.out);
    for (std::size_t i = 0; i < cells.size(); ++i) {
      result.grids.push_back(StudyGrid(a, result.frame_numbers, cells[i], i + 1 == cells.size()));
    }
  } else {
    const std::vector<TraceReader> readers = OpenGivenTraces(a);
    CheckProcessorsFit("--trace '" + a.traces.back() + "'", readers.back().header().cell_count(),
                       processors.back());
    fs::create_directories(a.out);
    result.grids = StudyGivenTraces(a, readers);
    accuracy.scene = readers.front().header().scene;
  }
  result.accuracy.options = accuracy;
  try {
    SuiteOptions suite;
    const std::vector<SuiteSceneResult> scenes = ReadSuiteResults(a.suite, &suite);
    result.suite_scenes = scenes.size();
    // The scene's name as the suite names it: a file's stem ("builtin" for the built-in one).
    const std::string name = fs::path(accuracy.scene).stem().string();
    if (!scenes.empty()) result.suite_headlines = SuiteHeadlines(suite, scenes, name);
  } catch (const InputError& e) {
    result.suite_error = e.what();
  }
  if (a.accuracy_frames > 0) result.accuracy = MeasureAccuracy(accuracy);
  result.depth = MeasureDepth(result.accuracy);
  SubdivisionOptions sub;
  sub.scene = accuracy.scene;  // a sequence's first volume, or the first given trace's scene
  sub.res = a.accuracy_res;
  sub.frames = a.subdivision_frames;
  sub.fine = a.subdivision_fine;
  sub.out = (fs::path(a.out) / "subdivisions").string();
  sub.quiet = a.quiet;
  result.subdivisions = MeasureSubdivisions(sub);
  ScaleOptions scale;
  scale.scene = accuracy.scene;
  scale.binary = a.traces.empty() ? a.binary : "";
  scale.out = (fs::path(a.out) / "scale").string();
  scale.frames = a.scale_frames;
  if (!a.quiet && !scale.binary.empty() && scale.frames > 0) {
    std::cerr << "scale: record, analyze and replay at "
              << scale.res.size() + scale.cells.size() - 1 << " small points\n";
  }
  result.scale = MeasureScale(scale);
  if (!a.traces.empty()) result.scale.not_measured = "the study was given captures (--trace)";
  return result;
}

}  // namespace raycell
