// Engine events per second on the classic hold model: N pending events; each handled event
// schedules one new event at now + a random delay (uniform in [0, 2000] ps), so the queue
// stays at N. For each queue: the bare queue (push/pop only), the full Simulator loop (a
// component that reschedules itself through Simulator::Schedule), and the queue's share of
// the loop's time (loop rate / bare-queue rate). Deterministic: splitmix64 from SEED.
//
// Usage: bench_engine_hold [MAX_N=1000000] [SEED=1]
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "base/check.h"
#include "engine/event_queue.h"
#include "engine/simulator.h"

namespace raycell {
namespace {

struct SplitMix64 {
  std::uint64_t state;
  std::uint64_t operator()() {
    std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  SimTime Delay() { return SimTime::Picoseconds((*this)() % 2001); }
};

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Bare queue: N events, `warmup` untimed holds, then `ops` timed holds. Returns events/s.
template <typename Queue>
double QueueHold(std::size_t n, std::uint64_t warmup, std::uint64_t ops, std::uint64_t seed,
                 std::uint64_t* checksum) {
  SplitMix64 rng{seed};
  Queue q(n);
  std::uint64_t seq = 0;
  for (; seq < n; ++seq) q.Push(Event{rng.Delay(), 0, seq, 0, 0, 0});
  SimTime last;
  auto hold = [&] {
    const Event e = q.Pop();
    last = e.time;
    q.Push(Event{e.time + rng.Delay(), 0, seq++, 0, 0, 0});
  };
  for (std::uint64_t i = 0; i < warmup; ++i) hold();
  const auto start = std::chrono::steady_clock::now();
  for (std::uint64_t i = 0; i < ops; ++i) hold();
  const double s = Seconds(start);
  *checksum = last.picoseconds();
  return double(ops) / s;
}

class Holder : public Component {
 public:
  explicit Holder(std::uint64_t seed) : rng_{seed} {}
  void Handle(const Event&, Simulator& sim) override {
    sim.NoteProgress();
    sim.Schedule(0, rng_.Delay(), 0);
    if (--budget == 0) sim.Stop();
  }
  std::string Name() const override { return "holder"; }
  SimTime FirstDelay() { return rng_.Delay(); }
  std::uint64_t budget = 0;  // events until Stop()

 private:
  SplitMix64 rng_;
};

// Full loop: the same hold through Simulator::Run. Returns events/s.
template <typename Queue>
double SimulatorHold(std::size_t n, std::uint64_t warmup, std::uint64_t ops, std::uint64_t seed,
                     std::uint64_t* checksum) {
  Holder holder(seed);
  Simulator sim({}, std::make_unique<Queue>(n));
  sim.Add(holder);
  for (std::size_t i = 0; i < n; ++i) sim.Schedule(0, holder.FirstDelay(), 0);
  auto run_events = [&](std::uint64_t count) {
    holder.budget = count;
    sim.Run();
  };
  run_events(warmup);
  const std::uint64_t before = sim.events_handled();
  const auto start = std::chrono::steady_clock::now();
  run_events(ops);
  const double s = Seconds(start);
  *checksum = sim.now().picoseconds();
  return double(sim.events_handled() - before) / s;
}

template <typename Queue>
void Row(std::size_t n, std::uint64_t seed) {
  const std::uint64_t ops = std::max<std::uint64_t>(2'000'000, 4 * n);
  const std::uint64_t warmup = std::max<std::uint64_t>(100'000, n);
  std::uint64_t c1 = 0, c2 = 0;
  const double queue = QueueHold<Queue>(n, warmup, ops, seed, &c1);
  const double loop = SimulatorHold<Queue>(n, warmup, ops, seed, &c2);
  RAYCELL_CHECK_EQ(c1, c2);  // the same events in the same order: the same last time
  std::printf("%-11s %10zu %10llu %14.2f %14.2f %10.1f %12.1f%%\n", Queue().Name().c_str(), n,
              (unsigned long long)ops, queue / 1e6, loop / 1e6, 1e9 / loop, 100.0 * loop / queue);
}

}  // namespace
}  // namespace raycell

int main(int argc, char** argv) {
  const std::size_t max_n = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 1000'000;
  const std::uint64_t seed = argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 1;
  std::printf("hold model, delay uniform [0, 2000] ps, seed %llu\n", (unsigned long long)seed);
  std::printf("%-11s %10s %10s %14s %14s %10s %13s\n", "queue", "N", "events", "queue Mev/s",
              "engine Mev/s", "ns/event", "queue share");
  for (std::size_t n = 100; n <= max_n; n *= 10) {
    raycell::Row<raycell::BinaryHeapQueue>(n, seed);
    raycell::Row<raycell::QuaternaryHeapQueue>(n, seed);
  }
  return 0;
}
