#include "study/report.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "base/check.h"
#include "base/file.h"
#include "base/format.h"
#include "scheduling/balanced_scheduler.h"
#include "scheduling/best_scheduler.h"
#include "scheduling/cell_tree_scheduler.h"
#include "scheduling/max_work.h"

namespace raycell {
namespace {

namespace fs = std::filesystem;

double Mean(const std::vector<FrameAnalysis>& t, double (*f)(const FrameAnalysis&)) {
  double sum = 0;
  for (const FrameAnalysis& x : t) sum += f(x);
  return t.empty() ? 0 : sum / double(t.size());
}

std::string Percent(double part, double whole) {
  return FormatFixed(whole != 0 ? 100.0 * part / whole : 0.0, 1) + "%";
}

// "+1.2%" or "-4.8%": part / whole with its sign.
std::string SignedPercent(double part, double whole) {
  char text[64];
  std::snprintf(text, sizeof text, "%+.1f%%", whole != 0 ? 100.0 * part / whole : 0.0);
  return text;
}

// The first sentence of report.md: what was recorded, or that captures were given.
std::string Scene(const StudyResult& r) {
  const StudyOptions& a = r.options;
  if (!a.traces.empty()) return "Given captures, every frame of each. ";
  std::ostringstream s;
  const std::vector<int>& frames = r.frame_numbers;
  if (a.sequence()) {
    s << "Scene `" << a.scene << "` (one volume per frame), frames " << frames.front() << ".."
      << frames.back();
  } else {
    s << "Scene `" << a.scene << "`, " << frames.size() << " frames";
  }
  if (a.orbit_degrees() == 0) {
    s << " with a still camera";
  } else {
    s << " orbiting " << a.orbit_degrees() << " degrees";
  }
  s << ", " << a.res << ". ";
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

// A plot script's path: beside the running binary (the build copies tools/plot_*.py next to
// build/tools/raycell), else in its ../share/raycell (an install: cmake --install). The report
// needs no source tree.
std::string PlotScript(const std::string& name) {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec)
    throw InputError("plots: cannot find the running binary (/proc/self/exe): " + ec.message());
  const fs::path dir = exe.parent_path();
  for (const fs::path& p : {dir / name, dir / ".." / "share" / "raycell" / name}) {
    if (fs::is_regular_file(p)) return p.lexically_normal().string();
  }
  throw InputError("plots: " + name + " is neither beside " + exe.string() + " nor in " +
                   (dir / ".." / "share" / "raycell").lexically_normal().string() +
                   " (the build copies it beside the binary; cmake --install puts it in "
                   "share/raycell)");
}

// Runs a plot script; InputError naming the command if it fails.
void RunPlot(const std::string& cmd) {
  if (std::system(cmd.c_str()) != 0) {
    throw InputError("plots failed: `" + cmd +
                     "` (it needs python3 with matplotlib: Debian "
                     "package python3-matplotlib, installed by tools/setup.sh)");
  }
}

void Plot(const std::string& out, const std::vector<std::string>& cells, bool processors,
          bool depth, bool subdivisions) {
  std::string cmd = Python() + " " + Quote(PlotScript("plot_study.py")) + " " + Quote(out);
  if (processors) cmd += " --processors";
  if (depth) cmd += " --depth";
  if (subdivisions) cmd += " --subdivisions";
  for (const auto& c : cells) cmd += " " + Quote(c);
  RunPlot(cmd);
  for (const auto& c : cells) {
    for (const char* p : {"fetches_", "cell_trees_", "bracket_"}) {
      if (!fs::exists(fs::path(out) / (p + c + ".png"))) throw InputError("plot missing: " + c);
    }
  }
  if (processors && !fs::exists(fs::path(out) / "processors.png")) {
    throw InputError("plot missing: processors");
  }
  if (depth && !fs::exists(fs::path(out) / "depth.png")) throw InputError("plot missing: depth");
  if (subdivisions && !fs::exists(fs::path(out) / "subdivisions.png")) {
    throw InputError("plot missing: subdivisions");
  }
}

// Picoseconds as milliseconds, one decimal.
std::string Ms(SimTime t) { return FormatFixed(double(t.picoseconds()) / 1e9, 1); }

// "12.3% fewer" or "4.5% more" (`less` instead of "fewer" for amounts), of `value` against
// `base`.
std::string Change(double value, double base, const char* less) {
  const double change = base != 0 ? 100.0 * (value - base) / base : 0.0;
  return FormatFixed(std::abs(change), 1) + "% " + (change <= 0 ? less : "more");
}

// The rows of `g.processors` with `p` processors, in ProcessorsSchedulers() order.
std::vector<const ProcessorsReplay*> RowsOf(const GridStudy& g, std::uint32_t p) {
  std::vector<const ProcessorsReplay*> rows;
  for (const ProcessorsReplay& r : g.processors) {
    if (r.processors == p) rows.push_back(&r);
  }
  return rows;
}

// The time bound column: one value where the schedulers' bounds agree (the bound holds for
// any scheduler; only what warm caches hold at a frame's start could tell them apart), else
// each scheduler's, in their order.
std::string BoundCell(const std::vector<const ProcessorsReplay*>& rows, bool* differ) {
  bool same = true;
  std::string each;
  for (const ProcessorsReplay* r : rows) {
    same = same && r->total.time_bound == rows.front()->total.time_bound;
    each += (each.empty() ? "" : " / ") + Ms(r->total.time_bound);
  }
  *differ = *differ || !same;
  return same ? Ms(rows.front()->total.time_bound) : each;
}

// The fastest of `rows` (the first on ties): its time over its bound, and its name.
std::string BestOverBound(const std::vector<const ProcessorsReplay*>& rows) {
  const ProcessorsReplay* best = rows.front();
  for (const ProcessorsReplay* r : rows) best = r->total.time < best->total.time ? r : best;
  const double bound = double(best->total.time_bound.picoseconds());
  return FormatFixed(bound > 0 ? double(best->total.time.picoseconds()) / bound : 0.0, 2) + " (`" +
         best->scheduler->name + "`)";
}

// "At 8 processors `balanced` fetches ... than Max Work ...", or nothing without those rows.
std::string BalancedAgainstMaxWork(const GridStudy& g, std::uint32_t p) {
  const ProcessorsReplay *mw = nullptr, *b = nullptr;
  for (const ProcessorsReplay& r : g.processors) {
    if (r.processors != p) continue;
    if (r.scheduler == &kMaxWorkEntry) mw = &r;
    if (r.scheduler == &kBalancedEntry) b = &r;
  }
  if (!mw || !b) return "";
  std::ostringstream s;
  s << "At " << p << " processors `balanced` fetches "
    << Change(double(b->total.fetches), double(mw->total.fetches), "fewer")
    << " cells than Max Work (" << b->total.fetches << " against " << mw->total.fetches
    << ") and takes "
    << Change(double(b->total.time.picoseconds()), double(mw->total.time.picoseconds()), "less")
    << " time (" << Ms(b->total.time) << " against " << Ms(mw->total.time) << " ms).\n\n";
  return s.str();
}

// Writes `text` to dir/name via a temporary file.
void WriteFile(const std::string& dir, const std::string& name, const std::string& text) {
  WriteFileAtomically((fs::path(dir) / name).string(), text);
}

}  // namespace

void RunPlotScript(const std::string& name, const std::vector<std::string>& args) {
  std::string cmd = Python() + " " + Quote(PlotScript(name));
  for (const std::string& a : args) cmd += " " + Quote(a);
  RunPlot(cmd);
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

std::string FetchesCsv(const GridStudy& g) {
  std::ostringstream s;
  s << "frame";
  for (const SchedulerReplay& r : g.replays) s << ',' << r.scheduler->name;
  s << ",bound,lower_bound,best_length\n";
  for (std::size_t i = 0; i < g.trees.size(); ++i) {
    s << g.trees[i].frame;
    for (const SchedulerReplay& r : g.replays) s << ',' << r.replay.frames[i].fetches;
    s << ',' << g.trees[i].bound << ',' << *g.trees[i].lower_bound << ',' << *g.trees[i].best_length
      << '\n';
  }
  return s.str();
}

std::string GridReport(const GridStudy& g) {
  std::ostringstream s;
  const auto& tr = g.trees;
  const std::uint64_t mw = g.replay(kMaxWorkEntry).total.fetches;
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
  for (const SchedulerReplay& r : g.replays) {
    s << "| fetches, " << r.scheduler->label << " | " << r.replay.total.fetches << " |\n";
  }
  s << "| maxGen bound (summed) | " << bound << " |\n";
  for (const SchedulerReplay& r : g.replays) {
    const SchedulerEntry& k = *r.scheduler;
    if (k.oracle || &k == &kMaxWorkEntry) continue;
    const double f = double(r.replay.total.fetches);
    s << "| " << k.label << " against Max Work"
      << (&k == &kCellTreeEntry ? " (the paper: 30% fewer)" : "") << " | "
      << Percent(f - double(mw), double(mw)) << " |\n";
  }
  // Online against the oracle (issue 24): the fewest fetches of a scheduler that knows only
  // earlier frames (Max Work included), over those of the frame's own best schedule.
  const SchedulerReplay* online = nullptr;
  const SchedulerReplay* oracle = nullptr;
  for (const SchedulerReplay& r : g.replays) {
    if (!r.scheduler->oracle) {
      if (online == nullptr || r.replay.total.fetches < online->replay.total.fetches) online = &r;
    } else if (r.scheduler == &kBestEntry) {
      oracle = &r;
    }
  }
  if (online != nullptr && oracle != nullptr && oracle->replay.total.fetches > 0) {
    s << "| online / oracle: " << online->scheduler->label << " against the best-schedule oracle | "
      << FormatFixed(double(online->replay.total.fetches) / double(oracle->replay.total.fetches), 2)
      << " |\n";
  }
  // Nothing to close when Peel already meets the lower bound.
  const std::string closed =
      peel == lower ? "-" : Percent(double(peel) - double(best), double(peel) - double(lower));
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
    << "| share of Peel's distance to the lower bound closed by the best schedule | " << closed
    << " |\n"
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

std::string ProcessorsCsv(const GridStudy& g) {
  std::ostringstream s;
  s << "scheduler,processors,fetches,time_ps,time_bound_ps,work_ps,stall_ps,idle_ps,"
       "utilisation\n";
  for (const ProcessorsReplay& r : g.processors) {
    const ReplayResult& t = r.total;
    s << r.scheduler->name << ',' << r.processors << ',' << t.fetches << ',' << t.time.picoseconds()
      << ',' << t.time_bound.picoseconds() << ',' << t.work.picoseconds() << ','
      << t.stall.picoseconds() << ',' << t.idle.picoseconds() << ','
      << FormatFixed(t.utilisation, 4) << '\n';
  }
  return s.str();
}

std::string ProcessorsReport(const GridStudy& g) {
  if (g.processors.empty()) return "";
  const std::vector<const SchedulerEntry*> schedulers = ProcessorsSchedulers();
  std::ostringstream s;
  s << "## Several processors (" << g.heading << ")\n\n"
    << "The capture replayed on boards of " << g.processors.front().processors << " to "
    << g.processors.back().processors
    << " block processors, the default configuration otherwise: memory warm across frames "
       "(the board's and the caches), a one-cell cache per processor, replayed per Cell Tree "
       "node with one processor and per ray segment beyond (granularity auto, exact either "
       "way). Max Work (`maxwork`) and Cell Tree scheduling (`celltree`) against `balanced`, "
       "the scheduler for several processors (docs/design.md §5 \"Load balancing\"): "
       "celltree-best's plan shared by the processors, the cached cell first, "
       "joining busy cells when no free one is ready and at least 3 fetches of work wait there "
       "(processors sharing a cell share out its rays), and postponing small batches on boards "
       "of 8 processors or more. Released work goes first to a waiting processor that holds its "
       "cell (docs/design.md §2). Fetches into the "
       "processors' caches and simulated time are summed over the frames; utilisation is the "
       "share of the processors' time spent working. The time bound holds for any scheduler "
       "(the work over the processors, the busiest link's least transfers, the longest chain of "
       "dependent work, and the work with the caches' least fetches over the processors; "
       "`time_bound_ps` in docs/schemas.md): time / bound is how far the fastest of the three "
       "is from what no scheduler can beat.\n\n"
    << "| processors |";
  for (const char* what : {"fetches", "time ms", "utilisation"}) {
    for (const SchedulerEntry* e : schedulers) s << ' ' << what << ", `" << e->name << "` |";
  }
  s << " time bound ms | fastest time / bound |\n|---:|";
  for (std::size_t i = 0; i < 3 * schedulers.size() + 2; ++i) s << "---:|";
  s << '\n';
  bool differ = false;
  for (std::size_t i = 0; i < g.processors.size(); ++i) {
    const std::uint32_t p = g.processors[i].processors;
    if (i > 0 && g.processors[i - 1].processors >= p) break;  // the next scheduler's rows
    const std::vector<const ProcessorsReplay*> rows = RowsOf(g, p);
    if (rows.empty()) continue;
    s << "| " << p << " |";
    for (const ProcessorsReplay* r : rows) s << ' ' << r->total.fetches << " |";
    for (const ProcessorsReplay* r : rows) s << ' ' << Ms(r->total.time) << " |";
    for (const ProcessorsReplay* r : rows) s << ' ' << FormatFixed(r->total.utilisation, 2) << " |";
    s << ' ' << BoundCell(rows, &differ) << " | " << BestOverBound(rows) << " |\n";
  }
  s << '\n';
  if (differ) {
    s << "Where the schedulers' time bounds differ (warm caches holding other cells when a frame "
         "starts), the column gives each, in the order of the schedulers.\n\n";
  }
  s << BalancedAgainstMaxWork(g, 8) << "![time and fetches against processors](processors.png)\n\n"
    << "`processors.csv`: per scheduler and processor count, fetches, time, time bound, work, "
       "stall and idle (summed over processors) in picoseconds, and utilisation.\n\n";
  return s.str();
}

std::string AccuracyCsv(const std::vector<AccuracyRow>& rows) {
  std::string s = "knob,value,seconds,time_ratio,error,error_kind,fetch_change,default\r\n";
  for (const AccuracyRow& r : rows) {
    s += CsvField(r.knob) + ',' + CsvField(r.value) + ',' + FormatPythonFloat(r.seconds) + ',' +
         FormatPythonFloat(r.time_ratio) + ',' + FormatPythonFloat(r.error) + ',' +
         CsvField(r.error_kind) + ',' + FormatPythonFloat(r.fetch_change) + ',' +
         (r.is_default ? "True" : "False") + "\r\n";
  }
  return s;
}

std::string AccuracyTable(const std::vector<AccuracyRow>& rows) {
  std::string s =
      "| knob | value | time (ratio to most accurate) | error | fetch change | default |\n"
      "|---|---:|---:|---:|---:|---|\n";
  for (const AccuracyRow& r : rows) {
    char change[64];
    std::snprintf(change, sizeof change, "%+.1f%%", 100 * r.fetch_change);
    s += "| " + r.knob + " | " + r.value + " | " + FormatFixed(r.seconds, 2) + " s (" +
         FormatFixed(r.time_ratio, 2) + ") | " + FormatFixed(r.error, 4) + " (" + r.error_kind +
         ") | " + change + " | " + (r.is_default ? "yes" : "") + " |\n";
  }
  return s;
}

std::string AccuracyReport(const AccuracyStudy& a) {
  if (!a.measured && a.not_measured.empty()) return "";
  if (!a.measured) return "## Run time against error\n\nNot measured: " + a.not_measured + ".\n";
  std::ostringstream s;
  s << "## Run time against error\n\n"
    << "The knobs that trade accuracy for speed, on " << a.options.frames << " frame(s) of the "
    << "same scene at " << a.options.res << " in 3x3x3 cells (`study/accuracy.h`; "
    << "times are ratios to the most accurate setting measured in the same run). Renderer "
    << "rows: image RMSE against a capture with a four times finer step, and the change in "
    << "Cell Tree scheduling's fetches. Max depth rows: the same against max depth "
    << kDeepestMaxDepth << " at the default step (record's default max depth marked). Replay "
    << "rows: error in simulated time and fetches against per-ray-segment replay without "
    << "sampling.\n\n"
    << AccuracyTable(a.rows) << "\n![run time against error](accuracy/accuracy.png)\n\n"
    << "CSV: `accuracy/accuracy.csv`.\n";
  return s.str();
}

std::string DepthCsv(const DepthStudy& d) {
  std::ostringstream s;
  s << "max_depth,default,rays,primary_rays,reflection_rays,refraction_rays,shadow_rays,nodes,"
       "fetches_maxwork,fetches_celltree,time_maxwork_ps,time_celltree_ps,rmse\n";
  for (const DepthRow& r : d.rows) {
    s << r.max_depth << ',' << (r.is_default ? 1 : 0) << ',' << r.rays;
    for (const std::uint64_t n : r.rays_by_kind) s << ',' << n;
    s << ',' << r.nodes << ',' << r.fetches_maxwork << ',' << r.fetches_celltree << ','
      << r.time_maxwork.picoseconds() << ',' << r.time_celltree.picoseconds() << ','
      << FormatPythonFloat(r.rmse) << '\n';
  }
  return s.str();
}

std::string DepthReport(const DepthStudy& d) {
  if (!d.measured && d.not_measured.empty()) return "";
  const std::string heading = "## Limited depth recursion\n\n";
  if (!d.measured) return heading + "Not measured: " + d.not_measured + ".\n";
  std::ostringstream s;
  s << heading << "The renderer's maximum depth of reflection and refraction rays (`raycell "
    << "record --max-depth`; shadow rays are cast at every depth) from 0 to "
    << d.rows.back().max_depth << ", on the run time against error section's max depth "
    << "captures (" << d.options.frames << " frame(s) of the same scene at " << d.options.res
    << " in 3x3x3 cells, the default step; no capture made again; `study/depth.h`). Summed "
    << "over the frames: rays, Cell Tree nodes, and the fetches (one-cell cache) and simulated "
    << "time of Max Work (`maxwork`) and Cell Tree scheduling (`celltree`), replayed per Cell "
    << "Tree node with the default configuration (exact with one processor); image RMSE against "
    << "max depth " << d.rows.back().max_depth << ".\n\n"
    << "| max depth | rays | spawned: reflection / refraction / shadow | Cell Tree nodes | rays "
       "per node | fetches, Max Work | fetches, Cell Tree | Cell Tree against Max Work | time "
       "ms, Max Work | time ms, Cell Tree | image RMSE vs max depth "
    << d.rows.back().max_depth << " | default |\n|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    << "---:|---:|---|\n";
  for (const DepthRow& r : d.rows) {
    const double mw = double(r.fetches_maxwork), ct = double(r.fetches_celltree);
    s << "| " << r.max_depth << " | " << r.rays << " | " << r.rays_by_kind[1] << " / "
      << r.rays_by_kind[2] << " / " << r.rays_by_kind[3] << " | " << r.nodes << " | "
      << FormatFixed(r.nodes ? double(r.rays) / double(r.nodes) : 0.0, 1) << " | "
      << r.fetches_maxwork << " | " << r.fetches_celltree << " | " << SignedPercent(ct - mw, mw)
      << " | " << FormatFixed(double(r.time_maxwork.picoseconds()) / 1e9, 2) << " | "
      << FormatFixed(double(r.time_celltree.picoseconds()) / 1e9, 2) << " | "
      << FormatFixed(r.rmse, 4) << " | " << (r.is_default ? "yes" : "") << " |\n";
  }
  s << "\n![rays, fetches, time and error against max depth](depth.png)\n\n"
    << "`depth.csv`: per max depth, rays by kind, Cell Tree nodes, each scheduler's fetches and "
       "simulated time in picoseconds, and the image RMSE; the captures in `accuracy/max-depth-N/`."
    << "\n";
  return s.str();
}

std::string SubdivisionsCsv(const SubdivisionStudy& d) {
  std::ostringstream s;
  s << "spec,scheduler,cells,footprint_min,footprint_median,footprint_max,fetches,cache_bytes,"
       "board_bytes,stall_ps,time_ps\n";
  for (const SubdivisionRow& r : d.rows) {
    s << r.spec << ',' << r.scheduler << ',' << r.cells << ',' << r.footprint_min << ','
      << r.footprint_median << ',' << r.footprint_max << ',' << r.fetches << ',' << r.cache_bytes
      << ',' << r.board_bytes << ',' << r.stall_ps << ',' << r.time_ps << '\n';
  }
  return s.str();
}

std::string SubdivisionsReport(const SubdivisionStudy& d) {
  if (!d.measured && d.not_measured.empty()) return "";
  const std::string heading = "## Subdivisions\n\n";
  if (!d.measured) return heading + "Not measured: " + d.not_measured + ".\n";
  const SubdivisionOptions& o = d.options;
  std::ostringstream s;
  s << heading << "Cells of several shapes from one capture (issue 23): `" << o.scene
    << "` recorded once on " << o.fine << " cells with `--regroupable` (" << o.frames
    << " frames of an orbit, 3.75 degrees a frame, " << o.res << "; `" << o.out
    << "/fine.rct`), replayed regrouped into each SPEC (`raycell replay fine.rct --cells "
       "SPEC`; docs/design.md §1 \"Subdivisions\") under Max Work and Cell Tree scheduling, "
       "with the on-chip cache sized in bytes to the median footprint of the uniform 3x3x3 grid, "
    << d.cache_bytes
    << " bytes, so that the cells' shapes make the difference; the default configuration "
       "otherwise. Cache bytes cross the board->cache link, board bytes PCI; changes are "
       "against 3x3x3 under the same scheduler. Footprints: of the non-empty cells (dynamic: "
       "each cell's largest over the frames).\n\n"
    << "| SPEC | scheduler | cells | footprints KiB, min / median / max | fetches | cache bytes "
       "| board bytes | stall ms |\n|---|---|---:|---:|---:|---:|---:|---:|\n";
  const auto kib = [](std::uint64_t b) { return FormatFixed(double(b) / 1024, 0); };
  const auto ms = [](std::uint64_t ps) { return FormatFixed(double(ps) / 1e9, 1); };
  for (const SubdivisionRow& r : d.rows) {
    const SubdivisionRow* base = nullptr;
    for (const SubdivisionRow& b : d.rows) {
      if (b.spec == d.rows.front().spec && b.scheduler == r.scheduler) base = &b;
    }
    const bool is_base = base == &r || base == nullptr;
    const auto change = [&](double v, double b, const char* less) {
      return is_base ? std::string() : " (" + Change(v, b, less) + ")";
    };
    s << "| " << r.spec << " | " << r.scheduler << " | " << r.cells << " | " << kib(r.footprint_min)
      << " / " << kib(r.footprint_median) << " / " << kib(r.footprint_max) << " | " << r.fetches
      << change(double(r.fetches), base ? double(base->fetches) : 0, "fewer") << " | "
      << FormatFixed(double(r.cache_bytes) / 1e6, 1) << " MB"
      << change(double(r.cache_bytes), base ? double(base->cache_bytes) : 0, "less") << " | "
      << FormatFixed(double(r.board_bytes) / 1e6, 2) << " MB"
      << change(double(r.board_bytes), base ? double(base->board_bytes) : 0, "less") << " | "
      << ms(r.stall_ps) << change(double(r.stall_ps), base ? double(base->stall_ps) : 0, "less")
      << " |\n";
  }
  s << "\n![bytes moved and fetch stall per subdivision](subdivisions.png)\n\n"
    << "`subdivisions.csv`: per SPEC and scheduler, the non-empty cells, their footprints' "
       "min, median and max, fetches, bytes into the cache and into the board, stall and "
       "simulated time in picoseconds.\n";
  return s.str();
}

std::string SuiteHeadlinesReport(const StudyResult& r) {
  std::ostringstream s;
  const std::string dir = "`" + r.options.suite + "`";
  s << "## On the suite\n\n";
  if (!r.suite_error.empty()) {
    s << "The suite's results in " << dir << " could not be read: " << r.suite_error << ".\n\n";
  } else if (r.suite_headlines.empty()) {
    s << "This study measures one scene. `raycell suite` (about five minutes) measures the "
         "recommended scheduler and subdivision (`--scheduler auto`, `--cells auto:N`) on a "
         "suite of scenes, each figure as the geometric mean over the scenes and the worst "
         "scene; no results of it in "
      << dir << " (`--suite DIR` reads another folder).\n\n";
  } else {
    s << "The recommendations on the suite, from the " << r.suite_scenes << " scenes' results of "
      << "`raycell suite` in " << dir
      << " (its report.md has every table), with this scene's own figure where it is one of "
         "them:\n";
    for (const std::string& h : r.suite_headlines) s << "- " << h << "\n";
    s << "\n";
  }
  return s.str();
}

std::string StudyReport(const StudyResult& r) {
  const StudyOptions& a = r.options;
  std::ostringstream s;
  s << "# raycell study\n\n" << Scene(r);
  s << "Replays use the default GI-Cube configuration (one block "
    << "processor with a one-cell cache; `raycell replay --print-config`), per Cell Tree "
    << "node (exact for this configuration), except in the several processors section. "
    << "Online schedulers: Max Work, Cell Tree "
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
  s << SuiteHeadlinesReport(r);
  for (const GridStudy& g : r.grids) s << GridReport(g);
  for (const GridStudy& g : r.grids) s << ProcessorsReport(g);
  const std::string accuracy = AccuracyReport(r.accuracy);
  const std::string depth = DepthReport(r.depth);
  s << accuracy << (accuracy.empty() ? "" : "\n") << depth << (depth.empty() ? "" : "\n")
    << SubdivisionsReport(r.subdivisions) << "\n"
    << ScaleReport(r.scale);
  return s.str();
}

void PlotAccuracy(const std::string& dir) {
  RunPlot(Python() + " " + Quote(PlotScript("plot_accuracy.py")) + " " + Quote(dir));
  if (!fs::exists(fs::path(dir) / "accuracy.png")) throw InputError("plot missing: accuracy");
}

std::string WriteStudyReport(const StudyResult& r) {
  const std::string& out = r.options.out;
  std::vector<std::string> labels;
  bool processors = false;
  for (const GridStudy& g : r.grids) {
    labels.push_back(g.cells);
    WriteFile(out, "cell_trees_" + g.cells + ".csv", TreesCsv(g));
    WriteFile(out, "fetches_" + g.cells + ".csv", FetchesCsv(g));
    if (g.processors.empty()) continue;
    RAYCELL_CHECK(!processors && "one grid replays several processors");
    processors = true;
    WriteFile(out, "processors.csv", ProcessorsCsv(g));
  }
  if (r.depth.measured) WriteFile(out, "depth.csv", DepthCsv(r.depth));
  if (r.subdivisions.measured) {
    WriteFile(out, "subdivisions.csv", SubdivisionsCsv(r.subdivisions));
  }
  Plot(out, labels, processors, r.depth.measured, r.subdivisions.measured);
  if (r.scale.measured) {
    WriteFile(out, "scale.csv", ScaleCsv(r.scale));
    RunPlotScript("plot_scale.py", {out});
    if (!fs::exists(fs::path(out) / "scale.png")) throw InputError("plot missing: scale");
  }
  if (r.accuracy.measured) {
    WriteFile(r.accuracy.options.out, "accuracy.csv", AccuracyCsv(r.accuracy.rows));
    PlotAccuracy(r.accuracy.options.out);
  }
  const std::string report = (fs::path(out) / "report.md").string();
  WriteFileAtomically(report, StudyReport(r));
  return report;
}

}  // namespace raycell
