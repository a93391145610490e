#include "search/best_schedule.h"

#include <algorithm>
#include <optional>
#include <sstream>

#include "base/check.h"
#include "base/parallel.h"
#include "graph/forest.h"
#include "graph/peel.h"
#include "graph/schedule.h"
#include "search/beam_search.h"
#include "search/optimum.h"
#include "search/search_util.h"

namespace raycell {

std::string BestScheduleResult::ToString() const {
  std::ostringstream s;
  s << length << " (" << method << "; Peel " << peel_length;
  if (two_level_length) s << ", two-level " << two_level_length;
  if (beam_length) s << ", beam " << beam_length;
  if (local_length) s << ", local search " << local_length;
  s << ", bound " << bound << ", lower " << lower << (optimal ? ", optimal" : "") << ")";
  return s.str();
}

namespace {

// The seed of chain `i`: distinct per chain, fixed by the options' seed.
std::uint64_t ChainSeed(std::uint64_t seed, std::size_t i) {
  return MixBits(seed ^ MixBits(0x6c6e73ULL + i));
}

// Chain i's options: o.local with its own seed and, when o.vary_windows, its window lengths
// shifted by -4, -2, 0, +2 entries (chains 0, 1, 2, 3, then again), the longest solved
// exactly, and large windows (LocalSearchOptions::large_every) in the odd chains only: the
// chains then fall into different local optima, and the best of them is taken. On the
// 27-cell study capture (24 frames) four chains without large windows gave 87.08 on average,
// four with them 86.67 (11 frames shorter, 2 longer), this portfolio 86.67 (10 shorter, none
// longer) for less work: the even chains end at their window limit, the odd ones at their
// work limit.
LocalSearchOptions ChainOptions(const BestScheduleOptions& o, std::size_t i) {
  LocalSearchOptions lo = o.local;
  lo.seed = ChainSeed(o.seed, i);
  if (o.vary_windows) {
    const long shift = 2 * long(i % 4) - 4;
    lo.min_window = std::size_t(std::max<long>(1, long(lo.min_window) + shift));
    lo.max_window = std::size_t(std::max<long>(long(lo.min_window), long(lo.max_window) + shift));
    if (o.local.exact_window >= o.local.max_window) lo.exact_window = lo.max_window;
    if (i % 2 == 0) lo.large_every = 0;  // the odd chains keep o.local's
  }
  return lo;
}

// Runs the local-search chains, `threads` at a time; results in chain order.
std::vector<LocalSearchResult> RunChains(const CellForest& forest, const std::vector<CellId>& start,
                                         const BestScheduleOptions& o) {
  std::vector<LocalSearchResult> results(o.chains);
  const unsigned threads = o.threads ? unsigned(std::min(o.threads, o.chains)) : HardwareThreads();
  ParallelFor(o.chains, threads, [&](std::size_t i) {
    LocalSearchOptions lo = ChainOptions(o, i);
    lo.lower_bound = std::max(lo.lower_bound, o.lower_bound);
    lo.late_lower_bound = o.late_lower_bound;
    results[i] = ImproveSchedule(forest, start, lo);
  });
  return results;
}

// OptimumResult::ToString without the schedule and the wall time (not reproducible).
std::string Status(const OptimumResult& r) {
  std::ostringstream s;
  s << ToString(r.status);
  if (r.status == OptimumResult::kOptimal) s << " " << r.length;
  if (r.status == OptimumResult::kUnknown) s << " in [" << r.lower << ", " << r.upper << "]";
  s << " (" << r.states_expanded << " states): " << r.reason;
  return s.str();
}

class Best {
 public:
  Best(const CellTree& tree, const BestScheduleOptions& o) : tree_(tree), o_(o) {}

  BestScheduleResult Run() {
    out_.bound = Bound(tree_);
    out_.lower = std::max<std::uint64_t>(out_.bound, o_.lower_bound);
    const PeelResult peel = Peel(tree_);
    out_.peel_length = peel.schedule.size();
    Offer(peel.schedule, "peel");
    if (!Done() && o_.beam_width > 0 && BeamIsCut(peel.schedule.size())) RunTwoLevel();
    // The forest only for the searches that run on it (it costs about as much as the tree).
    std::optional<CellForest> forest;
    const auto forest_of_tree = [&]() -> const CellForest& {
      if (!forest) forest = CellForest::FromTree(tree_);
      return *forest;
    };
    if (!Done() && o_.beam_width > 0) RunBeam(forest_of_tree());
    // Small trees: the exact search first, which often proves the beam's schedule optimal;
    // if it does not, once more after the local search, with its (maybe shorter) schedule.
    const bool exact = o_.exact_states > 0 && tree_.node_count() <= o_.exact_max_nodes;
    if (exact) WaitForLateBound();  // the exact search prunes with it
    if (!Done() && exact) RunExact();
    const std::size_t before = out_.schedule.size();
    if (!Done() && o_.chains > 0) RunLocal(forest_of_tree());
    if (!Done() && exact && out_.schedule.size() < before) RunExact();
    WaitForLateBound();
    out_.length = out_.schedule.size();
    out_.optimal = out_.lower >= out_.length;
    RAYCELL_CHECK(IsFeasible(tree_, out_.schedule));
    RAYCELL_CHECK_LE(out_.lower, out_.length);
    return std::move(out_);
  }

 private:
  // Whether the best schedule meets a lower bound. With a late bound this depends on when it
  // arrives; so it may only decide whether to go on looking, never what is kept.
  bool Done() const {
    return out_.schedule.size() <= std::max(out_.lower, KnownNow(o_.late_lower_bound));
  }

  void WaitForLateBound() {
    if (o_.late_lower_bound) out_.lower = std::max(out_.lower, o_.late_lower_bound->Wait());
  }

  // Keeps `schedule` if it is shorter than the best so far (the first one always). Its
  // feasibility is checked once, on the schedule kept at the end of Run (a run over the whole
  // tree: on a union of millions of nodes each such check cost 1.3% of a replay's CPU).
  void Offer(const std::vector<CellId>& schedule, const std::string& method) {
    if (!out_.method.empty() && schedule.size() >= out_.schedule.size()) return;
    out_.schedule = schedule;
    out_.method = method;
  }

  void RunBeam(const CellForest& forest) {
    BeamOptions bo;
    bo.width = o_.beam_width;
    bo.max_node_visits = o_.beam_max_node_visits;
    const BeamResult r = BeamSearch(forest, bo);
    out_.beam_length = r.schedule.size();
    out_.beam_states = r.states;
    out_.work += r.node_visits;
    Offer(r.schedule, "beam(" + std::to_string(o_.beam_width) + ")");
  }

  // Whether the beam's nominal work on the whole tree, about width x layers (Peel's length at
  // most) x nodes, exceeds its limit, so that it would narrow its width: then the two-level
  // schedule is worth its cost (coarse_of given).
  bool BeamIsCut(std::size_t peel_length) const {
    if (o_.coarse_of.empty()) return false;
    const double work = double(o_.beam_width) * double(peel_length) * double(tree_.node_count());
    return work > double(o_.beam_max_node_visits);
  }

  // The two-level schedule: a beam search of the tree contracted to the coarse cells, then one
  // of each entry's forest; each search gets a share of beam_max_node_visits in proportion to
  // its nodes (at least one visit), so the whole costs about one beam budget.
  void RunTwoLevel() {
    const double nodes = double(std::max<std::size_t>(tree_.node_count(), 1));
    const auto plan = [this, nodes](const CellTree& t) {
      if (t.node_count() == 0) return std::vector<CellId>{};
      BeamOptions bo;
      bo.width = o_.beam_width;
      bo.max_node_visits = std::max<std::uint64_t>(
          1, std::uint64_t(double(o_.beam_max_node_visits) * double(t.node_count()) / nodes));
      const BeamResult r = BeamSearch(CellForest::FromTree(t), bo);
      out_.work += r.node_visits;
      return r.schedule;
    };
    std::vector<CellId> coarse_of = o_.coarse_of;
    coarse_of.resize(tree_.cell_count(), CellId(0));  // cells past the map: never in the tree
    const std::vector<CellId> s = TwoLevelSchedule(tree_, coarse_of, plan, plan);
    out_.two_level_length = s.size();
    Offer(s, "2level-beam(" + std::to_string(o_.beam_width) + ")");
  }

  void RunLocal(const CellForest& forest) {
    const std::vector<LocalSearchResult> chains = RunChains(forest, out_.schedule, o_);
    const std::string method = out_.method + "+lns(" + std::to_string(o_.chains) + "x" +
                               std::to_string(o_.local.max_windows) + ")";
    const LocalSearchResult* best = &chains[0];
    for (const LocalSearchResult& c : chains) {
      out_.windows += c.windows;
      out_.large_windows += c.large_windows;
      out_.work += c.work;
      if (c.schedule.size() < best->schedule.size()) best = &c;
    }
    out_.local_length = best->schedule.size();
    Offer(best->schedule, method);
  }

  void RunExact() {
    OptimumOptions eo;
    eo.incumbent = out_.schedule;
    eo.lower_bound = out_.lower;
    eo.limits.max_states = o_.exact_states;
    eo.limits.max_seconds = 1e30;  // limited by states only
    eo.limits.max_nodes = o_.exact_max_nodes;
    const OptimumResult r = ExactOptimum(tree_, eo);
    out_.exact_states += r.states_expanded;
    out_.exact_status = Status(r);
    if (r.status == OptimumResult::kTooLarge) return;
    out_.lower = std::max(out_.lower, r.lower);
    if (r.status == OptimumResult::kOptimal) Offer(r.schedule, out_.method + "+exact");
  }

  const CellTree& tree_;
  const BestScheduleOptions o_;
  BestScheduleResult out_;
};

}  // namespace

BestScheduleResult BestSchedule(const CellTree& tree, const BestScheduleOptions& options) {
  return Best(tree, options).Run();
}

}  // namespace raycell
