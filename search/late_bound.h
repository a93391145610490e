// A lower bound on a tree's optimum that becomes known while a schedule search runs: the
// bracket (analysis/analysis.cpp) computes its lower bound on one thread while the search runs
// on the others, so that a frame takes about the longer of the two instead of their sum.
//
// Why the search's answer does not depend on when the value arrives: the searches use a
// lower bound only to stop once their best schedule meets it (then it is optimal), and keep a
// schedule only when it is strictly shorter than their best, which no schedule can be once
// the best meets a lower bound. So a search that learns the bound late does more work, never
// another schedule. Where a search would use the value to decide anything else (the exact
// search's pruning, BestScheduleOptions), it waits for it: Wait.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>

namespace raycell {

class LateBound {
 public:
  // Makes `value` known (once; 0 when the bound could not be computed) and wakes waiters.
  void Publish(std::uint64_t value) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      value_.store(value, std::memory_order_release);
      published_ = true;
    }
    cv_.notify_all();
  }
  // The value if it is known yet, else 0 (no bound): for stopping early only.
  std::uint64_t Now() const { return value_.load(std::memory_order_acquire); }
  // The value, waiting until it is known.
  std::uint64_t Wait() const {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait(lock, [this] { return published_; });
    return value_.load(std::memory_order_relaxed);
  }

 private:
  std::atomic<std::uint64_t> value_{0};
  mutable std::mutex mutex_;
  mutable std::condition_variable cv_;
  bool published_ = false;
};

// The value `bound` (null: none) makes known now, else 0: what a search may stop on.
inline std::uint64_t KnownNow(const LateBound* bound) { return bound ? bound->Now() : 0; }

}  // namespace raycell
