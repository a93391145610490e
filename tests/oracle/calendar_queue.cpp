#include "tests/oracle/calendar_queue.h"

#include <algorithm>

#include "base/check.h"

namespace raycell {
namespace {

// The earliest events, whose spacing sets the day length when the size doubles or halves.
constexpr std::size_t kSpacingSample = 64;

// Sorting by "comes after" puts the earliest event last. A type, not a function, so that the
// algorithms inline it.
struct After {
  bool operator()(const Event& a, const Event& b) const { return EventBefore(b, a); }
};

// The smallest s with 2^s >= v (0 for v <= 1), at most 63.
unsigned CeilLog2(std::uint64_t v) {
  if (v <= 1) return 0;
  return std::min(63u, unsigned(64 - __builtin_clzll(v - 1)));
}

}  // namespace

CalendarQueue::CalendarQueue() : bins_(kMinBins) {}

CalendarQueue::CalendarQueue(std::size_t reserve) : CalendarQueue() {
  far_.reserve(std::min<std::size_t>(reserve, 1024));
}

void CalendarQueue::PlaceSlow(const Event& event, std::uint64_t day) const {
  if (day <= day_) {  // usually the latest of its time (largest seq): near the back
    front_.insert(std::upper_bound(front_.begin(), front_.end(), event, After()), event);
  } else {
    far_.push_back(event);
    far_day_ = std::min(far_day_, day);
  }
}

void CalendarQueue::PullFar() const {
  std::uint64_t next = UINT64_MAX;
  std::size_t kept = 0;
  for (const Event& e : far_) {
    const std::uint64_t day = Day(e);
    if (day - day_ < bins_.size()) {  // day >= day_: far days never lie before the front's
      bins_[day & (bins_.size() - 1)].push_back(e);
      ++in_bins_;
    } else {
      far_[kept++] = e;
      next = std::min(next, day);
    }
  }
  walked_ += far_.size();
  far_.resize(kept);
  far_day_ = next;
}

void CalendarQueue::Advance() const {
  RAYCELL_CHECK(size_ > 0);
  while (front_.empty()) {
    if (in_bins_ == 0) {  // nothing in the year ahead: jump to the earliest far day
      day_ = far_day_ - 1;
      PullFar();
    }
    ++day_;
    ++walked_;
    if (far_day_ - day_ < bins_.size()) PullFar();  // the year now reaches a far event
    std::vector<Event>& bin = bins_[day_ & (bins_.size() - 1)];
    if (bin.empty()) continue;
    front_.swap(bin);  // the bin keeps the front's old (empty) storage
    in_bins_ -= front_.size();
    ++days_sorted_;
    sorted_ += front_.size();
    if (front_.size() == 2) {  // the usual day: a swap at most
      if (After()(front_[1], front_[0])) std::swap(front_[0], front_[1]);
    } else if (front_.size() > 2) {
      std::sort(front_.begin(), front_.end(), After());
    }
  }
}

void CalendarQueue::EstimateDay(std::vector<std::uint64_t> times) {
  const std::size_t k = std::min(kSpacingSample, times.size());
  std::nth_element(times.begin(), times.begin() + (k - 1), times.end());
  std::sort(times.begin(), times.begin() + k);
  // About one event a day near the front: the median gap between the earliest events, not
  // their mean, so that stragglers far from the others do not stretch the days. Ties count
  // once (they share a day whatever its length); when the earliest events are all ties, the
  // mean spacing of all events.
  std::vector<std::uint64_t> gaps;
  for (std::size_t i = 0; i + 1 < k; ++i) {
    if (times[i + 1] != times[i]) gaps.push_back(times[i + 1] - times[i]);
  }
  std::uint64_t gap = 0;
  if (!gaps.empty()) {
    std::nth_element(gaps.begin(), gaps.begin() + gaps.size() / 2, gaps.end());
    gap = gaps[gaps.size() / 2];
  } else {
    gap = (*std::max_element(times.begin(), times.end()) - times[0]) / times.size();
  }
  shift_ = CeilLog2(gap);
}

void CalendarQueue::Rebuild(std::size_t bins, bool estimate) {
  std::vector<Event> all;
  all.reserve(size_);
  all.insert(all.end(), front_.begin(), front_.end());
  front_.clear();
  for (std::vector<Event>& b : bins_) {
    all.insert(all.end(), b.begin(), b.end());
    b.clear();
  }
  all.insert(all.end(), far_.begin(), far_.end());
  far_.clear();
  RAYCELL_CHECK_EQ(all.size(), size_);
  bins_.resize(bins);
  shrink_below_ = bins > kMinBins ? bins / 4 : 0;
  in_bins_ = 0;
  far_day_ = UINT64_MAX;
  ops_ = walked_ = days_sorted_ = sorted_ = 0;
  if (all.empty()) return;
  std::vector<std::uint64_t> times;
  times.reserve(all.size());
  for (const Event& e : all) times.push_back(e.time.picoseconds());
  if (estimate) EstimateDay(times);
  day_ = *std::min_element(times.begin(), times.end()) >> shift_;
  for (const Event& e : all) Place(e);
  std::sort(front_.begin(), front_.end(), After());
}

void CalendarQueue::Adapt() {
  // Per pop (about half the operations): more than 4 days walked or far events scanned
  // means short days; more than 8 events a sorted day means long ones.
  if (walked_ > 2 * ops_ && shift_ < 63) {
    ++shift_;
    Rebuild(bins_.size(), false);
  } else if (sorted_ > 8 * days_sorted_ && shift_ > 0) {
    --shift_;
    Rebuild(bins_.size(), false);
  } else {
    ops_ = walked_ = days_sorted_ = sorted_ = 0;
  }
}

}  // namespace raycell
