#include "search/local_search.h"

#include <algorithm>
#include <sstream>

#include "base/check.h"
#include "search/beam_search.h"
#include "search/optimum.h"
#include "search/search_util.h"

namespace raycell {

std::string LocalSearchResult::ToString() const {
  std::ostringstream s;
  s << schedule.size() << " entries after " << windows << " windows (" << large_windows
    << " large; " << improvements << " shorter, " << plateau_moves << " plateau moves, "
    << deletions << " deletions, " << kicks << " kicks)";
  return s.str();
}

namespace {

using Index = CellForest::Index;

class LocalSearch {
 public:
  LocalSearch(const CellForest& f, std::vector<CellId> schedule, const LocalSearchOptions& o)
      : f_(f), o_(o), timer_(f), rng_(o.seed), schedule_(std::move(schedule)) {
    if (o.min_window < 1 || o.min_window > o.max_window) {
      throw InputError("local search: min_window (" + std::to_string(o.min_window) +
                       ") must be at least 1 and at most max_window (" +
                       std::to_string(o.max_window) + ")");
    }
    if (o.large_every != 0 && (o.large_min < 1 || o.large_min > o.large_max)) {
      throw InputError("local search: large_min (" + std::to_string(o.large_min) +
                       ") must be at least 1 and at most large_max (" +
                       std::to_string(o.large_max) + ")");
    }
  }

  LocalSearchResult Run() {
    RAYCELL_CHECK(timer_.ComputeEarliest(schedule_));
    Retime();
    DeleteIdle();
    out_.schedule = schedule_;
    std::uint64_t since_better = 0;
    while (out_.windows < o_.max_windows && out_.work < o_.max_work &&
           out_.retimes < o_.max_retimes && !Done()) {
      ++out_.windows;
      TryWindow();
      if (schedule_.size() < out_.schedule.size()) {
        out_.schedule = schedule_;
        since_better = 0;
      } else if (o_.kick_after != 0 && ++since_better % o_.kick_after == 0) {
        Kick();
      }
    }
    return std::move(out_);
  }

 private:
  bool Done() const {
    return out_.schedule.size() <=
           std::max<std::uint64_t>({o_.lower_bound, KnownNow(o_.late_lower_bound), 1});
  }

  // Times of the current schedule, and its nodes bucketed by earliest entry.
  void Retime() {
    const ScheduleTimes& t = timer_.Compute(schedule_);
    RAYCELL_CHECK(t.feasible);
    out_.work += f_.size() + schedule_.size();
    ++out_.retimes;
    const std::size_t len = schedule_.size();
    bucket_start_.assign(len + 2, 0);
    for (Index n = 0; n < f_.size(); ++n) ++bucket_start_[t.earliest[n] + 2];
    for (std::size_t i = 2; i < bucket_start_.size(); ++i) bucket_start_[i] += bucket_start_[i - 1];
    by_earliest_.resize(f_.size());
    for (Index n = 0; n < f_.size(); ++n) by_earliest_[bucket_start_[t.earliest[n] + 1]++] = n;
    bucket_start_.pop_back();  // bucket p: by_earliest_[bucket_start_[p] .. bucket_start_[p+1])
  }

  // Deletes entries that no node needs, one at a time, re-timing after each.
  void DeleteIdle() {
    while (out_.retimes < o_.max_retimes) {
      const ScheduleTimes& t = timer_.times();
      needed_.assign(schedule_.size(), false);
      for (Index n = 0; n < f_.size(); ++n) {
        if (t.earliest[n] == t.latest[n]) needed_[t.earliest[n]] = true;
      }
      const auto it = std::find(needed_.begin(), needed_.end(), false);
      if (it == needed_.end()) return;
      schedule_.erase(schedule_.begin() + (it - needed_.begin()));
      ++out_.deletions;
      Retime();
    }
  }

  // The nodes entries i..j-1 must process, increasing.
  std::vector<Index> WindowNodes(std::size_t i, std::size_t j) const {
    const ScheduleTimes& t = timer_.times();
    std::vector<Index> nodes;
    for (std::size_t k = bucket_start_[i]; k < bucket_start_[j]; ++k) {
      const Index n = by_earliest_[k];
      if (std::size_t(t.latest[n]) < j) nodes.push_back(n);
    }
    std::sort(nodes.begin(), nodes.end());
    return nodes;
  }

  void TryWindow() {
    const std::size_t len = schedule_.size();
    const bool large = o_.large_every != 0 && rng_.Below(o_.large_every) == 0;
    out_.large_windows += large;
    const std::size_t k =
        std::min<std::size_t>(len, large ? rng_.Between(o_.large_min, o_.large_max)
                                         : rng_.Between(o_.min_window, o_.max_window));
    const std::size_t i = rng_.Below(len - k + 1), j = i + k;
    const CellForest sub = CellForest::Sub(f_, WindowNodes(i, j));
    out_.work += sub.size();
    if (!large && k <= o_.exact_window) {
      ShorterOptions so;
      so.upper = k + 1;
      so.seed = rng_.Next() | 1;
      so.limits.max_states = o_.exact_states;
      so.limits.max_seconds = 1e30;  // limited by states and memory only
      so.limits.max_bytes = o_.exact_bytes;
      const ShorterResult r = FindShorter(sub, so);
      out_.work += r.work;
      if (r.status == ShorterResult::kFound) Replace(i, j, r.schedule);
      if (r.status != ShorterResult::kStopped) return;
    }
    BeamOptions bo;
    bo.width = o_.beam_width;
    bo.seed = rng_.Next() | 1;
    bo.upper = k + 1;
    const BeamResult r = BeamSearch(sub, bo);
    out_.work += r.node_visits;
    if (r.found) Replace(i, j, r.schedule);
  }

  void Replace(std::size_t i, std::size_t j, const std::vector<CellId>& w) {
    RAYCELL_CHECK_LE(w.size(), j - i);
    if (w.size() == j - i && std::equal(w.begin(), w.end(), schedule_.begin() + i)) return;
    ++(w.size() < j - i ? out_.improvements : out_.plateau_moves);
    schedule_.erase(schedule_.begin() + i, schedule_.begin() + j);
    schedule_.insert(schedule_.begin() + i, w.begin(), w.end());
    Retime();
    DeleteIdle();
  }

  void Kick() {
    ++out_.kicks;
    if (schedule_.size() > out_.schedule.size() + o_.kick_slack) schedule_ = out_.schedule;
    for (std::size_t k = 0; k < o_.kick_size && !f_.cells().empty(); ++k) {
      const std::size_t at = rng_.Below(schedule_.size() + 1);
      schedule_.insert(schedule_.begin() + at, f_.cells()[rng_.Below(f_.cells().size())]);
    }
    Retime();  // inserting fetches never makes a schedule infeasible
  }

  const CellForest& f_;
  const LocalSearchOptions o_;
  ScheduleTimer timer_;
  SeededRandom rng_;
  std::vector<CellId> schedule_;  // the walk's current schedule
  LocalSearchResult out_;         // out_.schedule: the best so far
  std::vector<std::size_t> bucket_start_;
  std::vector<Index> by_earliest_;
  std::vector<bool> needed_;
};

}  // namespace

LocalSearchResult ImproveSchedule(const CellForest& forest, std::vector<CellId> schedule,
                                  const LocalSearchOptions& options) {
  const std::size_t input = schedule.size();
  LocalSearchResult out = LocalSearch(forest, std::move(schedule), options).Run();
  RAYCELL_CHECK(IsFeasible(forest, out.schedule));
  RAYCELL_CHECK_LE(out.schedule.size(), input);
  return out;
}

}  // namespace raycell
