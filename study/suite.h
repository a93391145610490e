// `raycell suite` as a library (issue 42; docs/design.md §7 "The suite"): every scene of a
// suite recorded once (or reused), replayed under the schedulers at 1 and several processors
// and regrouped into several subdivisions, each comparison summarised over the scenes by its
// geometric mean and its worst scene. One scene's work is independent of the others' and
// ends in a file of its own (OUT/scenes/NAME.csv), so a cluster runs one scene per task and
// the report is made from the files (tools/slurm/submit_suite.sh).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "analysis/character.h"

namespace raycell {

struct SuiteOptions {
  // Scene files (.toml) and volumes (.vdb), or folders of them; empty: the installed suite
  // (SuiteFolder()) and the volumes of `data` when it exists.
  std::vector<std::string> scenes;
  std::string data = "../shared/data";  // real volumes that join the default suite if present
  std::string res = "128x128", cells = "3x3x3", fine = "12x12x12", out = "out/suite";
  int frames = 8;                // per scene, from its first frame (a sequence: at most these)
  std::uint32_t processors = 8;  // the board of several processors (and 1)
  std::string only;              // one scene by name: its file only, no report (a Slurm task)
  bool report_only = false;      // the report from OUT/scenes/*.csv, nothing replayed
  bool list = false;             // print each scene's name and file (tab-separated), nothing else
  int threads = 0;               // recording threads (0: all cores); replays use the cores too
  bool quiet = false;
};

// A scene of the suite: its name (the file's stem), the file, and what it stands for (the
// comment at the top of a scene file; for a volume, the file's kind).
struct SuiteScene {
  std::string name, file, about;
  bool sequence = false;  // a printf pattern of one volume per frame
  int first_frame = 0, frame_count = 0;
};

// One replay's totals.
struct SuiteRow {
  std::string kind;       // "scheduler" or "cells"
  std::string name;       // the scheduler, or the subdivision SPEC
  std::string scheduler;  // the scheduler a "cells" row was replayed under
  std::uint32_t processors = 1;
  std::uint64_t fetches = 0, cache_bytes = 0;
  std::uint64_t time_ps = 0, time_after_first_ps = 0;  // all frames; frames after the first
};

struct SuiteSceneResult {
  SuiteScene scene;
  CaptureCharacter character;  // of the capture in --cells
  double record_seconds = 0;   // 0 when reused; not in the files, which every machine writes alike
  std::uint64_t cache_capacity = 0;  // the subdivision rows' cache: 3x3x3's median footprint
  std::vector<SuiteRow> rows;
};

// The suite folder shipped with raycell: scenes/ beside the running binary (the build copies
// it there) or ../share/raycell/scenes (an install). InputError if neither exists.
std::string SuiteFolder();
// The scenes the options name, sorted by name within each folder; InputError for a file that
// does not exist or is neither .toml nor .vdb, two scenes of one name, or no scene at all.
std::vector<SuiteScene> SuiteScenes(const SuiteOptions& options);

// The schedulers compared at one processor and at several (registry names; those not in the
// registry are left out), and the subdivisions into as many cells as `cells` (NXxNYxNZ, the
// uniform grid first): for 3x3x3, 3x3x3, auto:27, kd:27:footprint, kd:27:sqrt,
// dynamic:27:sqrt and grid:27:crossings.
std::vector<std::string> SuiteSchedulers(std::uint32_t processors);
std::vector<std::string> SuiteSubdivisions(const std::string& cells);

// Records (or reuses) one scene's captures under OUT/captures/ and replays them; writes
// OUT/scenes/NAME.csv.
SuiteSceneResult RunSuiteScene(const SuiteOptions& options, const SuiteScene& scene);
// The per-scene file and its reader (InputError naming the file when it is not one).
std::string SuiteSceneCsv(const SuiteSceneResult& r);
SuiteSceneResult ReadSuiteSceneCsv(const std::string& path);

// report.md's text from the scenes' results: the character table, then per comparison one
// row per scene, the geometric mean of the ratios over the scenes and the worst scene.
std::string SuiteReportText(const SuiteOptions& options,
                            const std::vector<SuiteSceneResult>& scenes);
// The scene whose own figure report.md's headlines give beside the suite's: the built-in one.
inline constexpr const char* kSuiteBeside = "builtin";
// report.md's headlines: per comparison of `auto` (several processors and one against their
// baselines, auto:N against the uniform grid), the geometric mean over the scenes, the worst
// scene, and `beside`'s own figure when it is one of the scenes.
std::vector<std::string> SuiteHeadlines(const SuiteOptions& options,
                                        const std::vector<SuiteSceneResult>& scenes,
                                        const std::string& beside);
// The results a suite left in DIR/scenes/*.csv, sorted by name (empty when there are none;
// InputError for a file that is not one), and in `options` what the rows tell of the options
// they were made with: processors (the largest count replayed) and cells (the first
// subdivision row's, the uniform grid).
std::vector<SuiteSceneResult> ReadSuiteResults(const std::string& dir, SuiteOptions* options);
// report.md from the scenes' results (geometric means and worst scenes), suite.csv (every
// row of every scene) and the plots. Returns report.md's text.
std::string SuiteReport(const SuiteOptions& options, const std::vector<SuiteSceneResult>& scenes);

// The whole run: every scene (or `only`), then the report into options.out.
void RunSuite(const SuiteOptions& options);

}  // namespace raycell
