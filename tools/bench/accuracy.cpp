// Run time against error for the knobs that trade one for the other (study/accuracy.h), alone:
// the section `raycell study` ends its report with, on any scene, size and number of frames.
// Prints the Markdown table and writes OUT/accuracy.csv and OUT/accuracy.png (the captures
// in OUT/, one folder per renderer setting).
//
// Usage: bench_accuracy [--scene builtin|FILE.vdb] [--res 128x128] [--frames 4]
//                       [--out bench-out/accuracy]
#include "study/accuracy.h"

#include <CLI/CLI.hpp>
#include <iostream>

#include "base/check.h"
#include "base/file.h"
#include "study/report.h"

int main(int argc, char** argv) {
  raycell::AccuracyOptions options;
  options.out = "bench-out/accuracy";
  CLI::App app{"Run time against error for the renderer's and the replay's knobs.",
               "bench_accuracy"};
  app.add_option("--scene", options.scene, "builtin or a .vdb file")->capture_default_str();
  app.add_option("--res", options.res, "image size WxH")->capture_default_str();
  app.add_option("--frames", options.frames, "frames of the orbit (20 degrees), 1..1000")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  app.add_option("--out", options.out, "folder for the captures, the CSV and the plot")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    options.quiet = false;
    const raycell::AccuracyStudy study = raycell::MeasureAccuracy(options);
    if (!study.measured) throw raycell::InputError(study.not_measured);
    raycell::WriteFileAtomically(options.out + "/accuracy.csv", raycell::AccuracyCsv(study.rows));
    raycell::PlotAccuracy(options.out);
    std::cout << raycell::AccuracyTable(study.rows);
  } catch (const raycell::InputError& e) {
    std::cerr << "bench_accuracy: error: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
