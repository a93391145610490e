// Lower bounds per frame of a trace: maxGen, then the bound after each stage of LowerBound
// (pairs matching, the program with pairs and triples, + blocks, + cuts), with the time of
// each stage, the states searched, the Peel length (an upper bound) and the process's peak
// memory so far. The cell grid comes from the trace header.
//
// Usage: bench_lower_bounds TRACE [FRAMES=all] [MAX_TOTAL_STATES] [MAX_GROUP_STATES]
//   FRAMES as "0..23", "5" or "all".
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "base/check.h"
#include "base/parse.h"
#include "graph/analysis.h"
#include "graph/lower_bound.h"
#include "graph/peel.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

double PeakMegabytes() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

int Main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: bench_lower_bounds TRACE [FRAMES=all] [MAX_TOTAL_STATES] "
                 "[MAX_GROUP_STATES]\n");
    return 2;
  }
  const TraceReader reader = TraceReader::Open(argv[1]);
  std::vector<int> frames;
  const std::string range = argc > 2 ? argv[2] : "all";
  if (range == "all") {
    for (std::size_t f = 0; f < reader.frames().size(); ++f) frames.push_back(int(f));
  } else {
    frames = ParseFrameRange(range, "FRAMES");
  }
  LowerBoundOptions options;
  options.grid = reader.header().cells;
  if (argc > 3) options.max_total_states = ParseUint(argv[3], "MAX_TOTAL_STATES");
  if (argc > 4) options.max_group_states = ParseUint(argv[4], "MAX_GROUP_STATES");
  std::printf("# %s, grid %ux%ux%u, max_total_states %llu, max_group_states %llu\n", argv[1],
              options.grid[0], options.grid[1], options.grid[2],
              (unsigned long long)options.max_total_states,
              (unsigned long long)options.max_group_states);
  std::printf("%5s %6s %5s %6s", "frame", "nodes", "peel", "maxgen");
  bool header = false;
  for (int f : frames) {
    if (f < 0 || std::size_t(f) >= reader.frames().size()) {
      throw InputError("FRAMES: frame " + std::to_string(f) + " is not in the trace");
    }
    const CellTree tree = BuildFrameTree(reader, std::size_t(f));
    const std::size_t peel = Peel(tree).schedule.size();
    const auto t0 = std::chrono::steady_clock::now();
    const LowerBoundResult r = LowerBound(tree, options);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!header) {
      for (std::size_t i = 1; i < r.stages.size(); ++i) {
        std::printf(" %16s", r.stages[i].name.substr(0, 16).c_str());
      }
      std::printf(" %8s %6s %10s %8s\n", "seconds", "cuts", "states", "peak MB");
      header = true;
    }
    std::printf("%5d %6zu %5zu %6llu", f, tree.node_count(), peel, (unsigned long long)r.max_gen);
    for (std::size_t i = 1; i < r.stages.size(); ++i) {
      std::printf(" %8llu (%5.1fs)", (unsigned long long)r.stages[i].value, r.stages[i].seconds);
    }
    std::printf(" %8.2f %6zu %10llu %8.0f%s\n", s, r.cuts, (unsigned long long)r.states,
                PeakMegabytes(), r.limits_reached ? " limits" : "");
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace
}  // namespace raycell

int main(int argc, char** argv) {
  try {
    return raycell::Main(argc, argv);
  } catch (const raycell::InputError& e) {
    std::fprintf(stderr, "bench_lower_bounds: %s\n", e.what());
    return 2;
  }
}
