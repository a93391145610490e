// Random (a baseline, docs/design.md §2): a cell drawn uniformly among the cells with queued
// work. The generator is implemented here (xoshiro256**, seeded through splitmix64, and
// rejection sampling for bounded draws) so that a seed gives the same choices with every
// compiler and standard library. Each frame re-seeds from (seed, frame_index): frames are
// independent and any one can be replayed alone.
#pragma once

#include <cstdint>

#include "base/random.h"
#include "scheduling/scheduler.h"

namespace raycell {

// xoshiro256** 1.0 (Blackman and Vigna 2018).
class Xoshiro256 {
 public:
  // The state from four splitmix64 outputs, as the authors recommend.
  explicit Xoshiro256(std::uint64_t seed);
  Xoshiro256(std::uint64_t s0, std::uint64_t s1, std::uint64_t s2, std::uint64_t s3)
      : s_{s0, s1, s2, s3} {}
  std::uint64_t Next();
  // Uniform in [0, n) without modulo bias; n must be > 0.
  std::uint64_t Below(std::uint64_t n);

 private:
  std::uint64_t s_[4];
};

// Its registry entry (SchedulerEntry), defined in random_scheduler.cpp.
extern const SchedulerEntry kRandomEntry;

class RandomScheduler : public Scheduler {
 public:
  explicit RandomScheduler(std::uint64_t seed)
      : Scheduler(kRandomEntry), seed_(seed), rng_(FrameSeed(seed, 0)) {}
  void BeginFrame(const FrameInfo& frame) override;
  std::optional<CellId> Next(const QueueView& queues) override;
  // A random choice cannot be foretold without drawing it: no prediction, no prefetch.
  std::optional<CellId> Peek(const QueueView&) const override { return std::nullopt; }
  std::uint64_t seed() const { return seed_; }
  // The generator seed of one frame: distinct frames get unrelated streams.
  static std::uint64_t FrameSeed(std::uint64_t seed, std::size_t frame_index);

 private:
  std::uint64_t seed_;
  Xoshiro256 rng_;
};

}  // namespace raycell
