// Per-segment replay speed: the batch core (replay/replayer.cpp) against the reference it
// replaced (tests/oracle/reference_replayer.cpp: one engine event per unit through the
// Simulator's event queue), on the frames of a capture, for configurations that replay per
// ray segment (more than one processor). Each frame is decoded and its work graph built
// once, untimed; only ReplayFrame is timed, in CPU time of this thread (which a loaded,
// shared machine disturbs far less than wall time). The two cores run in turn on every
// frame, REPS times; the median of the per-rep totals is printed, and the results of the two
// are checked equal.
//
// It compiles the reference it measures against from the replay's oracle (tests/oracle/:
// test-only code, which tools/bench/ alone may include); not run by the tests.
//
// With --core-only the reference is not run: each frame is replayed REPS times in a row, as a
// sweep replays its configurations on a frame it decoded once, and between the replays the
// frame's records stay warm in the caches, where alternating with the reference evicts them.
//
// Usage: build/tools/bench_replay_core TRACE [FRAMES=all] [REPS=3] [CASE=all|-1]
//            [--core-only]
// CASE numbers the configurations in Cases()' order, from 0.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "base/check.h"
#include "base/cpu_time.h"
#include "graph/frame_tree.h"
#include "replay/config.h"
#include "replay/replayer.h"
#include "replay/work.h"
#include "scheduling/scheduler.h"
#include "tests/oracle/reference_replayer.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

struct Frame {
  std::size_t index;
  std::unique_ptr<CellTree> tree, previous;
  WorkGraph work;
};

struct Case {
  std::string label;
  ReplayConfig config;
};

std::vector<Case> Cases() {
  std::vector<Case> cases;
  const auto add = [&](const std::string& label, const std::string& scheduler, int processors,
                       const char* capacity, bool prefetch) {
    ReplayConfig c = DefaultConfig();
    ApplyOverride(c, "scheduler", scheduler);
    ApplyOverride(c, "processors.count", std::to_string(processors));
    ApplyOverride(c, "level.cache.capacity", capacity);
    ApplyOverride(c, "processors.prefetch", prefetch ? "true" : "false");
    ApplyOverride(c, "granularity", "ray");
    cases.push_back({label, c});
  };
  add("celltree, 1 processor, 1 cell", "celltree", 1, "1 cell", false);
  add("celltree, 2 processors, 2 cells", "celltree", 2, "2 cells", false);
  add("maxwork, 4 processors, 4 cells, prefetch", "maxwork", 4, "4 cells", true);
  add("random, 8 processors, 2 cells", "random", 8, "2 cells", false);
  // Case 0 on eight processors: the core's cost of parallelism with the same scheduler.
  add("celltree, 8 processors, 1 cell", "celltree", 8, "1 cell", false);
  // Tens of processors (issue 43): Max Work's segments per second at 64 processors against
  // one, on a capture of hundreds of cells (case 6 / case 5); and case 0 on 64 processors.
  add("maxwork, 1 processor, 1 cell", "maxwork", 1, "1 cell", false);
  add("maxwork, 64 processors, 1 cell", "maxwork", 64, "1 cell", false);
  add("celltree, 64 processors, 1 cell", "celltree", 64, "1 cell", false);
  return cases;
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace
}  // namespace raycell

int main(int argc, char** argv) {
  using namespace raycell;
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: bench_replay_core TRACE [FRAMES=all] [REPS=3] [CASE=all|-1] "
                 "[--core-only]\n");
    return 2;
  }
  try {
    const TraceReader reader = TraceReader::Open(argv[1]);
    std::size_t frames = reader.frames().size();
    if (argc > 2 && std::string(argv[2]) != "all") {
      char* end = nullptr;
      const unsigned long long n = std::strtoull(argv[2], &end, 10);
      if (end == argv[2] || *end != '\0' || n == 0) {
        throw std::invalid_argument(std::string("FRAMES must be a positive count or 'all', not '") +
                                    argv[2] + "'");
      }
      frames = std::min<std::size_t>(frames, n);
    }
    const int reps = argc > 3 ? std::max(1, std::atoi(argv[3])) : 3;
    const int only = argc > 4 ? std::atoi(argv[4]) : -1;  // one configuration, by number
    const bool core_only = argc > 5 && std::string(argv[5]) == "--core-only";
    if (argc > 5 && !core_only) {
      throw std::invalid_argument(std::string("unknown argument '") + argv[5] +
                                  "' (expected --core-only)");
    }
    const TraceHeader& h = reader.header();
    std::vector<Frame> loaded;
    std::uint64_t segments = 0;
    for (std::size_t i = 0; i < frames; ++i) {
      const RayBatch rays = reader.LoadFrame(i);
      CellTreeBuilder builder;
      builder.AddBatch(rays);
      Frame f{i, std::make_unique<CellTree>(builder.Finish()), nullptr,
              RaySegmentWork(rays, h.cell_count())};
      if (i > 0) f.previous = std::make_unique<CellTree>(BuildFrameTree(reader, i - 1));
      segments += f.work.total_segments();
      loaded.push_back(std::move(f));
    }
    std::printf("%s: %zu frames, %llu segments per replay; CPU seconds, median of %d\n", argv[1],
                frames, (unsigned long long)segments, reps);
    std::printf("%-44s %10s %10s %12s %12s %8s\n", "configuration", "reference", "core",
                "ref Mseg/s", "core Mseg/s", "speed-up");
    const std::vector<Case> cases = Cases();
    for (std::size_t k = 0; k < cases.size(); ++k) {
      if (only >= 0 && std::size_t(only) != k) continue;
      const Case& c = cases[k];
      // Per repetition, summed over the frames. Each frame is replayed REPS times in a row:
      // with --core-only as a sweep replays its configurations on a frame it decoded once
      // (the frame's records stay warm in the caches), else the reference before each core.
      std::vector<double> ref_s(reps, 0.0), core_s(reps, 0.0);
      for (const Frame& f : loaded) {
        const FrameTrees info{f.index, f.tree.get(), f.previous.get(), h.cell_count()};
        for (int r = 0; r < reps; ++r) {
          auto a = core_only ? nullptr : MakeScheduler(*c.config.scheduler, c.config.seed);
          auto b = MakeScheduler(*c.config.scheduler, c.config.seed);
          std::optional<ReplayResult> x;
          const double t0 = ThreadCpuSeconds();
          if (a) x = ReferenceReplayFrame(f.work, h.footprints, c.config, *a, info, Bound(*f.tree));
          const double t1 = ThreadCpuSeconds();
          const ReplayResult y =
              ReplayFrame(f.work, h.footprints, c.config, *b, info, Bound(*f.tree));
          const double t2 = ThreadCpuSeconds();
          if (x) {
            RAYCELL_CHECK_EQ(x->time, y.time);
            RAYCELL_CHECK_EQ(x->fetches, y.fetches);
            RAYCELL_CHECK_EQ(x->events, y.events);
          }
          ref_s[r] += t1 - t0;
          core_s[r] += t2 - t1;
        }
      }
      if (core_only) {
        const double core = Median(core_s);
        std::printf("%-44s %10s %10.3f %12s %12.1f %8s\n", c.label.c_str(), "-", core, "-",
                    double(segments) / core / 1e6, "-");
        continue;
      }
      const double ref = Median(ref_s), core = Median(core_s);
      std::printf("%-44s %10.3f %10.3f %12.1f %12.1f %7.1fx\n", c.label.c_str(), ref, core,
                  double(segments) / ref / 1e6, double(segments) / core / 1e6, ref / core);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_replay_core: %s\n", e.what());
    return 2;
  }
  return 0;
}
