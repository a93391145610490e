// raycell suite: every scene of a suite recorded, replayed and compared (study/suite.h); its
// options parsed here.
#include <iostream>
#include <memory>

#include "study/suite.h"
#include "tools/commands.h"

namespace raycell {

void AddSuiteCommand(CLI::App& app) {
  auto args = std::make_shared<SuiteOptions>();
  CLI::App* cmd = app.add_subcommand(
      "suite",
      "Record a suite of scenes and report each comparison's geometric mean and worst "
      "scene.");
  cmd->footer(
      "A claim about schedulers or subdivisions holds only if it holds on scenes it was not\n"
      "tuned on. The suite records every scene once (or reuses its capture when the scene\n"
      "file, the options and the raycell binary are unchanged) on --fine cells with\n"
      "--regroupable, reads it regrouped into --cells, and:\n"
      "  - replays Max Work, balanced, balanced-critical, celltree-adaptive and auto on a\n"
      "    board of --processors processors: fetches (every frame) and simulated time over\n"
      "    the frames after the first (frame 0 is the board's cold load, the same for every\n"
      "    scheduler) against Max Work;\n"
      "  - replays Max Work, celltree (the paper's Cell Tree scheduling), celltree-adaptive,\n"
      "    auto and the oracle best on one processor: fetches over the oracle's;\n"
      "  - regroups the capture into the uniform grid --cells and, with N its cells, auto:N,\n"
      "    kd:N:footprint, kd:N:sqrt, dynamic:N:sqrt and grid:N:crossings, the cache sized to\n"
      "    the uniform grid's median cell, under Max Work and auto: bytes moved into the\n"
      "    cache against the uniform grid.\n"
      "A scene whose volume changes per frame cannot be regrouped: it is recorded in --cells\n"
      "and left out of the subdivision table.\n"
      "It writes OUT/report.md (per comparison one row per scene, the geometric mean of the\n"
      "ratios and the worst scene; the scenes' character: rays per pixel, secondary rays,\n"
      "maxGen per cell), OUT/suite.csv (every replay's totals), OUT/suite.png, one file per\n"
      "scene in OUT/scenes/ and the captures in OUT/captures/.\n"
      "The default suite is the scene files shipped with raycell (scenes/: fog, clouds,\n"
      "mirrors, glass, CSG, thin surfaces, terrain, the built-in scene, a large volume, an\n"
      "animation) and the volumes of --data when that folder exists.\n"
      "On a Slurm cluster: tools/slurm/submit_suite.sh runs one scene per array task\n"
      "(--only NAME) and the report (--report) when all have ended.\n\n"
      "Examples:\n"
      "  raycell suite                                # the default suite into out/suite/\n"
      "  raycell suite --scenes scenes/dense_fog.toml --scenes my_scene.toml --frames 16\n"
      "  raycell suite --res 256x256 --processors 16 --out out/suite-256");
  cmd->add_option("--scenes", args->scenes,
                  "a scene file (.toml), a volume (.vdb) or a folder of them, repeatable; "
                  "default: the shipped suite and --data's volumes");
  cmd->add_option("--data", args->data,
                  "a folder of real volumes (.vdb, and sequences NAME_0001.vdb ... in "
                  "subfolders) that join the default suite when it exists")
      ->capture_default_str();
  cmd->add_option("--res", args->res, "image size WxH")->capture_default_str();
  cmd->add_option("--frames", args->frames, "frames per scene (at least 2)")->capture_default_str();
  cmd->add_option("--cells", args->cells, "the cells replayed, NXxNYxNZ")->capture_default_str();
  cmd->add_option("--fine", args->fine,
                  "the fine grid each scene is recorded on and regrouped from; each count a "
                  "multiple of --cells'")
      ->capture_default_str();
  cmd->add_option("--processors", args->processors, "the board of several processors, 2..64")
      ->capture_default_str();
  cmd->add_option("--out", args->out, "folder for the report, CSVs, plot and captures")
      ->capture_default_str();
  cmd->add_option("--only", args->only,
                  "one scene, by name (its file's stem): its captures and OUT/scenes/NAME.csv, "
                  "no report (a cluster's array task)");
  cmd->add_flag("--report", args->report_only,
                "only the report, from every scene's OUT/scenes/NAME.csv (after --only runs)");
  cmd->add_flag("--list", args->list,
                "print the scenes, one per line: NAME, a tab, FILE; nothing is recorded");
  cmd->add_option("--threads", args->threads, "rendering threads, 0 = all cores")
      ->capture_default_str();
  cmd->add_flag("--quiet", args->quiet, "no progress");
  cmd->callback([args] {
    RunSuite(*args);
    if (args->only.empty() && !args->list) std::cout << "report: " << args->out << "/report.md\n";
  });
}

}  // namespace raycell
