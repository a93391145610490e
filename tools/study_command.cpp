// raycell study: the main job end to end (study/study.h), its options parsed here and its
// report written by study/report.h.
#include <filesystem>
#include <iostream>
#include <memory>

#include "study/report.h"
#include "study/study.h"
#include "tools/commands.h"

namespace raycell {

void AddStudyCommand(CLI::App& app) {
  auto args = std::make_shared<StudyOptions>();
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
      "On the finest grid (the last of --cells, or the last --trace) it replays Max Work,\n"
      "Cell Tree scheduling and balanced on 1, 2, 4, 8 and 16 block processors (--processors,\n"
      "up to 64): time,\n"
      "fetches and the time's lower bound in OUT/processors.csv and processors.png.\n"
      "Then measures run time against error for the renderer's step, cutoff, precision and\n"
      "max depth and the replay's granularity and sampling on short captures of the same\n"
      "scene (study/accuracy.h; --accuracy-frames 0 skips it), and from its captures of max\n"
      "depth 0..5 the depth section: rays, Cell Tree nodes, fetches and simulated time under\n"
      "Max Work and Cell Tree scheduling, image RMSE against max depth 5 (OUT/depth.csv,\n"
      "depth.png; absent, saying why, when run time against error is skipped).\n"
      "Last, the subdivision section: one capture of the scene with --regroupable on\n"
      "12x12x12 cells (--subdivision-fine; --subdivision-frames frames at --accuracy-res;\n"
      "0 frames skips it) replayed regrouped into 3x3x3, kd:27:footprint, kd:27:work,\n"
      "kd:27:sqrt, a byte budget, an octree, dynamic:27, dynamic:27:sqrt and\n"
      "grid:27:crossings under Max Work and Cell Tree scheduling, the cache sized to the\n"
      "median 3x3x3 footprint: fetches, bytes over each link, stall (OUT/subdivisions.csv,\n"
      "subdivisions.png).\n"
      "Then the scale section (study/scale.h): record, analyze and replay (Max Work) each\n"
      "run as its own process at 32x32 to 128x128 in 4x4x4 cells and at 64x64 in 2x2x2\n"
      "to 16x16x16 cells, --scale-frames frames each: wall time and peak memory against\n"
      "visits and cells, with their log-log slopes (OUT/scale.csv, scale.png).\n"
      "With no options: the built-in scene, 24 frames over 90 degrees, 2x2x2 and 3x3x3\n"
      "cells, 256x256, into out/study/ (out/ is outside every source folder); about two\n"
      "minutes on 2 cores.\n"
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
                      "builtin, a scene file FILE.toml (docs/scenes.md: its camera, lights and "
                      "materials, turned by --orbit), a .vdb file, or a printf pattern of one "
                      "file per frame (see record), e.g. fluid_data_%04d.vdb with --frames "
                      "150..155")
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
                  "frames of the run time against error captures (the depth section's too); 0 "
                  "skips both sections")
      ->capture_default_str();
  cmd->add_option("--subdivision-frames", args->subdivision_frames,
                  "frames of the subdivision section's fine capture; 0 skips the section")
      ->capture_default_str();
  cmd->add_option("--suite", args->suite,
                  "a `raycell suite` folder: the report quotes its headlines (geometric mean and "
                  "worst scene of each recommendation) beside this scene's figure")
      ->capture_default_str();
  cmd->add_option("--processors", args->processors,
                  "the boards of the several processors section, ascending, each 1..64 (e.g. "
                  "1,8,64)")
      ->capture_default_str();
  cmd->add_option("--scale-frames", args->scale_frames,
                  "frames of each capture of the scale section; 0 skips the section")
      ->capture_default_str();
  cmd->add_option("--subdivision-fine", args->subdivision_fine,
                  "the subdivision section's fine grid, each count a multiple of 3 (e.g. "
                  "24x24x24 for finer k-d and octree cells, at about 8 times the capture)")
      ->capture_default_str();
  cmd->add_option("--accuracy-res", args->accuracy_res,
                  "image size of the run time against error captures (the depth and subdivision "
                  "sections' too)")
      ->capture_default_str();
  cmd->add_option("--effort", args->effort,
                  "budget of the bracket of each frame's optimum: quick (the study's), default "
                  "(analyze --bracket's, about ten times the work) or thorough")
      ->capture_default_str();
  cmd->add_flag("--quiet", args->quiet, "no progress bars");
  CLI::Option* orbit = recording[3];
  cmd->callback([args, orbit] {
    args->orbit_given = orbit->count() > 0;
    std::error_code error;  // the scale section runs this binary; without it, not measured
    args->binary = std::filesystem::read_symlink("/proc/self/exe", error).string();
    const std::string report = WriteStudyReport(RunStudy(*args));
    std::cout << "report: " << report << "\n";
  });
}

}  // namespace raycell
