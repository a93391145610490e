// raycell replay: a trace through the GI-Cube memory model under a ray scheduler.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>

#include "base/check.h"
#include "base/file.h"
#include "base/parallel.h"
#include "base/progress.h"
#include "base/table.h"
#include "replay/config.h"
#include "runner/driver.h"
#include "runner/result_table.h"
#include "runner/timeline.h"
#include "scheduling/scheduler.h"
#include "tools/commands.h"
#include "tools/frames.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

struct ReplayArgs {
  std::string trace, config, scheduler, granularity, frames, format = "table", out, timeline, cells;
  std::vector<std::string> sets;
  std::uint32_t sample = 1;
  unsigned jobs = HardwareThreads();
  std::uint64_t timeline_limit = kTimelineLimitBytes;  // hidden option, for the tests
  bool print_config = false, quiet = false;
};

// Every output below prints the result's StatsTable (runner/result_table.h).

StatsTable FrameTable(const ReplayResult& r, const ResultColumns& columns) {
  StatsTable t;
  t.AddInt("frame", r.frame);
  AddResult(r, columns, &t);
  return t;
}

void PrintJson(const TraceReplay& t, std::ostream& out) {
  out << "{\"schema\":\"raycell-replay/1\",\"frames\":[";
  for (std::size_t i = 0; i < t.frames.size(); ++i) {
    out << (i ? ",\n" : "\n");
    PrintJsonLine(FrameTable(t.frames[i], kReplayJsonColumns), out);
  }
  out << "\n],\n\"total\":";
  PrintJsonLine(ToStatsTable(t.total, kReplayJsonColumns), out);
  out << "}\n";
}

void PrintCsv(const TraceReplay& t, std::ostream& out) {
  StatsTable total;
  total.AddText("frame", "total");
  AddResult(t.total, kReplayCsvColumns, &total);
  PrintCsvHeader(total, out);
  for (const ReplayResult& r : t.frames) PrintCsvRow(FrameTable(r, kReplayCsvColumns), out);
  PrintCsvRow(total, out);
}

std::string Ms(std::uint64_t ps) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", double(ps) * 1e-9);
  return buf;
}

// How far the time is from its lower bound: "1.234", or "-" for a bound of 0 (no work).
std::string TimeOverBound(std::uint64_t time_ps, std::uint64_t bound_ps) {
  if (bound_ps == 0) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", double(time_ps) / double(bound_ps));
  return buf;
}

void TableRow(const std::string& frame, const StatsTable& t, std::ostream& out) {
  const StatValue& bound = *t.Find("bound");
  char line[512];
  std::snprintf(
      line, sizeof line, "%8s %9llu %7s %12s %13s %10s %12s %12s %12s %6.1f%% %10llu %12llu\n",
      frame.c_str(), (unsigned long long)t.Count("fetches"),
      std::holds_alternative<NoValue>(bound) ? "-" : FormatValue(bound).c_str(),
      Ms(t.Count("time_ps")).c_str(), Ms(t.Count("time_bound_ps")).c_str(),
      TimeOverBound(t.Count("time_ps"), t.Count("time_bound_ps")).c_str(),
      Ms(t.Count("work_ps")).c_str(), Ms(t.Count("stall_ps")).c_str(),
      Ms(t.Count("idle_ps")).c_str(), 100 * t.Real("utilisation"),
      (unsigned long long)t.Count("peak_queued_rays"), (unsigned long long)t.Count("segments"));
  out << line;
}

// `time bound ms` is the lower bound on the time under any scheduler (time_bound_ps), and
// `time/bound` how far the replay is from it.
void PrintTable(const TraceReplay& t, std::ostream& out) {
  out << "   frame   fetches   bound      time ms time bound ms time/bound      work ms"
         "     stall ms      idle ms   util peak rays     segments\n";
  for (const ReplayResult& r : t.frames) {
    TableRow(std::to_string(r.frame), ToStatsTable(r, kReplayTableColumns), out);
  }
  const StatsTable total = ToStatsTable(t.total, kReplayTableColumns);
  TableRow("total", total, out);
  out << "bytes fetched per level:";
  for (const StatsTable& l : std::get<StatTables>(*total.Find("levels"))) {
    out << " " << FormatValue(*l.Find("name")) << " " << l.Count("bytes");
  }
  out << "\n";
}

ReplayConfig MakeConfig(const ReplayArgs& a) {
  ReplayConfig c = a.config.empty() ? DefaultConfig() : LoadConfig(a.config);
  if (!a.scheduler.empty()) ApplyOverride(c, "scheduler", a.scheduler, "--scheduler");
  if (!a.granularity.empty()) ApplyOverride(c, "granularity", a.granularity, "--granularity");
  for (const std::string& s : a.sets) {
    const auto eq = s.find('=');
    if (eq == std::string::npos) throw InputError("--set '" + s + "': expected KEY=VALUE");
    ApplyOverride(c, s.substr(0, eq), s.substr(eq + 1));
  }
  ValidateConfig(c, "the configuration");
  return c;
}

void Write(const std::string& path, const std::string& text) {
  if (path.empty()) {
    std::cout << text;
    return;
  }
  WriteFileAtomically(path, text, "--out " + path);
}

void Run(const ReplayArgs& a) {
  const ReplayConfig config = MakeConfig(a);
  if (a.print_config) {
    std::cout << ToToml(config);
    return;
  }
  if (a.trace.empty()) throw InputError("give a TRACE file to replay (or --print-config)");
  if (a.format != "table" && a.format != "json" && a.format != "csv") {
    throw InputError("--format '" + a.format + "': expected table, json or csv");
  }
  if (a.sample < 1) throw InputError("--sample: must be at least 1");
  if (a.jobs < 1) throw InputError("--jobs: must be at least 1");
  const TraceReader reader = TraceReader::Open(a.trace, a.cells);
  if (!reader.warning().empty()) std::cerr << "raycell: warning: " << reader.warning() << "\n";
  Progress progress(!a.quiet);
  if (!a.timeline.empty() && a.sample > 1) {
    throw InputError("--timeline shows the replay as it ran; it cannot be combined with --sample " +
                     std::to_string(a.sample) + " (the sample's times are scaled afterwards)");
  }
  const std::vector<std::size_t> frames = SelectFrameRange(reader, a.frames);
  const auto replay = [&](ReplayObserver* observer) {
    return ReplayTrace(
        reader, frames, config, [&](double f) { progress.Update(f, "replaying"); }, a.sample,
        observer, a.jobs);
  };
  TraceReplay t;
  if (a.timeline.empty()) {
    t = replay(nullptr);
  } else {  // streamed to a temporary, renamed when complete; removed if too large
    TimelineOptions options{a.trace, {}, a.timeline_limit, "--timeline " + a.timeline};
    for (const FrameSummary& f : reader.frames()) options.frame_numbers.push_back(f.frame);
    WriteFileAtomically(
        a.timeline,
        [&](std::ostream& out) {
          TimelineWriter writer(out, config, reader.header().footprints, options);
          t = replay(&writer);
          writer.Finish();
        },
        "--timeline " + a.timeline);
  }
  progress.Done();
  std::ostringstream out;
  a.format == "json"  ? PrintJson(t, out)
  : a.format == "csv" ? PrintCsv(t, out)
                      : PrintTable(t, out);
  Write(a.out, out.str());
}

}  // namespace

namespace {

// One line per scheduler of the registry: "  maxwork      Max Work: ...".
std::string SchedulersHelp() {
  std::size_t width = 0;
  for (const SchedulerEntry& e : SchedulerRegistry()) width = std::max(width, std::strlen(e.name));
  std::string out;
  for (const SchedulerEntry& e : SchedulerRegistry()) {
    out += "  " + std::string(e.name) + std::string(width + 2 - std::strlen(e.name), ' ') +
           e.meaning + "\n";
  }
  return out;
}

}  // namespace

void AddReplayCommand(CLI::App& app) {
  auto args = std::make_shared<ReplayArgs>();
  CLI::App* cmd = app.add_subcommand(
      "replay", "Replay a trace through the GI-Cube memory model under a ray scheduler.");
  cmd->footer(
      "Block processors ask the scheduler for a cell, fetch it through the memory levels\n"
      "(latency + footprint / bandwidth per level), and work every ray queued there;\n"
      "rays move on to the queue of their next cell, spawned rays are worked in place.\n"
      "Reported per frame and in total: fetches into the processors' caches (and bytes per\n"
      "level), the maxGen bound where it holds (one processor with a one-cell cache),\n"
      "simulated time split into work, fetch stall and idle, a lower bound on the time that\n"
      "no scheduler beats (the work over the processors, the busiest link's transfers, the\n"
      "longest chain of dependent work) and the time over it, utilisation, peak queued rays,\n"
      "and the rays, segments and samples processed (equal to the trace's).\n\n"
      "Schedulers:\n" +
      SchedulersHelp() + "\nDefaults (see --print-config):\n" + DefaultsHelp() +
      "\nExamples:\n"
      "  raycell replay capture.rct --scheduler maxwork\n"
      "  raycell replay capture.rct --granularity node --format json --out r.json\n"
      "  raycell replay capture.rct --set processors.count=2 --set level.cache.capacity=2\n"
      "  raycell replay capture.rct --timeline timeline.json --frames 0..1   # ui.perfetto.dev\n"
      "  raycell replay --print-config > gicube.toml");
  cmd->add_option("TRACE", args->trace, "trace file written by `raycell record`");
  cmd->add_option("--cells", args->cells, kCellsSpecHelp);
  cmd->add_option("--config", args->config, "TOML configuration (unknown keys are errors)");
  cmd->add_option("--scheduler", args->scheduler,
                  SchedulerNameList(", ") + " (see Schedulers below)");
  cmd->add_option(
      "--granularity", args->granularity,
      "ray (per ray segment, exact), node (per Cell Tree node, aggregated) or auto (node "
      "with one processor, where it is exact; ray otherwise)");
  cmd->add_option("--set", args->sets,
                  "override a configuration key, KEY=VALUE (repeatable), "
                  "e.g. processors.count=2");
  cmd->add_option("--frames", args->frames, "frame numbers A..B (default: all)");
  cmd->add_option("--sample", args->sample,
                  "replay 1 in K ray trees (a primary ray and its descendants) of each frame and "
                  "scale rays, segments, samples and work back by K: faster, approximate")
      ->capture_default_str();
  cmd->add_option("--format", args->format, "table, json or csv")->capture_default_str();
  cmd->add_option("--jobs", args->jobs,
                  "threads (default: the hardware threads); `auto` runs its check's replays of "
                  "the frames seen on them at once, and most planners (not "
                  "balanced-adaptive) make frame i's plan on a spare one while frame i is read; "
                  "the results are the same for any number");
  cmd->add_option("--out", args->out, "write the results to FILE instead of standard output");
  cmd->add_option("--timeline", args->timeline,
                  "also write the replay as a Chrome trace-event JSON FILE, for ui.perfetto.dev or "
                  "chrome://tracing: a track per processor (fetch, work, idle) and per memory "
                  "level (transfers), queue counters, frame marks (docs/schemas.md); refused past "
                  "about 256 MB (choose fewer --frames)");
  cmd->add_option("--timeline-limit", args->timeline_limit,
                  "the timeline's size limit in bytes (for tests)")
      ->group("");  // hidden
  cmd->add_flag("--print-config", args->print_config, "print the full configuration and exit");
  cmd->add_flag("--quiet", args->quiet, "no progress bar");
  cmd->callback([args] { Run(*args); });
}

}  // namespace raycell
