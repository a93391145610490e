// The study's scale section: see scale.h.
#include "study/scale.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "base/check.h"
#include "base/format.h"
#include "traces/cell_dims.h"
#include "traces/format.h"
#include "traces/trace_reader.h"

extern char** environ;

namespace raycell {
namespace {

namespace fs = std::filesystem;

// The last non-empty line of a child's log, for the message of a failure.
std::string LastLine(const fs::path& log) {
  std::ifstream in(log);
  std::string line, last;
  while (std::getline(in, line)) {
    if (!line.empty()) last = line;
  }
  return last.empty() ? "(no message)" : last;
}

// Runs `binary args...` with its standard output discarded and its standard error in `log`;
// false (and `why`) if it cannot be started or does not exit 0.
bool RunChild(const std::string& binary, const std::vector<std::string>& args, const fs::path& log,
              ScaleRun& run, std::string& why) {
  const fs::path peak_file = fs::path(log).replace_extension(".peak");
  fs::remove(peak_file);
  std::vector<std::string> env_strings;
  for (char** e = environ; *e != nullptr; ++e) {
    if (std::string_view(*e).rfind("RAYCELL_PEAK_FILE=", 0) != 0) env_strings.emplace_back(*e);
  }
  env_strings.push_back("RAYCELL_PEAK_FILE=" + peak_file.string());
  std::vector<char*> envp, argv;
  for (std::string& s : env_strings) envp.push_back(s.data());
  envp.push_back(nullptr);
  std::vector<std::string> all = {binary};
  all.insert(all.end(), args.begin(), args.end());
  for (std::string& s : all) argv.push_back(s.data());
  argv.push_back(nullptr);
  std::string command = "raycell";
  for (const std::string& a : args) command += " " + a;

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  const auto start = std::chrono::steady_clock::now();
  pid_t pid = 0;
  const int spawned =
      posix_spawn(&pid, binary.c_str(), &actions, nullptr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) {
    why = "cannot start " + binary + " (" + std::to_string(spawned) + ")";
    return false;
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    why = "`" + command + "` failed (" +
          (WIFEXITED(status) ? "exit " + std::to_string(WEXITSTATUS(status)) : "killed") +
          "): " + LastLine(log);
    return false;
  }
  std::ifstream peak(peak_file);
  if (!(peak >> run.peak_kb) || run.peak_kb == 0) {
    why = "`" + command + "` did not report its peak memory in " + peak_file.string();
    return false;
  }
  return true;
}

// Where the point (res, cells) is in s.points, adding it if new.
std::size_t PointIndex(ScaleStudy& s, const std::string& res, const std::string& cells) {
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    if (s.points[i].res == res && s.points[i].cells == cells) return i;
  }
  ScalePoint p;
  p.res = res;
  p.cells = cells;
  s.points.push_back(p);
  return s.points.size() - 1;
}

bool MeasurePoint(const ScaleOptions& o, ScalePoint& p, std::string& why) {
  const std::string name = p.res + "_" + p.cells;
  const fs::path dir(o.out);
  const std::string trace = (dir / (name + ".rct")).string();
  const std::vector<std::vector<std::string>> commands = {
      {"record", "--scene", o.scene, "--res", p.res, "--cells", p.cells, "--orbit",
       std::to_string(o.frames) + ":" + std::to_string(2 * o.frames), "--no-images", "--quiet",
       "--out", trace},
      {"analyze", trace, "--quiet", "--format", "csv"},
      {"replay", trace, "--scheduler", "maxwork", "--quiet"}};
  RAYCELL_CHECK(commands.size() == ScaleCommands().size());
  for (std::size_t c = 0; c < commands.size(); ++c) {
    ScaleRun run;
    if (!RunChild(o.binary, commands[c], dir / (name + "." + ScaleCommands()[c] + ".log"), run,
                  why)) {
      return false;
    }
    p.runs.push_back(run);
    if (c == 0) {
      const TraceReader reader = TraceReader::Open(trace);
      p.cell_count = reader.header().cell_count();
      for (const FrameSummary& f : reader.frames()) p.visits += f.visits;
    }
  }
  return true;
}

}  // namespace

double LogLogSlope(const std::vector<double>& x, const std::vector<double>& y) {
  RAYCELL_CHECK(x.size() == y.size());
  const double n = static_cast<double>(x.size());
  double sx = 0, sy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    RAYCELL_CHECK(x[i] > 0 && y[i] > 0);
    sx += std::log(x[i]);
    sy += std::log(y[i]);
  }
  double sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double dx = std::log(x[i]) - sx / n;
    sxx += dx * dx;
    sxy += dx * (std::log(y[i]) - sy / n);
  }
  return sxx > 0 ? sxy / sxx : 0;
}

ScaleStudy MeasureScale(const ScaleOptions& o) {
  ScaleStudy s;
  s.options = o;
  if (o.frames <= 0) {
    s.not_measured = "skipped (--scale-frames 0)";
    return s;
  }
  if (o.binary.empty()) {
    s.not_measured = "no raycell binary to run (the study was run as a library)";
    return s;
  }
  fs::create_directories(o.out);
  std::string why;
  ScaleRun startup;
  if (!RunChild(o.binary, {"--version"}, fs::path(o.out) / "version.log", startup, why)) {
    s.not_measured = why;
    return s;
  }
  s.startup_seconds = startup.seconds;
  for (const std::string& res : o.res) s.visits_series.push_back(PointIndex(s, res, o.cells_at));
  for (const std::string& cells : o.cells) {
    s.cells_series.push_back(PointIndex(s, o.res_at, cells));
  }
  for (ScalePoint& p : s.points) {
    if (!MeasurePoint(o, p, why)) {
      s.not_measured = why;
      s.points.clear();
      return s;
    }
  }
  for (std::size_t c = 0; c < ScaleCommands().size(); ++c) {
    ScaleSlope slope;
    slope.command = ScaleCommands()[c];
    const auto fit = [&](const std::vector<std::size_t>& series, bool on_visits, bool memory) {
      std::vector<double> x, y;
      for (std::size_t i : series) {
        const ScalePoint& p = s.points[i];
        x.push_back(static_cast<double>(on_visits ? p.visits : p.cell_count));
        y.push_back(memory ? static_cast<double>(p.runs[c].peak_kb) : p.runs[c].seconds);
      }
      return LogLogSlope(x, y);
    };
    slope.time_on_visits = fit(s.visits_series, true, false);
    slope.memory_on_visits = fit(s.visits_series, true, true);
    slope.time_on_cells = fit(s.cells_series, false, false);
    slope.memory_on_cells = fit(s.cells_series, false, true);
    s.slopes.push_back(slope);
  }
  s.measured = true;
  return s;
}

std::string ScaleCsv(const ScaleStudy& s) {
  std::ostringstream out;
  out << "res,cells,cell_count,visits,series,command,seconds,peak_mb\n";
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    const ScalePoint& p = s.points[i];
    const auto in = [i](const std::vector<std::size_t>& v) {
      return std::find(v.begin(), v.end(), i) != v.end();
    };
    const std::string series = in(s.visits_series) && in(s.cells_series) ? "both"
                               : in(s.visits_series)                     ? "visits"
                                                                         : "cells";
    for (std::size_t c = 0; c < p.runs.size(); ++c) {
      out << p.res << ',' << p.cells << ',' << p.cell_count << ',' << p.visits << ',' << series
          << ',' << ScaleCommands()[c] << ',' << FormatFixed(p.runs[c].seconds, 3) << ','
          << FormatFixed(static_cast<double>(p.runs[c].peak_kb) / 1024.0, 1) << '\n';
    }
  }
  return out.str();
}

std::string ScaleReport(const ScaleStudy& s) {
  std::ostringstream out;
  out << "## Scale\n\n";
  if (!s.measured) {
    out << "Not measured: " << s.not_measured << ".\n";
    return out.str();
  }
  const ScaleOptions& o = s.options;
  out << "Wall time and peak memory of `raycell record`, `analyze` (no bracket) and `replay` "
      << "(Max Work, 1 processor), each run as its own process on a capture of " << o.frames
      << " frames of the scene: at " << o.res.front() << " to " << o.res.back() << " in "
      << o.cells_at << " cells (visits), and at " << o.res_at << " in " << o.cells.front() << " to "
      << o.cells.back() << " cells (`study/scale.h`; OUT/scale.csv, scale.png). "
      << "Slopes are least-squares fits of log time (memory) on log visits (cells): 1 is "
      << "linear. These points are small, so a process's fixed cost (`raycell --version`: "
      << FormatFixed(s.startup_seconds * 1000, 0) << " ms, and the libraries' memory) "
      << "flattens them; BENCHMARKS.md \"Scale\" has the same up to 2048x2048 and 4096 "
      << "cells.\n\n";
  out << "| image | cells | visits |";
  for (const std::string& c : ScaleCommands()) out << ' ' << c << " s (MB) |";
  out << "\n|---|---|---:|";
  for (std::size_t c = 0; c < ScaleCommands().size(); ++c) out << "---:|";
  out << '\n';
  for (const ScalePoint& p : s.points) {
    out << "| " << p.res << " | " << p.cells << " | " << p.visits << " |";
    for (const ScaleRun& r : p.runs) {
      out << ' ' << FormatFixed(r.seconds, 2) << " ("
          << FormatFixed(static_cast<double>(r.peak_kb) / 1024.0, 0) << ") |";
    }
    out << '\n';
  }
  out << "\n| command | time on visits | memory on visits | time on cells | memory on cells "
         "|\n|---|---:|---:|---:|---:|\n";
  for (const ScaleSlope& sl : s.slopes) {
    out << "| " << sl.command << " | " << FormatFixed(sl.time_on_visits, 2) << " | "
        << FormatFixed(sl.memory_on_visits, 2) << " | " << FormatFixed(sl.time_on_cells, 2) << " | "
        << FormatFixed(sl.memory_on_cells, 2) << " |\n";
  }
  out << "\n![Scale](scale.png)\n";
  return out.str();
}

}  // namespace raycell
