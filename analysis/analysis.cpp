#include "analysis/analysis.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <exception>
#include <utility>

#include "base/check.h"
#include "base/parallel.h"
#include "graph/peel.h"
#include "graph/schedule.h"
#include "search/late_bound.h"
#include "search/optimum.h"

namespace raycell {

BracketOptions BracketEffort(const std::string& name) {
  BracketOptions o;  // "default": the graph/ modules' own defaults
  o.best.threads = 0;
  if (name == "default") return o;
  if (name == "quick") {
    o.lower.triples = false;
    o.lower.max_blocks = 60;
    // 500,000 states in all: raycell study in about two minutes on 2 cores; twice as many give
    // slightly higher bounds for far more time (BENCHMARKS.md "Bracketing the optimum").
    o.lower.max_total_states = 500'000;
    o.lower.max_cut_rounds = 40;
    o.best.beam_width = 64;
    o.best.chains = 2;
    o.best.local.max_windows = 2000;
    o.best.local.max_work = 200'000'000;
    o.best.exact_states = 20000;
    return o;
  }
  if (name == "thorough") {
    o.lower.max_triples *= 4;
    o.lower.max_blocks *= 4;
    o.lower.max_group_states *= 4;
    o.lower.max_total_states *= 4;
    o.lower.max_cut_rounds *= 2;
    o.best.beam_width *= 4;
    o.best.chains *= 2;
    o.best.local.max_windows *= 4;
    o.best.local.max_work *= 4;
    o.best.exact_states *= 10;
    return o;
  }
  throw InputError("--effort '" + name + "': expected quick, default or thorough");
}

std::vector<CellId> BoardCells(const std::array<std::uint32_t, 3>& n) {
  std::vector<CellId> coarse_of;
  if (n[0] == 0 || n[1] == 0 || n[2] == 0) return coarse_of;
  const std::uint32_t bx = (n[0] + 1) / 2, by = (n[1] + 1) / 2;
  for (std::uint32_t z = 0; z < n[2]; ++z) {
    for (std::uint32_t y = 0; y < n[1]; ++y) {
      for (std::uint32_t x = 0; x < n[0]; ++x) {
        coarse_of.push_back(CellId(x / 2 + bx * (y / 2 + by * (z / 2))));
      }
    }
  }
  return coarse_of;
}

std::optional<double> FrameAnalysis::gap() const {
  if (!lower_bound || !best_length) return std::nullopt;
  if (*lower_bound == 0) return 0.0;
  return double(*best_length - *lower_bound) / double(*lower_bound);
}

namespace {

// The lower bound and the schedule search told of it (it stops when a schedule meets it):
// with options.overlap the bound on a thread of its own while the search runs, which gives
// the same results (search/late_bound.h) in about the longer of the two times.
std::pair<LowerBoundResult, BestScheduleResult> BoundAndSearch(const CellTree& tree,
                                                               const BracketOptions& options) {
  BestScheduleOptions best = options.best;
  if (best.coarse_of.empty()) best.coarse_of = BoardCells(options.lower.grid);
  if (!options.overlap) {
    LowerBoundResult lb = LowerBound(tree, options.lower);
    best.lower_bound = std::max(best.lower_bound, lb.value);
    return {std::move(lb), BestSchedule(tree, best)};
  }
  LateBound late;
  LowerBoundResult lb;
  Background bound([&] {
    try {
      lb = LowerBound(tree, options.lower);
    } catch (...) {
      late.Publish(0);
      throw;
    }
    late.Publish(lb.value);
  });
  best.late_lower_bound = &late;
  BestScheduleResult b = BestSchedule(tree, best);  // on a throw, ~Background joins the bound
  bound.Join();                                     // rethrows the bound's exception
  return {std::move(lb), std::move(b)};
}

// Brackets the optimum of `tree`: the lower bound and the schedule search. A proved optimum
// (a.optimum, from --exact) tightens both sides.
void Bracket(const CellTree& tree, const BracketOptions& options,
             const std::vector<CellId>& optimal_schedule, FrameAnalysis& a) {
  auto [lb, b] = BoundAndSearch(tree, options);
  RAYCELL_CHECK(IsFeasible(tree, b.schedule));
  std::uint64_t lower = std::max<std::uint64_t>(lb.value, b.lower);
  a.lower_bound_method = lb.value >= b.lower ? lb.method : "exact search";
  a.best_schedule = std::move(b.schedule);
  a.best_method = b.method;
  if (a.optimum && *a.optimum < a.best_schedule.size()) {  // --exact found a shorter one
    a.best_schedule = optimal_schedule;
    a.best_method = "exact search";
  }
  if (a.optimum && *a.optimum > lower) {
    lower = *a.optimum;
    a.lower_bound_method = "exact search";
  }
  RAYCELL_CHECK_LE(Bound(tree), lower);
  RAYCELL_CHECK_LE(lower, a.best_schedule.size());
  a.lower_bound = lower;
  a.best_length = a.best_schedule.size();
  if (lower == a.best_schedule.size() && !a.optimum) {
    a.optimum = lower;
    a.optimum_status = "optimal (the best schedule meets the lower bound)";
  }
}

}  // namespace

FrameAnalysis AnalyzeTree(const CellTree& tree, const AnalyzeOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  FrameAnalysis a;
  a.rays = tree.rays();
  a.nodes = tree.node_count();
  a.bound = Bound(tree);
  PeelResult peel = Peel(tree);
  a.peel_schedule = std::move(peel.schedule);
  a.splits = peel.split_peels;
  std::vector<CellId> optimal_schedule;  // from the exact search, when it proves one
  if (options.exact) {
    OptimumLimits limits;
    limits.max_states = options.max_states;
    limits.max_seconds = options.max_seconds;
    limits.max_nodes = options.max_nodes;
    OptimumResult r = ExactOptimum(tree, limits);
    if (r.status == OptimumResult::kOptimal) {
      a.optimum = r.length;
      a.optimum_status = "optimal";
      optimal_schedule = std::move(r.schedule);
    } else {
      a.optimum_status =
          (r.status == OptimumResult::kTooLarge ? "too large: " : "unknown: ") + r.reason;
    }
  }
  if (options.bracket) Bracket(tree, options.bracket_options, optimal_schedule, a);
  a.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return a;
}

}  // namespace raycell
