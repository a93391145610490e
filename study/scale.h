// The study's scale section (issue 43): the wall time and the peak memory of `raycell record`,
// `raycell analyze` and `raycell replay` (Max Work, one processor) against the visits a
// capture holds and against its number of cells. Each command runs as a child process of the
// raycell binary, as a user runs it, so that its memory is its own: the child writes its peak
// resident memory (VmHWM of /proc/self/status, the memory of the program after exec alone)
// into the file RAYCELL_PEAK_FILE names (tools/raycell_main.cpp). The wait's rusage cannot be
// used: Linux starts a spawned child's maximum RSS at its parent's.
//
// Points: the scene at each of ScaleOptions::res in ScaleOptions::cells_at cells (the visits
// series), and at ScaleOptions::res_at in each of ScaleOptions::cells (the cells series), each
// a capture of `frames` frames of an orbit. The slopes are least-squares fits of log time (or
// log memory) on log visits (or log cells). BENCHMARKS.md "Scale" carries the same up to
// 2048x2048 and 4096 cells (tools/bench/scale.sh).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace raycell {

// The commands of a point, in the report's order.
inline const std::vector<std::string>& ScaleCommands() {
  static const std::vector<std::string> commands = {"record", "analyze", "replay"};
  return commands;
}

struct ScaleOptions {
  std::string scene;   // record's --scene
  std::string binary;  // the raycell binary to run; empty: the section is not measured
  std::string out;     // folder of the captures and the children's logs
  std::vector<std::string> res = {"32x32", "64x64", "128x128"};
  std::string cells_at = "4x4x4";
  std::vector<std::string> cells = {"2x2x2", "4x4x4", "8x8x8", "16x16x16"};
  std::string res_at = "64x64";
  int frames = 1;  // 0: not measured
};

struct ScaleRun {
  double seconds = 0;         // wall clock, spawn to exit
  std::uint64_t peak_kb = 0;  // the child's VmHWM
};

struct ScalePoint {
  std::string res, cells;  // as given to record
  std::uint64_t cell_count = 0, visits = 0;
  std::vector<ScaleRun> runs;  // one per ScaleCommands() entry
};

// A fit of log y on log x over the points of one series.
struct ScaleSlope {
  std::string command;  // a ScaleCommands() entry
  double time_on_visits = 0, memory_on_visits = 0, time_on_cells = 0, memory_on_cells = 0;
};

struct ScaleStudy {
  ScaleOptions options;
  bool measured = false;
  std::string not_measured;        // why not, when not measured
  double startup_seconds = 0;      // `raycell --version`: a process's fixed cost
  std::vector<ScalePoint> points;  // the visits series, then the cells series' other points
  std::vector<ScaleSlope> slopes;  // one per ScaleCommands() entry
  // The points of each series, in its order (indices into points).
  std::vector<std::size_t> visits_series, cells_series;
};

// The slope of the least-squares line through (log x, log y); 0 with fewer than two distinct
// x. Every value must be positive.
double LogLogSlope(const std::vector<double>& x, const std::vector<double>& y);

// Records, analyses and replays each point. Never throws for a child that fails: the section
// is then not measured, and not_measured says which command failed and its last message.
ScaleStudy MeasureScale(const ScaleOptions& options);

// scale.csv: one row per point and command.
std::string ScaleCsv(const ScaleStudy& s);
// The report's section (a heading and a table, or why it was not measured).
std::string ScaleReport(const ScaleStudy& s);

}  // namespace raycell
