// raycell study: the main job end to end. Records a scene for each cell grid, analyses every
// frame's Cell Tree, replays the capture under Max Work, Cell Tree scheduling and the Peel
// oracle, and writes a report with its tables, their CSVs, the frame images and plots.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <thread>

#include "analysis/analysis.h"
#include "base/check.h"
#include "base/file.h"
#include "base/format.h"
#include "base/parse.h"
#include "base/progress.h"
#include "replay/config.h"
#include "replay/driver.h"
#include "scheduling/scheduler.h"
#include "tools/commands.h"
#include "traces/record/cell_grid.h"
#include "traces/record/recorder.h"
#include "traces/record/scene.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

namespace fs = std::filesystem;

struct StudyArgs {
  std::string scene = "builtin", cells = "2x2x2,3x3x3", res = "256x256", out = "study";
  std::string accuracy_res = "128x128";
  std::string frames = "24";        // a count N (frames 0..N-1) or frame numbers A..B
  std::vector<int> frame_numbers;   // what `frames` says, set by Run
  int accuracy_frames = 2;          // 0: no run time against error section
  std::vector<std::string> traces;  // reused captures instead of recording
  std::string effort = "quick";     // the bracket's budget (BracketEffort)
  // Degrees the camera turns over the frames. Default: 90 for one volume (3.75 degrees per
  // frame over 24: consecutive frames alike, as in an animation), 0 for a sequence, whose
  // volumes are the animation.
  double orbit = 90;
  bool orbit_given = false;
  int threads = 0;
  bool quiet = false;
  bool sequence() const { return IsSequencePattern(scene); }
  double orbit_degrees() const { return orbit_given || !sequence() ? orbit : 0; }
};

constexpr int kMinFrames = 2, kMaxFrames = 10000;

// "N": frames 0..N-1 (an orbit of one volume); "A..B" (or "A-B"): frames A to B, as record
// reads them, which a sequence pattern needs (its files are numbered). Cell Tree scheduling
// follows frame i's tree in frame i+1, so a study needs at least two frames.
std::vector<int> StudyFrames(const StudyArgs& a) {
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

// The schedulers the study replays, in the report's order: the registry's studied ones,
// online first (they plan frame i+1 from what frame i showed, as hardware could), then the
// oracles (they know the frame itself).
std::vector<const SchedulerEntry*> StudySchedulers() {
  std::vector<const SchedulerEntry*> out;
  for (const bool oracle : {false, true}) {
    for (const SchedulerEntry& e : SchedulerRegistry()) {
      if (e.studied && e.oracle == oracle) out.push_back(&e);
    }
  }
  return out;
}

// The results for one cell grid (recorded) or one given trace.
struct GridStudy {
  std::string cells;  // the label in file names: "3x3x3", or the given trace's file stem
  std::string heading, capture, images;  // images: empty for a given trace
  std::vector<FrameAnalysis> trees{};
  std::map<std::string, TraceReplay> replays{};  // by scheduler name

  const TraceReplay& replay(const std::string& scheduler) const { return replays.at(scheduler); }
};

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

TraceReader RecordGrid(const StudyArgs& a, const std::string& cells) {
  RecordOptions o;
  o.scene.source = a.scene;
  o.frames = a.frame_numbers;
  o.camera.orbit_degrees = a.orbit_degrees();
  o.cells = ParseCellDims(cells);
  const auto wh = ParseResolution(a.res);
  o.settings.width = wh[0], o.settings.height = wh[1];
  o.out = (fs::path(a.out) / ("capture_" + cells + ".rct")).string();
  o.images_dir = (fs::path(a.out) / ("images_" + cells)).string();
  o.threads = a.threads;
  o.progress = !a.quiet;
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

// Brackets the optimum of every tree (AnalyzeTree with --bracket), frames in parallel on the
// machine's threads; each frame's result depends only on its tree, so on no thread count.
std::vector<FrameAnalysis> AnalyzeTrees(const std::vector<CellTree>& trees,
                                        const AnalyzeOptions& options, const std::string& label,
                                        bool quiet) {
  std::vector<FrameAnalysis> out(trees.size());
  std::atomic<std::size_t> next{0}, done{0};
  std::mutex mutex;
  Progress progress(!quiet);
  const auto work = [&] {
    for (std::size_t i; (i = next++) < trees.size();) {
      out[i] = AnalyzeTree(trees[i], options);
      std::lock_guard<std::mutex> lock(mutex);
      progress.Update(double(++done) / double(trees.size()),
                      label + ": bracketing the optimum, " + std::to_string(done) + "/" +
                          std::to_string(trees.size()) + " frames");
    }
  };
  std::vector<std::thread> threads;
  const unsigned n = std::max(1u, std::min(std::thread::hardware_concurrency(), 8u));
  for (unsigned t = 1; t < n; ++t) threads.emplace_back(work);
  work();
  for (std::thread& t : threads) t.join();
  progress.Done();
  return out;
}

// Replays the capture under each scheduler in one pass over the frames (ReplayFrames: each
// frame decoded and its tree built once), keeping the trees; then brackets every tree's
// optimum with the study's budget.
GridStudy StudyTrace(const TraceReader& reader, GridStudy g, const StudyArgs& a) {
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
                   numbers.push_back(frame.number);
                   for (std::size_t k = 0; k < results.size(); ++k) {
                     Accumulate(results[k], &replays[k].total);
                     replays[k].frames.push_back(results[k]);
                   }
                   return true;
                 });
    for (std::size_t k = 0; k < configs.size(); ++k) {
      FinishTotal(configs[k].processors.count, &replays[k].total);
      g.replays[configs[k].scheduler_name()] = std::move(replays[k]);
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
  return g;
}

GridStudy StudyGrid(const StudyArgs& a, const std::string& cells) {
  const TraceReader reader = RecordGrid(a, cells);
  return StudyTrace(
      reader, {cells, cells + " cells", "capture_" + cells + ".rct", "images_" + cells + "/"}, a);
}

std::string Stem(const std::string& path) { return fs::path(path).stem().string(); }

// The given traces, opened and checked before any work: readable, with frames, and with
// file stems (their labels) that differ, as their CSVs and plots would collide.
std::vector<TraceReader> OpenGivenTraces(const StudyArgs& a) {
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

// The given traces, each labelled by its file stem.
std::vector<GridStudy> StudyGivenTraces(const StudyArgs& a,
                                        const std::vector<TraceReader>& readers) {
  std::vector<GridStudy> grids;
  for (std::size_t i = 0; i < readers.size(); ++i) {
    const std::string& path = a.traces[i];
    const TraceReader& reader = readers[i];
    std::cerr << "reusing " << path << ": " << reader.frames().size() << " frames in "
              << Dims(reader.header()) << " cells\n";
    grids.push_back(StudyTrace(
        reader, {Stem(path), "`" + path + "` (" + Dims(reader.header()) + " cells)", path, ""}, a));
  }
  return grids;
}

// Writes `text` to dir/name via a temporary file.
void WriteFile(const std::string& dir, const std::string& name, const std::string& text) {
  WriteFileAtomically((fs::path(dir) / name).string(), text);
}

std::string TreesCsv(const GridStudy& g) {
  std::ostringstream s;
  s << "frame,rays,nodes,rays_per_node,bound,peel_length,splits,optimum,lower_bound,"
       "best_length,gap\n";
  for (const FrameAnalysis& t : g.trees) {
    s << t.frame << ',' << t.rays << ',' << t.nodes << ',' << FormatFixed(t.rays_per_node(), 2)
      << ',' << t.bound << ',' << t.peel_length() << ',' << t.splits << ','
      << (t.optimum ? std::to_string(*t.optimum) : "") << ',' << *t.lower_bound << ','
      << *t.best_length << ',' << FormatFixed(*t.gap(), 4) << '\n';
  }
  return s.str();
}

// Fetches per frame of every scheduler, and the bracket of the optimum.
std::string FetchesCsv(const GridStudy& g) {
  std::ostringstream s;
  s << "frame";
  for (const SchedulerEntry* k : StudySchedulers()) s << ',' << k->name;
  s << ",bound,lower_bound,best_length\n";
  for (std::size_t i = 0; i < g.trees.size(); ++i) {
    s << g.trees[i].frame;
    for (const SchedulerEntry* k : StudySchedulers())
      s << ',' << g.replay(k->name).frames[i].fetches;
    s << ',' << g.trees[i].bound << ',' << *g.trees[i].lower_bound << ',' << *g.trees[i].best_length
      << '\n';
  }
  return s.str();
}

double Mean(const std::vector<FrameAnalysis>& t, double (*f)(const FrameAnalysis&)) {
  double sum = 0;
  for (const FrameAnalysis& x : t) sum += f(x);
  return t.empty() ? 0 : sum / double(t.size());
}

std::string Percent(double part, double whole) {
  return FormatFixed(whole != 0 ? 100.0 * part / whole : 0.0, 1) + "%";
}

std::string GridReport(const GridStudy& g) {
  std::ostringstream s;
  const auto& tr = g.trees;
  const std::uint64_t mw = g.replay("maxwork").total.fetches;
  std::uint64_t bound = 0, peel = 0, lower = 0, best = 0, proved = 0;
  for (const FrameAnalysis& t : tr) {
    bound += t.bound, peel += t.peel_length(), lower += *t.lower_bound, best += *t.best_length;
    proved += t.optimum ? 1 : 0;
  }
  s << "## " << g.heading << "\n\n"
    << "![fetches per frame](fetches_" << g.cells << ".png)\n\n"
    << "| | value |\n|---|---:|\n"
    << "| frames | " << tr.size() << " |\n"
    << "| rays per frame (mean) | "
    << FormatFixed(Mean(tr, [](const FrameAnalysis& x) { return double(x.rays); }), 0) << " |\n"
    << "| Cell Tree nodes per frame (mean) | "
    << FormatFixed(Mean(tr, [](const FrameAnalysis& x) { return double(x.nodes); }), 1) << " |\n"
    << "| rays per node (mean; the paper: about 100) | "
    << FormatFixed(Mean(tr, [](const FrameAnalysis& x) { return x.rays_per_node(); }), 1) << " |\n";
  for (const SchedulerEntry* k : StudySchedulers()) {
    s << "| fetches, " << k->label << " | " << g.replay(k->name).total.fetches << " |\n";
  }
  s << "| maxGen bound (summed) | " << bound << " |\n";
  for (const SchedulerEntry* k : StudySchedulers()) {
    if (k->oracle || std::string(k->name) == "maxwork") continue;
    const double f = double(g.replay(k->name).total.fetches);
    s << "| " << k->label << " against Max Work"
      << (std::string(k->name) == "celltree" ? " (the paper: 30% fewer)" : "") << " | "
      << Percent(f - double(mw), double(mw)) << " |\n";
  }
  s << "\nThe optimum of each frame's Cell Tree (fewest fetches with a one-cell cache) lies "
       "between the best lower bound and the best schedule found:\n\n"
    << "![bracket of the optimum](bracket_" << g.cells << ".png)\n\n"
    << "| | value |\n|---|---:|\n"
    << "| maxGen bound (summed) | " << bound << " |\n"
    << "| best lower bound (summed) | " << lower << " |\n"
    << "| best schedule found (summed) | " << best << " |\n"
    << "| Peel schedule (summed) | " << peel << " |\n"
    << "| best schedule against Peel | " << Percent(double(best) - double(peel), double(peel))
    << " |\n"
    << "| share of Peel's distance to the lower bound closed by the best schedule | "
    << Percent(double(peel) - double(best), double(peel) - double(lower)) << " |\n"
    << "| gap (best - lower) / lower, mean over frames | "
    << Percent(Mean(tr, [](const FrameAnalysis& x) { return *x.gap(); }), 1) << " |\n"
    << "| frames whose optimum was proved | " << proved << " of " << tr.size() << " |\n";
  s << "\n![Cell Tree size](cell_trees_" << g.cells << ".png)\n\n"
    << "Per frame: `cell_trees_" << g.cells
    << ".csv` (rays, nodes, bound, Peel, optimum, lower bound, best schedule, gap), `fetches_"
    << g.cells << ".csv` (fetches per scheduler, the bound and the bracket)"
    << (g.images.empty() ? "" : "; images in `" + g.images + "`") << "; the capture `" << g.capture
    << "`.\n\n";
  return s.str();
}

std::string Report(const StudyArgs& a, const std::vector<GridStudy>& grids) {
  std::ostringstream s;
  s << "# raycell study\n\n";
  if (a.traces.empty() && a.sequence()) {
    s << "Scene `" << a.scene << "` (one volume per frame), frames " << a.frame_numbers.front()
      << ".." << a.frame_numbers.back() << " orbiting " << a.orbit_degrees() << " degrees, "
      << a.res << ". ";
  } else if (a.traces.empty()) {
    s << "Scene `" << a.scene << "`, " << a.frame_numbers.size() << " frames orbiting "
      << a.orbit_degrees() << " degrees, " << a.res << ". ";
  } else {
    s << "Given captures, every frame of each. ";
  }
  s << "Replays use the default GI-Cube configuration (one block "
    << "processor with a one-cell cache; `raycell replay --print-config`), per Cell Tree "
    << "node (exact for this configuration). Online schedulers: Max Work, Cell Tree "
    << "scheduling (frame i+1 follows the Peel schedule of frame i's tree; frame 0 runs Max "
    << "Work), and the same with the best schedule found for frame i's tree, or for frames "
    << "i-1 and i together, instead of Peel's. Oracles: each frame's own Peel schedule, and "
    << "its own best schedule. Each frame's optimum is bracketed as `raycell analyze "
    << "--bracket --effort " << a.effort << "` does (lower bound: projections of the paths "
    << "on groups of cells combined by an integer program; upper: beam and local search, "
    << "exact search on small trees)"
    << (a.effort == "quick"
            ? ", with the study's small budget: `raycell study --effort default` (about ten "
              "times the work) or `raycell analyze CAPTURE --bracket` narrow it further"
            : "")
    << ". Every budget counts states, not seconds: the numbers are the same on any "
    << "machine. An oracle's replay can fetch fewer cells than its schedule is long (an "
    << "entry whose cell has no ready ray is skipped), and the best-schedule oracle replays "
    << "the plan the online schedulers make (`raycell replay --scheduler best`), whose budget "
    << "is smaller than the bracket's.\n\n";
  for (const GridStudy& g : grids) s << GridReport(g);
  return s.str();
}

std::string Python() {
  return access("/usr/bin/python3", X_OK) == 0 ? "/usr/bin/python3" : "python3";
}

// 'text' for the shell.
std::string Quote(const std::string& text) {
  std::string q = "'";
  for (char c : text) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Run time against error on a short capture of the same scene: tools/bench/accuracy.py runs
// this binary on each knob's settings; its table goes into the report, its CSV and plot
// into OUT/accuracy/. Empty when switched off.
std::string Accuracy(const StudyArgs& a, const std::string& scene) {
  if (a.accuracy_frames == 0) return "";
  try {
    SceneSpec spec;
    spec.source = scene;
    Scene::Load(spec, 0);  // a given trace's scene may live elsewhere
  } catch (const InputError& e) {
    return "## Run time against error\n\nNot measured: the scene `" + scene +
           "` cannot be loaded here (" + e.what() + ").\n";
  }
  const fs::path dir = fs::path(a.out) / "accuracy";
  const std::string cmd = "RAYCELL=" + Quote(fs::read_symlink("/proc/self/exe").string()) + " " +
                          Python() + " " + Quote(RAYCELL_SOURCE_DIR "/tools/bench/accuracy.py") +
                          " --scene " + Quote(scene) + " --res " + Quote(a.accuracy_res) +
                          " --frames " + std::to_string(a.accuracy_frames) + " --out " +
                          Quote(dir.string());
  if (!a.quiet) std::cerr << "measuring run time against error (" << cmd << ")\n";
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) throw InputError("cannot run `" + cmd + "`");
  std::string table;
  char buf[4096];
  for (std::size_t n; (n = fread(buf, 1, sizeof buf, p)) > 0;) table.append(buf, n);
  if (pclose(p) != 0 || !fs::exists(dir / "accuracy.png")) {
    throw InputError("run time against error failed: `" + cmd +
                     "` (it needs python3 with matplotlib and numpy: Debian package "
                     "python3-matplotlib, installed by tools/setup.sh)");
  }
  std::ostringstream s;
  s << "## Run time against error\n\n"
    << "The knobs that trade accuracy for speed, on " << a.accuracy_frames << " frame(s) of the "
    << "same scene at " << a.accuracy_res << " in 3x3x3 cells (`tools/bench/accuracy.py`; "
    << "times are ratios to the most accurate setting measured in the same run). Renderer "
    << "rows: image RMSE against a capture with a four times finer step, and the change in "
    << "Cell Tree scheduling's fetches. Replay rows: error in simulated time and fetches "
    << "against per-ray-segment replay without sampling.\n\n"
    << table << "\n![run time against error](accuracy/accuracy.png)\n\n"
    << "CSV: `accuracy/accuracy.csv`.\n";
  return s.str();
}

void Plot(const std::string& out, const std::vector<std::string>& cells) {
  std::string cmd =
      Python() + " " + Quote(RAYCELL_SOURCE_DIR "/tools/plot_study.py") + " " + Quote(out);
  for (const auto& c : cells) cmd += " " + Quote(c);
  if (std::system(cmd.c_str()) != 0) {
    throw InputError("plots failed: `" + cmd +
                     "` (it needs python3 with matplotlib: Debian "
                     "package python3-matplotlib, installed by tools/setup.sh)");
  }
  for (const auto& c : cells) {
    for (const char* p : {"fetches_", "cell_trees_", "bracket_"}) {
      if (!fs::exists(fs::path(out) / (p + c + ".png"))) throw InputError("plot missing: " + c);
    }
  }
}

void Run(StudyArgs& a) {
  if (a.traces.empty()) a.frame_numbers = StudyFrames(a);
  if (a.accuracy_frames < 0 || a.accuracy_frames > 1000) {
    throw InputError("--accuracy-frames: must be in 0..1000");
  }
  ParseResolution(a.accuracy_res);  // InputError naming it, before any work
  BracketEffort(a.effort);          // likewise
  if (!std::isfinite(a.orbit_degrees())) {
    throw InputError("--orbit: must be a finite number of degrees");
  }
  std::vector<GridStudy> grids;
  // A sequence's knobs are measured on the volume of its first frame.
  std::string accuracy_scene = a.sequence() ? FrameFile(a.scene, a.frame_numbers.front()) : a.scene;
  if (a.traces.empty()) {
    const std::vector<std::string> cells = SplitList(a.cells);
    fs::create_directories(a.out);
    for (const std::string& c : cells) grids.push_back(StudyGrid(a, c));
  } else {
    const std::vector<TraceReader> readers = OpenGivenTraces(a);
    fs::create_directories(a.out);
    grids = StudyGivenTraces(a, readers);
    accuracy_scene = readers.front().header().scene;
  }
  std::vector<std::string> labels;
  for (const GridStudy& g : grids) labels.push_back(g.cells);
  for (const GridStudy& g : grids) {
    WriteFile(a.out, "cell_trees_" + g.cells + ".csv", TreesCsv(g));
    WriteFile(a.out, "fetches_" + g.cells + ".csv", FetchesCsv(g));
  }
  Plot(a.out, labels);
  const std::string accuracy = Accuracy(a, accuracy_scene);
  WriteFile(a.out, "report.md", Report(a, grids) + accuracy);
  std::cout << "report: " << (fs::path(a.out) / "report.md").string() << "\n";
}

}  // namespace

void AddStudyCommand(CLI::App& app) {
  auto args = std::make_shared<StudyArgs>();
  CLI::App* cmd = app.add_subcommand(
      "study", "The main job: record, analyse and replay a scene; write a report with plots.");
  cmd->footer(
      "For each cell grid: records an orbit of the scene (trace and PNG per frame), analyses\n"
      "every frame's Cell Tree (rays per node, maxGen bound, Peel, and the optimum bracketed\n"
      "between the best lower bound and the best schedule found, as analyze --bracket with\n"
      "--effort, quick by default), replays the capture under Max Work, Cell Tree scheduling,\n"
      "the same with the best schedule of frame i or of frames i-1 and i (celltree-best,\n"
      "celltree-union), and the Peel and best-schedule oracles, and writes OUT/report.md\n"
      "with the tables, the CSV behind each, and plots of fetches, the bracket and Cell Tree\n"
      "size per frame (matplotlib).\n"
      "Then measures run time against error for the renderer's step, cutoff and precision\n"
      "and the replay's granularity and sampling on a short capture of the same scene\n"
      "(tools/bench/accuracy.py; --accuracy-frames 0 skips it).\n"
      "With no options: the built-in scene, 24 frames over 90 degrees, 2x2x2 and 3x3x3\n"
      "cells, 256x256; about two minutes on 2 cores.\n"
      "--frames N records frames 0..N-1 of one volume; --frames A..B records frames A to B,\n"
      "as record does: a sequence pattern (--scene 'fluid_%04d.vdb') needs this form, one\n"
      "file per frame, and then the camera stays still unless --orbit is given (the run\n"
      "time against error section uses the volume of its first frame).\n"
      "With --trace: no recording; every frame of each given capture is analysed and\n"
      "replayed (labelled by its file name), and the run time against error section uses\n"
      "the scene the first capture names, if it can be loaded here.\n\n"
      "Examples:\n"
      "  raycell study --scene ../shared/data/mj_smoke.vdb --frames 30 --out smoke-study\n"
      "  raycell study --scene '../shared/data/fluid_seq/fluid_data_%04d.vdb' --frames 150..155\n"
      "  raycell study --trace smoke.rct --trace fluid.rct --accuracy-frames 0");
  std::vector<CLI::Option*> recording = {
      cmd->add_option("--scene", args->scene,
                      "builtin, a .vdb file, or a printf pattern of one file per frame (see "
                      "record), e.g. fluid_data_%04d.vdb with --frames 150..155")
          ->capture_default_str(),
      cmd->add_option("--cells", args->cells, "cell grids, comma-separated")->capture_default_str(),
      cmd->add_option("--frames", args->frames,
                      "N: frames 0..N-1; A..B: frame numbers A to B (a sequence pattern's files)")
          ->capture_default_str(),
      cmd->add_option("--orbit", args->orbit,
                      "degrees the camera turns over the frames (default 90; 0 for a sequence "
                      "pattern)"),
      cmd->add_option("--res", args->res, "image size WxH")->capture_default_str()};
  CLI::Option* trace =
      cmd->add_option("--trace", args->traces,
                      "a capture to study instead of recording, repeatable (record's OUT)");
  for (CLI::Option* o : recording) trace->excludes(o);
  cmd->add_option("--out", args->out, "folder for the report, CSVs, plots, captures, images")
      ->capture_default_str();
  cmd->add_option("--threads", args->threads, "rendering threads, 0 = all cores")
      ->capture_default_str();
  cmd->add_option("--accuracy-frames", args->accuracy_frames,
                  "frames of the run time against error capture; 0 skips that section")
      ->capture_default_str();
  cmd->add_option("--accuracy-res", args->accuracy_res,
                  "image size of the run time against error capture")
      ->capture_default_str();
  cmd->add_option("--effort", args->effort,
                  "budget of the bracket of each frame's optimum: quick (the study's), default "
                  "(analyze --bracket's, about ten times the work) or thorough")
      ->capture_default_str();
  cmd->add_flag("--quiet", args->quiet, "no progress bars");
  CLI::Option* orbit = recording[3];
  cmd->callback([args, orbit] {
    args->orbit_given = orbit->count() > 0;
    Run(*args);
  });
}

}  // namespace raycell
