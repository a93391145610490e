// A calendar queue (R. Brown, "Calendar queues: a fast O(1) priority queue implementation
// for the simulation event set problem", CACM 31(10), 1988) whose days are sorted only when
// reached, as in a ladder queue (W. T. Tang, R. S. M. Goh, I. L.-J. Thng, "Ladder queue: an
// O(1) priority queue structure for large-scale discrete event simulation", ACM TOMACS
// 15(3), 2005), behind the EventQueue interface with the engine's exact order (time,
// priority, seq).
//
// Time is cut into days of 2^shift picoseconds. The events of the current day (and any
// pushed before it) are the `front`, a vector sorted so that its last element is the
// earliest event: a pop is a pop_back. The events of the next B - 1 days (B a power of two,
// the days of a "year") wait unsorted in bin day mod B; later ones wait unsorted in `far`.
// When the front runs out, the next non-empty day's bin becomes the front and is sorted
// (a few events, so O(1) per event); when the year ahead holds nothing, the current day
// jumps to the earliest far event, and far events move into bins as the year reaches them.
// A push lands in its bin or the far list in O(1), or into the sorted front by binary
// search when it is for the current day (zero-delay events).
//
// B follows the size (doubled above two events per bin, halved below one event per four
// bins). The day length starts from the median gap between the earliest events (not their
// mean, so that stragglers far from the others do not stretch every day) whenever B changes, and is
// then steered by what the operations cost (Oh and Ahn's SNOOPy calendar queue adapts the same
// way): doubled while pops walk many empty days or scan the far list, halved while days hold many
// events to sort. Each change rebuilds the bins in O(size) at most once per max(1024, size)
// operations, so O(1) amortised. Any sequence of pushes and pops is handled, also pushes before the
// last pop.
//
// Measured by tools/bench/engine_hold.cpp (BENCHMARKS.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "tests/oracle/event_queue.h"

namespace raycell {

class CalendarQueue final : public EventQueue {
 public:
  CalendarQueue();
  explicit CalendarQueue(std::size_t reserve);
  // Push, Top and Pop are inline (their usual cases: an event into its bin, the front's last
  // event), so that the Simulator, which calls them on a CalendarQueue* (final), pays no
  // call for them; the rarer work (a new day, a rebuild) is out of line.
  void Push(const Event& event) override {
    if (size_ == 0) day_ = Day(event);
    Place(event);
    ++size_;
    ++ops_;
    if (size_ > 2 * bins_.size()) {
      Rebuild(bins_.size() * 2, true);
    } else if (ops_ >= 1024 && ops_ >= size_) {
      Adapt();
    }
  }
  const Event& Top() const override {
    if (front_.empty()) Advance();
    return front_.back();
  }
  Event Pop() override {
    if (front_.empty()) Advance();
    const Event top = front_.back();
    front_.pop_back();
    --size_;
    ++ops_;
    if (size_ < shrink_below_) {
      Rebuild(bins_.size() / 2, true);
    } else if (ops_ >= 1024 && ops_ >= size_) {
      Adapt();
    }
    return top;
  }
  std::size_t Size() const override { return size_; }
  std::string Name() const override { return "calendar"; }

  // For tests and benchmarks: the days of a year and the length of a day in ps.
  std::size_t bucket_count() const { return bins_.size(); }
  std::uint64_t day_length() const { return std::uint64_t{1} << shift_; }

 private:
  static constexpr std::size_t kMinBins = 4;

  std::uint64_t Day(const Event& e) const { return e.time.picoseconds() >> shift_; }
  // Into the front, its bin or far, by day.
  void Place(const Event& event) const {
    const std::uint64_t day = Day(event);
    const std::uint64_t ahead = day - day_;  // wraps for days before the front's
    if (ahead - 1 < bins_.size() - 1) {      // 0 < ahead < B: a bin (the usual case)
      bins_[day & (bins_.size() - 1)].push_back(event);
      ++in_bins_;
    } else {
      PlaceSlow(event, day);
    }
  }
  void PlaceSlow(const Event& event, std::uint64_t day) const;  // the front or far
  void Advance() const;  // makes the front non-empty; size_ > 0
  void PullFar() const;  // far events within the year into bins
  // Moves every event again into `bins` bins; the day length is estimated anew when
  // `estimate`, else kept.
  void Rebuild(std::size_t bins, bool estimate);
  void EstimateDay(std::vector<std::uint64_t> times);
  void Adapt();  // called when ops_ >= max(1024, size_)

  // Mutable: Top() may have to sort the next day into the front.
  mutable std::vector<Event> front_;              // sorted, earliest last
  mutable std::vector<std::vector<Event>> bins_;  // unsorted, day mod B
  mutable std::vector<Event> far_;                // unsorted, a year or more ahead
  mutable std::uint64_t day_ = 0;                 // the front's day
  mutable std::uint64_t far_day_ = UINT64_MAX;    // earliest day in far_
  mutable std::size_t in_bins_ = 0;
  std::size_t size_ = 0;
  unsigned shift_ = 0;  // a day is 2^shift_ ps
  // Costs since the last adaptation: operations, days walked and far events scanned (too
  // short days), days sorted and events sorted (too long days).
  std::uint64_t ops_ = 0;
  // The bins halve when size_ falls below this: B / 4, or 0 at the fewest bins.
  std::size_t shrink_below_ = 0;
  mutable std::uint64_t walked_ = 0, days_sorted_ = 0, sorted_ = 0;
};

}  // namespace raycell
