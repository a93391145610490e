// `raycell study` as a library: for each cell grid (or given capture) it records the scene,
// replays the capture under every studied scheduler, brackets each frame's optimum, and
// measures run time against error for the knobs that trade one for the other. RunStudy
// returns what it found as data; study/report.h turns that into report.md, CSVs and plots,
// and the command (tools/study_command.cpp) only parses options into StudyOptions. On the
// finest grid it also replays boards of several processors (docs/design.md §5 "Load
// balancing"); from the run time against error section's max depth captures it makes the
// depth section (study/depth.h).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "analysis/analysis.h"
#include "runner/driver.h"
#include "scheduling/scheduler.h"
#include "study/accuracy.h"
#include "study/depth.h"
#include "study/scale.h"
#include "study/subdivisions.h"

namespace raycell {

struct StudyOptions {
  std::string scene = "builtin", cells = "2x2x2,3x3x3", res = "256x256", out = "out/study";
  std::string accuracy_res = "128x128";
  std::string frames = "24";   // a count N (frames 0..N-1) or frame numbers A..B
  int accuracy_frames = 2;     // 0: no run time against error section
  int subdivision_frames = 8;  // 0: no subdivision section (study/subdivisions.h)
  int scale_frames = 1;        // 0: no scale section (study/scale.h)
  // The boards of the several processors section, ascending, each 1..64.
  std::string processors = "1,2,4,8,16";
  // A `raycell suite` folder whose results the report quotes (study/suite.h): its headlines,
  // beside this scene's own figure when the scene is one of its scenes.
  std::string suite = "out/suite";
  // The raycell binary the scale section runs (tools/study_command.cpp: this process's);
  // empty: the section is not measured.
  std::string binary;
  std::string subdivision_fine = "12x12x12";  // its fine grid: each count a multiple of 3
  std::vector<std::string> traces;            // reused captures instead of recording
  std::string effort = "quick";               // the bracket's budget (BracketEffort)
  // Degrees the camera turns over the frames. Default: 90 for one volume (3.75 degrees per
  // frame over 24: consecutive frames alike, as in an animation), 0 for a sequence, whose
  // volumes are the animation.
  double orbit = 90;
  bool orbit_given = false;
  int threads = 0;        // rendering threads of the grids' captures, 0 = all cores
  bool quiet = false;     // no progress bars (the one-line summaries are still printed)
  bool sequence() const;  // the scene is a printf pattern of one volume per frame
  double orbit_degrees() const { return orbit_given || !sequence() ? orbit : 0; }
};

// The schedulers the study replays, in the report's order: the registry's studied ones,
// online first (they plan frame i+1 from what frame i showed, as hardware could), then the
// oracles (they know the frame itself).
std::vector<const SchedulerEntry*> StudySchedulers();

struct SchedulerReplay {
  const SchedulerEntry* scheduler = nullptr;
  TraceReplay replay;  // per Cell Tree node, the default configuration otherwise
};

// The several processors section, on the study's finest grid: Max Work, Cell Tree scheduling
// and `balanced` (the registry's scheduler for several processors), in the report's order,
// each on boards of StudyProcessorCounts() block processors.
std::vector<const SchedulerEntry*> ProcessorsSchedulers();
const std::vector<std::uint32_t>& StudyProcessorCounts();  // 1, 2, 4, 8, 16: the default
// The board sizes of StudyOptions::processors ("1,2,4,8,16"): InputError naming --processors
// unless each is in 1..64 and they ascend.
std::vector<std::uint32_t> ParseProcessorCounts(const std::string& list);

struct ProcessorsReplay {
  const SchedulerEntry* scheduler = nullptr;
  std::uint32_t processors = 1;  // processors.count
  // TraceReplay::total of every frame under the default configuration otherwise (warm memory,
  // granularity auto: per Cell Tree node with one processor, per ray segment beyond).
  ReplayResult total;
};

// The results for one cell grid (recorded) or one given trace.
struct GridStudy {
  std::string cells;    // the label in file names: "3x3x3", or the given trace's file stem
  std::string heading;  // the report's section title: "3x3x3 cells", or the trace and its grid
  std::string capture;  // the trace: relative to the study folder when recorded, else as given
  std::string images;   // the frames' images, relative to the study folder; empty for a trace
  std::vector<FrameAnalysis> trees;      // per frame, with the bracket of the optimum
  std::vector<SchedulerReplay> replays;  // one per StudySchedulers() entry, in its order
  // One per ProcessorsSchedulers() x StudyProcessorCounts() pair, the count varying fastest;
  // on the study's finest grid (the last one studied) only, empty on the others.
  std::vector<ProcessorsReplay> processors;

  // The replay under `scheduler` (a registry entry); CHECK-fails if it was not studied.
  const TraceReplay& replay(const SchedulerEntry& scheduler) const;
};

struct StudyResult {
  StudyOptions options;
  std::vector<int> frame_numbers;  // what options.frames says; empty for given traces
  std::vector<GridStudy> grids;    // in the order of --cells, or of the given traces
  AccuracyStudy accuracy;
  DepthStudy depth;               // from accuracy's captures: not measured when accuracy was not
  SubdivisionStudy subdivisions;  // one fine capture of the scene, at accuracy_res
  ScaleStudy scale;               // record, analyze and replay run at small points
  // The suite's results in options.suite: how many scenes, its headlines (SuiteHeadlines,
  // beside the scene's name), or why they could not be read.
  std::size_t suite_scenes = 0;
  std::vector<std::string> suite_headlines;
  std::string suite_error;
};

// Runs the study: checks the options (InputError naming the option, before any work),
// records and studies each grid (or each given trace) into options.out, replays the last one
// on several processors, then measures run time against error into options.out/accuracy/ and
// the depth section from its captures, and the subdivision section into
// options.out/subdivisions/. One summary line per capture on stderr, progress bars
// unless quiet.
StudyResult RunStudy(const StudyOptions& options);

}  // namespace raycell
