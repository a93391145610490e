// Regrouping speed (issue 23: at least 50 M visits/s): the stored visits of a regroupable
// capture's frames, held decoded in memory, regrouped by RayRegrouper into each SPEC given,
// timed on the wall clock; best of REPEATS runs per SPEC, the decode timed once beside it
// for comparison. Fine visits per second count the visits read (the capture's, empty cells'
// included).
//
// Usage: bench_regroup_speed CAPTURE [REPEATS=5] [SPEC...]   (default SPECs: 3x3x3
//        kd:27:footprint octree:256KiB dynamic:27)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "base/check.h"
#include "traces/regroup.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

int Main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_regroup_speed CAPTURE [REPEATS=5] [SPEC...]\n");
    return 2;
  }
  const std::string capture = argv[1];
  const int repeats = argc > 2 ? std::max(1, std::atoi(argv[2])) : 5;
  std::vector<std::string> specs;
  for (int i = 3; i < argc; ++i) specs.push_back(argv[i]);
  if (specs.empty()) specs = {"3x3x3", "kd:27:footprint", "octree:256KiB", "dynamic:27"};

  const TraceReader stored = TraceReader::OpenStored(capture);
  std::vector<std::vector<RayBatch>> frames(stored.frames().size());
  std::uint64_t visits = 0;
  auto t0 = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < frames.size(); ++i) {
    stored.ForEachBatch(i, [&](const RayBatch& b) {
      frames[i].push_back(b);
      visits += b.visit_count();
    });
  }
  const double decode = Seconds(t0);
  std::printf("capture %s: %zu frames, %llu stored visits; decode %.3f s (%.1f M visits/s)\n",
              capture.c_str(), frames.size(), static_cast<unsigned long long>(visits), decode,
              visits / decode / 1e6);
  std::printf("%-18s %8s %12s %10s %14s\n", "spec", "cells", "visits out", "best s",
              "M fine visits/s");
  for (const std::string& spec : specs) {
    // The view's maps: one per frame (the same for a static subdivision).
    const TraceReader view = TraceReader::Open(capture, spec);
    // RayRegrouper alone on the decoded batches, then the view's ForEachBatch (decoding and
    // regrouping as analyses read).
    double best = 1e300, best_view = 1e300;
    std::uint64_t out_visits = 0;
    for (int r = 0; r < repeats; ++r) {
      out_visits = 0;
      t0 = std::chrono::steady_clock::now();
      for (std::size_t i = 0; i < frames.size(); ++i) {
        RayRegrouper regrouper(view.CellMap(i));
        for (const RayBatch& b : frames[i]) out_visits += regrouper.Regroup(b).visit_count();
      }
      best = std::min(best, Seconds(t0));
      t0 = std::chrono::steady_clock::now();
      for (std::size_t i = 0; i < frames.size(); ++i) view.ForEachBatch(i, [](const RayBatch&) {});
      best_view = std::min(best_view, Seconds(t0));
    }
    std::printf("%-18s %8u %12llu %10.4f %14.1f   (read + regroup: %.1f M/s)\n", spec.c_str(),
                view.header().cell_count(), static_cast<unsigned long long>(out_visits), best,
                visits / best / 1e6, visits / best_view / 1e6);
  }
  return 0;
}

}  // namespace
}  // namespace raycell

int main(int argc, char** argv) {
  try {
    return raycell::Main(argc, argv);
  } catch (const raycell::InputError& e) {
    std::fprintf(stderr, "bench_regroup_speed: %s\n", e.what());
    return 2;
  }
}
