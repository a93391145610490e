// raycell: capture volume ray tracing traces, cell by cell, and study ray schedules on them.
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <iostream>
#include <string>

#include "base/check.h"
#include "tools/commands.h"

namespace {

// With RAYCELL_PEAK_FILE set, a command that succeeded writes its peak resident memory in kB
// there: VmHWM of /proc/self/status, which counts this program alone. (The study's scale
// section reads it, study/scale.h: the wait's rusage starts a spawned child at its parent's.)
void WritePeakMemory() {
  const char* file = std::getenv("RAYCELL_PEAK_FILE");
  if (file == nullptr || *file == '\0') return;
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmHWM:", 0) == 0) {
      std::ofstream(file) << std::stoull(line.substr(6)) << "\n";
      return;
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "raycell records what every ray of a volume ray tracer does, cell by cell, into\n"
      "compressed per-frame traces, for people who design memory-coherent ray tracing\n"
      "hardware and ray schedulers.\n\n"
      "  raycell study                      the main job: record, analyse, replay, report\n"
      "                                     (out/study/report.md)\n"
      "  raycell record                     record the built-in scene (out/capture.rct,\n"
      "                                     out/images/)\n"
      "  raycell record --scene smoke.vdb --cells 3x3x3 --frames 0..29 --orbit 360\n"
      "  raycell trace info capture.rct     what a capture holds\n"
      "  raycell trace cat capture.rct --frame 0 --format jsonl   rays as JSON Lines\n"
      "  raycell analyze capture.rct --exact  Cell Tree, maxGen bound, Peel, optimum\n"
      "  raycell replay capture.rct --scheduler maxwork   fetches and time on the GI-Cube model\n\n"
      "Run `raycell COMMAND --help` for each command's options.",
      "raycell"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "raycell 0.1.0");
  raycell::AddStudyCommand(app);
  raycell::AddSuiteCommand(app);
  raycell::AddRecordCommand(app);
  raycell::AddTraceCommand(app);
  raycell::AddAnalyzeCommand(app);
  raycell::AddReplayCommand(app);
  raycell::AddSweepCommand(app);
  int status = 0;
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {  // --help and --version exit 0, usage errors 2
    status = app.exit(e) == 0 ? 0 : 2;
  } catch (const raycell::InputError& e) {
    std::cerr << "raycell: error: " << e.what() << "\n";
    status = 2;
  } catch (const std::exception& e) {
    std::cerr << "raycell: error: " << e.what() << "\n";
    status = 1;
  }
  if (status == 0) WritePeakMemory();
  return status;
}
