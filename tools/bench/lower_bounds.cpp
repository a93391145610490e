// Lower bounds frame by frame (bounds/lower_bound.h): maxGen, then the bound after each stage
// of LowerBound (pairs matching, the program with pairs and triples, + blocks, + cuts), the
// Peel length (an upper bound), search states, cuts, CPU and wall time and peak memory. Each
// frame runs in a child process, so its time and peak resident memory are its own. The cell
// grid comes from the trace header.
//
// Usage:
//   bench_lower_bounds CAPTURE.rct [options]   every frame of a capture
//   bench_lower_bounds --synthetic [options]   random 27-cell trees of 500 .. --max-nodes nodes
// Options (defaults: LowerBoundOptions'):
//   --frames A-B          frame indices to run (default all)
//   --total-states N      max_total_states      --group-states N   max_group_states
//   --cut-states N        max_cut_states        --max-nodes N      largest synthetic tree
//   --effort E            start from BracketEffort(E).lower (quick|default|thorough); give it
//                         before the options it should not override
//   --block-cells N       max_block_cells       --cut-cells N      max_cut_group_cells
//   --merged-parts        merged_parts          --groups           also print every stage
//                                                                  and every group with a gain
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "analysis/analysis.h"
#include "base/check.h"
#include "base/parse.h"
#include "bounds/lower_bound.h"
#include "graph/frame_tree.h"
#include "graph/peel.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

struct Args {
  std::string capture;
  bool synthetic = false;
  std::string frames;
  std::uint64_t max_nodes = 16000;
  bool groups = false;
  LowerBoundOptions options;
};

Args Parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw InputError(k + ": a value is expected");
      return argv[++i];
    };
    if (k == "--synthetic") {
      a.synthetic = true;
    } else if (k == "--frames") {
      a.frames = value();
    } else if (k == "--total-states") {
      a.options.max_total_states = ParseUint(value(), k);
    } else if (k == "--group-states") {
      a.options.max_group_states = ParseUint(value(), k);
    } else if (k == "--cut-states") {
      a.options.max_cut_states = ParseUint(value(), k);
    } else if (k == "--effort") {
      a.options = BracketEffort(value()).lower;
    } else if (k == "--block-cells") {
      a.options.max_block_cells = static_cast<std::uint32_t>(ParseUint(value(), k, 1, 27));
    } else if (k == "--cut-cells") {
      a.options.max_cut_group_cells = ParseUint(value(), k, 1, 27);
    } else if (k == "--merged-parts") {
      a.options.merged_parts = true;
    } else if (k == "--groups") {
      a.groups = true;
    } else if (k == "--max-nodes") {
      a.max_nodes = ParseUint(value(), k, 1);
    } else if (!k.empty() && k[0] != '-' && a.capture.empty()) {
      a.capture = k;
    } else {
      throw InputError("unknown argument '" + k + "'");
    }
  }
  if (a.capture.empty() == !a.synthetic) throw InputError("give a capture or --synthetic");
  return a;
}

// Random ray trees over a 3x3x3 grid: each ray a walk to neighbouring cells (as rays cross
// cells), a primary ray and up to 3 spawned rays per ray tree, until `target` nodes.
CellTree Synthetic(std::size_t target, std::mt19937_64& rng) {
  CellTreeBuilder builder;
  RayBatch batch(false);
  RayId next = 0;
  std::uniform_int_distribution<int> length(2, 9), children(0, 3), axis(0, 2), sign(0, 1);
  auto step = [&](CellId c) {
    int xyz[3] = {int(c.value() % 3), int(c.value() / 3 % 3), int(c.value() / 9)};
    for (;;) {
      const int a = axis(rng), d = sign(rng) ? 1 : -1;
      if (xyz[a] + d < 0 || xyz[a] + d > 2) continue;
      xyz[a] += d;
      return CellId(xyz[0] + 3 * (xyz[1] + 3 * xyz[2]));
    }
  };
  auto add_ray = [&](RayKind kind, RayId parent, std::uint32_t spawn, CellId first) {
    batch.BeginRay(kind, parent, spawn, 0, 0);
    CellId c = first;
    batch.AddVisit(c, 1, 0, 0);
    for (int v = length(rng); v > 1; --v) batch.AddVisit(c = step(c), 1, 0, 0);
    return next++;
  };
  std::uniform_int_distribution<std::uint32_t> cell_number(0, 26);
  const auto cell = [&](auto& r) { return CellId(cell_number(r)); };
  while (builder.node_count() < target) {
    batch.Clear();
    batch.set_first_id(next);
    for (int i = 0; i < 64; ++i) {
      const RayId p = add_ray(RayKind::kPrimary, kNoParent, 0, cell(rng));
      const std::size_t begin = batch.visit_begin(p - batch.first_id());
      const std::size_t visits = batch.visit_end(p - batch.first_id()) - begin;
      for (int k = children(rng); k > 0; --k) {
        const auto spawn = std::uint32_t(rng() % visits);
        add_ray(RayKind::kShadow, p, spawn, batch.cells()[begin + spawn]);
      }
    }
    builder.AddBatch(batch);
  }
  return builder.Finish();
}

double Seconds(const timeval& t) { return double(t.tv_sec) + double(t.tv_usec) * 1e-6; }

// Runs the bound on `tree` in this (child) process and prints one line.
void Row(const std::string& label, const CellTree& tree, const LowerBoundOptions& options,
         bool groups) {
  const std::size_t peel = Peel(tree).schedule.size();
  rusage before{};
  getrusage(RUSAGE_SELF, &before);
  const auto t0 = std::chrono::steady_clock::now();
  const LowerBoundResult r = LowerBound(tree, options);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  rusage after{};
  getrusage(RUSAGE_SELF, &after);
  std::printf("%8s %7zu %5zu %6llu", label.c_str(), tree.node_count(), peel,
              (unsigned long long)r.max_gen);
  // The stages by kind (their names depend on the options: "ip(pairs)" without triples).
  auto kind = [](const std::string& name) {
    if (name == "pairs matching") return 0;
    if (name.rfind("ip(", 0) != 0) return -1;
    if (name.size() > 5 && name.compare(name.size() - 5, 5, "+cuts") == 0) return 3;
    return name.find("blocks") != std::string::npos ? 2 : 1;
  };
  for (int k = 0; k < 4; ++k) {
    unsigned long long v = 0;
    for (const LowerBoundStage& s : r.stages) {
      if (kind(s.name) == k) v = s.value;
    }
    std::printf(" %6llu", v);
  }
  std::printf(" %5llu %6.1f %6.1f %10llu %5zu %7.0f%s\n", (unsigned long long)r.value,
              Seconds(after.ru_utime) - Seconds(before.ru_utime), wall,
              (unsigned long long)r.states, r.cuts, double(after.ru_maxrss) / 1024.0,
              r.limits_reached ? " limits" : "");
  for (const LowerBoundStage& s : r.stages) {
    if (groups)
      std::printf("#   stage %-40s %4llu %10llu states %6.1f s\n", s.name.c_str(),
                  (unsigned long long)s.value, (unsigned long long)s.states, s.seconds);
  }
  for (const GroupBound& g : r.groups) {
    if (!groups) break;
    std::printf("#   group %2zu cells %4u strings maxgen %3u scs >= %3u %s %8llu states:",
                g.cells.size(), g.strings, g.max_gen_sum, g.scs_lower, g.exact ? "exact" : "     ",
                (unsigned long long)g.states);
    for (CellId c : g.cells) std::printf(" %u", c.value());
    std::printf("\n");
  }
  std::fflush(stdout);
}

template <typename F>
void InChild(F fn) {
  std::fflush(stdout);
  const pid_t pid = fork();
  RAYCELL_CHECK(pid >= 0);
  if (pid == 0) {
    try {
      fn();
    } catch (const InputError& e) {
      std::fprintf(stderr, "bench_lower_bounds: %s\n", e.what());
      std::_Exit(2);
    }
    std::fflush(stdout);
    std::_Exit(0);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) throw InputError("a child process failed");
}

int Main(int argc, char** argv) {
  Args a = Parse(argc, argv);
  std::printf("# max_total_states %llu, max_group_states %llu, max_cut_states %llu\n",
              (unsigned long long)a.options.max_total_states,
              (unsigned long long)a.options.max_group_states,
              (unsigned long long)a.options.max_cut_states);
  std::printf("%8s %7s %5s %6s %6s %6s %6s %6s %5s %6s %6s %10s %5s %7s\n", "frame", "nodes",
              "peel", "maxgen", "match", "ip2,3", "+blk", "+cuts", "bound", "cpu s", "wall s",
              "states", "cuts", "peak MB");
  if (a.synthetic) {
    a.options.grid = {3, 3, 3};
    for (std::size_t n = 500; n <= a.max_nodes; n *= 2) {
      InChild([&] {
        std::mt19937_64 rng(n);
        Row(std::to_string(n), Synthetic(n, rng), a.options, a.groups);
      });
    }
    return 0;
  }
  const TraceReader reader = TraceReader::Open(a.capture);
  a.options.grid = reader.header().cells;
  std::vector<int> frames;
  if (a.frames.empty()) {
    for (std::size_t f = 0; f < reader.frames().size(); ++f) frames.push_back(int(f));
  } else {
    frames = ParseFrameRange(a.frames);
  }
  for (int f : frames) {
    if (f < 0 || std::size_t(f) >= reader.frames().size()) {
      throw InputError("--frames: frame " + std::to_string(f) + " is not in the capture");
    }
    InChild([&] {
      Row(std::to_string(f), BuildFrameTree(reader, std::size_t(f)), a.options, a.groups);
    });
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
