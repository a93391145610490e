#include "scheduling/random_scheduler.h"

namespace raycell {

constexpr SchedulerEntry kRandomEntry = [] {
  SchedulerEntry e;
  e.name = "random";
  e.meaning = "a seeded random cell with work (a baseline)";
  e.label = "Random";
  e.make = [](std::uint64_t seed) -> std::unique_ptr<Scheduler> {
    return std::make_unique<RandomScheduler>(seed);
  };
  e.history = 0;  // reads no earlier frame
  e.seeded = true;
  e.predicts = false;
  e.studied = false;
  return e;
}();

namespace {
std::uint64_t Rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
}  // namespace

Xoshiro256::Xoshiro256(std::uint64_t seed) {
  SplitMix64 sm(seed);
  for (std::uint64_t& s : s_) s = sm.Next();
}

std::uint64_t Xoshiro256::Next() {
  const std::uint64_t result = Rotl(s_[1] * 5, 7) * 9;
  const std::uint64_t t = s_[1] << 17;
  s_[2] ^= s_[0];
  s_[3] ^= s_[1];
  s_[1] ^= s_[2];
  s_[0] ^= s_[3];
  s_[2] ^= t;
  s_[3] = Rotl(s_[3], 45);
  return result;
}

std::uint64_t Xoshiro256::Below(std::uint64_t n) {
  // Accept x >= 2^64 mod n: the accepted range is a whole number of copies of [0, n).
  const std::uint64_t threshold = (0 - n) % n;
  for (;;) {
    const std::uint64_t x = Next();
    if (x >= threshold) return x % n;
  }
}

std::uint64_t RandomScheduler::FrameSeed(std::uint64_t seed, std::size_t frame_index) {
  SplitMix64 a(seed);
  SplitMix64 b(a.Next() ^ static_cast<std::uint64_t>(frame_index));
  return b.Next();
}

void RandomScheduler::BeginFrame(const FrameInfo& frame) {
  rng_ = Xoshiro256(FrameSeed(seed_, frame.frame_index));
}

std::optional<CellId> RandomScheduler::Next(const QueueView& queues) {
  std::uint64_t with_work = 0;
  for (CellId c : CellRange(queues.cells)) with_work += queues.has_work(c) ? 1 : 0;
  if (with_work == 0) return std::nullopt;
  std::uint64_t k = rng_.Below(with_work);
  for (CellId c{0};; ++c) {
    if (queues.has_work(c) && k-- == 0) return c;
  }
}

}  // namespace raycell
