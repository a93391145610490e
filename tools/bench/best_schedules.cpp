// Schedules better than Peel (search/best_schedule.h), frame by frame: the maxGen bound,
// Peel, the beam search, beam + local search, the exact search's status, time, work and
// peak memory. Each frame runs in a child process, so its peak resident memory is its own.
//
// Usage:
//   bench_best_schedules CAPTURE.rct [options]     every frame of a capture
//   bench_best_schedules --synthetic [options]     random trees of 10^3 .. 10^5 nodes
// Options (defaults: BestScheduleOptions'):
//   --frames A-B,C      frame indices to run (into the capture's frames; default all)
//   --width N           beam width          --chains N     local-search chains
//   --windows N         windows per chain   --threads N    chains at once
//   --max-work N        node visits per chain (LocalSearchOptions::max_work)
//   --min-window N, --max-window N, --exact-window N, --kick-after N, --kick-size N,
//   --large-every N (0: no large windows), --large-min N, --large-max N
//                       local search (LocalSearchOptions)
//   --exact-states N    exact search states --seed N
//   --cells N           cells of the synthetic trees (27)
//   --max-nodes N       largest synthetic tree (100000)
//   --schedules         also print each best schedule
//   --plan-effort       the budget of the online schedulers' plans (scheduling/
//                       best_scheduler.h PlanEffort, fitted to each tree) instead: the
//                       planning time per frame
//   --union             the tree of each frame f >= 1 is the union of frames f-1 and f
//                       (graph/cell_tree.h UnionTree), as celltree-union plans
//   --exact-compare     instead: the exact search per frame (Peel as incumbent) with the
//                       maxGen heuristic alone (the search before the pair heuristic) and
//                       with pairs, --exact-states states each: status and states expanded
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "analysis/analysis.h"
#include "base/check.h"
#include "base/cpu_time.h"
#include "base/parse.h"
#include "graph/frame_tree.h"
#include "graph/peel.h"
#include "scheduling/best_scheduler.h"
#include "search/best_schedule.h"
#include "search/optimum.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

struct Args {
  std::string capture;
  bool synthetic = false, schedules = false, exact_compare = false, plan_effort = false;
  bool union_frames = false;  // the union of frames f-1 and f (celltree-union's plans)
  std::vector<int> frames;    // empty: all
  BestScheduleOptions options;
  std::uint32_t cells = 27;
  std::size_t max_nodes = 100000;
};

// One frame's figures, passed from the child process through a pipe.
struct Row {
  std::uint64_t nodes, bound, peel, beam, local, best, lower;
  bool optimal;
  double seconds, cpu_seconds;  // wall; CPU of every thread (less sensitive to the load)
  std::uint64_t beam_states, windows, work, exact_states;
  char exact[96];
};

Args Parse(int argc, char** argv) {
  Args a;
  auto value = [&](int& i) {
    if (i + 1 >= argc) throw InputError(std::string(argv[i]) + ": expected a value");
    return std::string(argv[++i]);
  };
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto number = [&] { return ParseUint(value(i), arg); };
    if (arg == "--synthetic") {
      a.synthetic = true;
    } else if (arg == "--union") {
      a.union_frames = true;
    } else if (arg == "--plan-effort") {
      a.plan_effort = true;
    } else if (arg == "--schedules") {
      a.schedules = true;
    } else if (arg == "--exact-compare") {
      a.exact_compare = true;
    } else if (arg == "--frames") {
      for (const std::string& part : Split(value(i), ',')) {
        for (int f : ParseFrameRange(part, arg)) a.frames.push_back(f);
      }
    } else if (arg == "--width") {
      a.options.beam_width = number();
    } else if (arg == "--chains") {
      a.options.chains = number();
    } else if (arg == "--max-work") {
      a.options.local.max_work = number();
    } else if (arg == "--windows") {
      a.options.local.max_windows = number();
    } else if (arg == "--min-window") {
      a.options.local.min_window = number();
    } else if (arg == "--max-window") {
      a.options.local.max_window = number();
    } else if (arg == "--exact-window") {
      a.options.local.exact_window = number();
    } else if (arg == "--kick-after") {
      a.options.local.kick_after = number();
    } else if (arg == "--kick-size") {
      a.options.local.kick_size = number();
    } else if (arg == "--large-every") {
      a.options.local.large_every = number();
    } else if (arg == "--large-min") {
      a.options.local.large_min = number();
    } else if (arg == "--large-max") {
      a.options.local.large_max = number();
    } else if (arg == "--threads") {
      a.options.threads = number();
    } else if (arg == "--exact-states") {
      a.options.exact_states = number();
    } else if (arg == "--seed") {
      a.options.seed = number();
    } else if (arg == "--cells") {
      a.cells = std::uint32_t(number());
    } else if (arg == "--max-nodes") {
      a.max_nodes = number();
    } else if (!arg.empty() && arg[0] != '-' && a.capture.empty()) {
      a.capture = arg;
    } else {
      throw InputError("unknown argument " + arg);
    }
  }
  if (a.capture.empty() && !a.synthetic) throw InputError("expected a capture or --synthetic");
  if (a.plan_effort) a.options = PlanEffort(a.options.seed);
  return a;
}

Row Measure(const CellTree& tree, const Args& a) {
  Row r{};
  const auto t0 = std::chrono::steady_clock::now();
  const double cpu0 = ProcessCpuSeconds();
  const BestScheduleResult b =
      BestSchedule(tree, a.plan_effort ? PlanEffort(a.options.seed, tree) : a.options);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.cpu_seconds = ProcessCpuSeconds() - cpu0;
  r.nodes = tree.node_count(), r.bound = b.bound, r.peel = b.peel_length;
  r.beam = b.beam_length, r.local = b.local_length, r.best = b.length, r.lower = b.lower;
  r.optimal = b.optimal;
  r.beam_states = b.beam_states, r.windows = b.windows, r.work = b.work;
  r.exact_states = b.exact_states;
  std::snprintf(r.exact, sizeof r.exact, "%s", b.exact_status.c_str());
  if (a.schedules) {
    std::printf("  schedule:");
    for (CellId c : b.schedule) std::printf(" %u", c.value());
    std::printf("\n");
    std::fflush(stdout);
  }
  return r;
}

// Runs `make` (which builds a tree) and Measure in a child process; the child's peak
// resident memory in MiB.
template <typename Make>
Row InChild(const Make& make, const Args& a, double& peak_mib) {
  int fds[2];
  RAYCELL_CHECK(pipe(fds) == 0);
  std::fflush(stdout);
  const pid_t pid = fork();
  RAYCELL_CHECK(pid >= 0);
  if (pid == 0) {
    close(fds[0]);
    const Row r = Measure(make(), a);
    RAYCELL_CHECK(write(fds[1], &r, sizeof r) == ssize_t(sizeof r));
    std::fflush(stdout);
    _exit(0);
  }
  close(fds[1]);
  Row r{};
  RAYCELL_CHECK(read(fds[0], &r, sizeof r) == ssize_t(sizeof r));
  close(fds[0]);
  int status = 0;
  rusage usage{};
  RAYCELL_CHECK(wait4(pid, &status, 0, &usage) == pid && WIFEXITED(status) &&
                WEXITSTATUS(status) == 0);
  peak_mib = double(usage.ru_maxrss) / 1024;
  return r;
}

const char* kHeader =
    "frame   nodes bound  peel  beam   lns  best lower  best/peel  seconds    cpu s  peak MiB  "
    "beam states   windows        work  exact\n";

void Print(const std::string& label, const Row& r, double peak) {
  std::printf(
      "%5s %7llu %5llu %5llu %5llu %5llu %5llu %5llu %10.3f %8.2f %8.2f %9.1f %12llu %9llu %11.3g  "
      "%s\n",
      label.c_str(), (unsigned long long)r.nodes, (unsigned long long)r.bound,
      (unsigned long long)r.peel, (unsigned long long)r.beam, (unsigned long long)r.local,
      (unsigned long long)r.best, (unsigned long long)r.lower, double(r.best) / r.peel, r.seconds,
      r.cpu_seconds, peak, (unsigned long long)r.beam_states, (unsigned long long)r.windows,
      double(r.work), r.exact);
  std::fflush(stdout);
}

std::string Exact(const OptimumResult& r) {
  char text[96];
  if (r.status == OptimumResult::kOptimal) {
    std::snprintf(text, sizeof text, "optimal %llu in %llu states", (unsigned long long)r.length,
                  (unsigned long long)r.states_expanded);
  } else {
    std::snprintf(text, sizeof text, "[%llu, %llu] after %llu states", (unsigned long long)r.lower,
                  (unsigned long long)r.upper, (unsigned long long)r.states_expanded);
  }
  return text;
}

int ExactCompare(const TraceReader& reader, const std::vector<int>& frames, const Args& a) {
  std::printf(
      "%s: exact search, Peel as incumbent, %llu states at most\n%5s %7s %5s %5s  %-36s %s\n",
      a.capture.c_str(), (unsigned long long)a.options.exact_states, "frame", "nodes", "bound",
      "peel", "maxGen heuristic", "pair heuristic");
  int proved_old = 0, proved_new = 0;
  for (const int f : frames) {
    const CellTree tree = BuildFrameTree(reader, std::size_t(f));
    OptimumOptions o;
    o.limits.max_states = a.options.exact_states;
    o.limits.max_seconds = 1e30;
    o.limits.max_nodes = 1'000'000;
    o.pair_heuristic = false;
    const OptimumResult old = ExactOptimum(tree, o);
    o.pair_heuristic = true;
    const OptimumResult now = ExactOptimum(tree, o);
    proved_old += old.status == OptimumResult::kOptimal;
    proved_new += now.status == OptimumResult::kOptimal;
    std::printf("%5d %7zu %5llu %5zu  %-36s %s\n", reader.frames()[f].frame, tree.node_count(),
                (unsigned long long)Bound(tree), Peel(tree).schedule.size(), Exact(old).c_str(),
                Exact(now).c_str());
    std::fflush(stdout);
  }
  std::printf("proved optimal: %d of %zu frames with the maxGen heuristic, %d with pairs\n",
              proved_old, frames.size(), proved_new);
  return 0;
}

int Capture(const Args& a) {
  const TraceReader reader = TraceReader::Open(a.capture);
  std::vector<int> frames = a.frames;
  if (frames.empty()) {
    for (std::size_t f = 0; f < reader.frames().size(); ++f) frames.push_back(int(f));
  }
  for (const int f : frames) {
    if (std::size_t(f) >= reader.frames().size()) {
      throw InputError("--frames: frame index " + std::to_string(f) + " past the capture's " +
                       std::to_string(reader.frames().size()) + " frames");
    }
  }
  if (a.exact_compare) return ExactCompare(reader, frames, a);
  std::printf("%s: %zu frames\n%s", a.capture.c_str(), frames.size(), kHeader);
  double peel = 0, best = 0, lower = 0, ratio = 0, gap = 0, seconds = 0, peak_max = 0;
  int n = 0, optimal = 0;
  for (const int f : frames) {
    double peak = 0;
    if (a.union_frames && f == 0) continue;  // no frame before it
    const Row r = InChild(
        [&] {
          if (!a.union_frames) return BuildFrameTree(reader, std::size_t(f));
          const CellTree before = BuildFrameTree(reader, std::size_t(f - 1));
          const CellTree tree = BuildFrameTree(reader, std::size_t(f));
          return UnionTree({&before, &tree});
        },
        a, peak);
    Print(std::to_string(reader.frames()[f].frame), r, peak);
    ++n, peel += r.peel, best += r.best, lower += r.lower, seconds += r.seconds;
    ratio += double(r.best) / r.peel, gap += double(r.best - r.lower) / r.lower;
    optimal += r.optimal, peak_max = std::max(peak_max, peak);
  }
  if (n == 0) return 0;
  std::printf(
      "mean over %d frames: Peel %.2f, best %.2f, lower %.2f; best/Peel %.4f (%.1f%% shorter); "
      "gap (best-lower)/lower %.2f%%; %d proved optimal; %.2f s per frame; peak %.1f MiB\n",
      n, peel / n, best / n, lower / n, ratio / n, 100 * (1 - ratio / n), 100 * gap / n, optimal,
      seconds / n, peak_max);
  return 0;
}

// Random ray trees as in bench/cell_tree_scaling.cpp: a primary ray and 0-4 spawned rays,
// each a random walk of 1-8 visits over `cells` cells, until the tree has `target` nodes.
CellTree Synthetic(std::size_t target, std::uint32_t cells, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  CellTreeBuilder builder;
  RayBatch batch(false);
  RayId next = 0;
  auto add_ray = [&](RayKind kind, RayId parent, std::uint32_t spawn, CellId first) {
    batch.BeginRay(kind, parent, spawn, 0, 0);
    CellId prev = first;
    batch.AddVisit(prev, 1, 0, 0);
    for (std::uint64_t v = 1 + rng() % 8; v > 1; --v) {
      CellId c;
      do c = CellId(rng() % cells);
      while (c == prev);
      batch.AddVisit(prev = c, 1, 0, 0);
    }
    return next++;
  };
  while (builder.node_count() < target) {
    batch.Clear();
    batch.set_first_id(next);
    for (int i = 0; i < 64 && builder.node_count() < target; ++i) {
      const RayId p = add_ray(RayKind::kPrimary, kNoParent, 0, CellId(rng() % cells));
      const std::size_t b = batch.visit_begin(p - batch.first_id());
      const std::size_t pv = batch.visit_end(p - batch.first_id()) - b;
      for (std::uint64_t k = rng() % 5; k > 0; --k) {
        const auto spawn = std::uint32_t(rng() % pv);
        add_ray(RayKind::kShadow, p, spawn, batch.cells()[b + spawn]);
      }
    }
    builder.AddBatch(batch);
  }
  return builder.Finish();
}

int SyntheticRuns(const Args& a) {
  std::printf("synthetic random trees, %u cells\n%s", a.cells, kHeader);
  for (std::size_t target = 1000; target <= a.max_nodes; target *= 10) {
    for (std::size_t t : {target, 3 * target}) {
      if (t > a.max_nodes) break;
      double peak = 0;
      const Row r = InChild([&] { return Synthetic(t, a.cells, a.options.seed); }, a, peak);
      Print(std::to_string(t), r, peak);
    }
  }
  return 0;
}

int Main(int argc, char** argv) {
  try {
    const Args a = Parse(argc, argv);
    return a.synthetic ? SyntheticRuns(a) : Capture(a);
  } catch (const InputError& e) {
    std::fprintf(stderr, "bench_best_schedules: %s\n", e.what());
    return 2;
  }
}

}  // namespace
}  // namespace raycell

int main(int argc, char** argv) { return raycell::Main(argc, argv); }
