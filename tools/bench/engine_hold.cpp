// Engine events per second on the classic hold model: N pending events; each handled event
// schedules one new event at now + a random delay (uniform in [0, 2000] ps), so the queue
// stays at N. For each queue: the bare queue (push/pop only), the full Simulator loop (a
// component that reschedules itself through Simulator::Schedule), and the queue's share of
// the loop's time (loop rate / bare-queue rate). Deterministic: splitmix64 from SEED.
//
// The slot queue (engine/slot_queue.h, what the replay runs on) holds the same model as N
// components with one pending event each, the handled one rescheduling itself: the same
// events in the same order (checked: the same last time as the heaps'). It has no Simulator
// loop; its row gives the bare queue only.
//
// Rates are events per second of this thread's CPU time (not wall time), which the other
// processes of a shared machine disturb much less. Each queue is measured REPS times, the three
// queues in turn (so that the load of a shared machine touches them alike), and the medians are
// printed.
//
// Usage: bench_engine_hold [MAX_N=1000000] [SEED=1] [REPS=5] [MIN_N=100] [QUEUES=all]
//   QUEUES: "all", or one of binary-heap, 4-ary-heap, calendar, slot (for profiling one queue).
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "base/check.h"
#include "base/cpu_time.h"
#include "base/random.h"
#include "engine/slot_queue.h"
#include "tests/oracle/calendar_queue.h"
#include "tests/oracle/event_queue.h"
#include "tests/oracle/simulator.h"

namespace raycell {
namespace {

// The hold model's delays, from a seeded splitmix64.
struct Delays {
  SplitMix64 rng;
  SimTime Delay() { return SimTime::Picoseconds(rng.Next() % 2001); }
};

// Bare queue: N events, `warmup` untimed holds, then `ops` timed holds. Returns events/s.
template <typename Queue>
double QueueHold(std::size_t n, std::uint64_t warmup, std::uint64_t ops, std::uint64_t seed,
                 std::uint64_t* checksum) {
  Delays rng{SplitMix64(seed)};
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
  const double start = ThreadCpuSeconds();
  for (std::uint64_t i = 0; i < ops; ++i) hold();
  const double s = ThreadCpuSeconds() - start;
  *checksum = last.picoseconds();
  return double(ops) / s;
}

// The same hold on the slot queue: slot i holds the i-th event; the handled slot reschedules
// itself. Returns events/s.
double SlotHold(std::size_t n, std::uint64_t warmup, std::uint64_t ops, std::uint64_t seed,
                std::uint64_t* checksum) {
  enum class Kind : std::uint8_t { kNone, kHold };
  Delays rng{SplitMix64(seed)};
  SlotQueue<Kind> q{static_cast<std::uint32_t>(n)};
  for (std::uint32_t i = 0; i < n; ++i) {
    q.Schedule(i, rng.Delay(), Kind::kHold);
    q.Update(i);
  }
  SimTime last;
  std::uint32_t p = q.top();
  auto hold = [&] {
    last = q.at(p).time;
    q.Clear(p);
    q.Schedule(p, last + rng.Delay(), Kind::kHold);
    p = q.Update(p);
  };
  for (std::uint64_t i = 0; i < warmup; ++i) hold();
  const double start = ThreadCpuSeconds();
  for (std::uint64_t i = 0; i < ops; ++i) hold();
  const double s = ThreadCpuSeconds() - start;
  *checksum = last.picoseconds();
  return double(ops) / s;
}

class Holder : public Component {
 public:
  explicit Holder(std::uint64_t seed) : rng_{SplitMix64(seed)} {}
  void Handle(const Event&, Simulator& sim) override {
    sim.NoteProgress();
    sim.Schedule(0, rng_.Delay(), 0);
    if (--budget == 0) sim.Stop();
  }
  std::string Name() const override { return "holder"; }
  SimTime FirstDelay() { return rng_.Delay(); }
  std::uint64_t budget = 0;  // events until Stop()

 private:
  Delays rng_;
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
  const double start = ThreadCpuSeconds();
  run_events(ops);
  const double s = ThreadCpuSeconds() - start;
  *checksum = sim.now().picoseconds();
  return double(sim.events_handled() - before) / s;
}

struct Rates {
  std::vector<double> queue, engine;  // events/s, one per run
};

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// One run of each measurement for queue type Queue at size n.
template <typename Queue>
void Measure(std::size_t n, std::uint64_t seed, Rates* rates) {
  const std::uint64_t ops = std::max<std::uint64_t>(2'000'000, 4 * n);
  const std::uint64_t warmup = std::max<std::uint64_t>(100'000, n);
  std::uint64_t c1 = 0, c2 = 0;
  rates->queue.push_back(QueueHold<Queue>(n, warmup, ops, seed, &c1));
  rates->engine.push_back(SimulatorHold<Queue>(n, warmup, ops, seed, &c2));
  RAYCELL_CHECK_EQ(c1, c2);  // the same events in the same order: the same last time
}

void Print(const std::string& name, std::size_t n, const Rates& r) {
  if (r.engine.empty()) {  // the slot queue: no Simulator loop
    std::printf("%-11s %10zu %5zu %14.2f %14s %10.1f %13s\n", name.c_str(), n, r.queue.size(),
                Median(r.queue) / 1e6, "-", 1e9 / Median(r.queue), "-");
    return;
  }
  const double queue = Median(r.queue), loop = Median(r.engine);
  std::printf("%-11s %10zu %5zu %14.2f %14.2f %10.1f %12.1f%%\n", name.c_str(), n, r.queue.size(),
              queue / 1e6, loop / 1e6, 1e9 / loop, 100.0 * loop / queue);
}

// The slot queue's hold, checked to end at the binary heap's last time.
void MeasureSlots(std::size_t n, std::uint64_t seed, Rates* rates) {
  const std::uint64_t ops = std::max<std::uint64_t>(2'000'000, 4 * n);
  const std::uint64_t warmup = std::max<std::uint64_t>(100'000, n);
  std::uint64_t c1 = 0, c2 = 0;
  rates->queue.push_back(SlotHold(n, warmup, ops, seed, &c1));
  QueueHold<BinaryHeapQueue>(n, warmup, ops, seed, &c2);
  RAYCELL_CHECK_EQ(c1, c2);  // the same events in the same order: the same last time
}

// The four queues measured in turn, `reps` times, so that a change in the machine's load
// touches all of them alike; medians printed.
void Rows(std::size_t n, std::uint64_t seed, int reps, const std::string& queues) {
  const auto on = [&](const std::string& name) { return queues == "all" || queues == name; };
  const bool b = on(BinaryHeapQueue().Name()), f = on(QuaternaryHeapQueue().Name()),
             c = on(CalendarQueue().Name()), s = on("slot");
  Rates binary, quaternary, calendar, slot;
  for (int i = 0; i < reps; ++i) {
    if (b) Measure<BinaryHeapQueue>(n, seed, &binary);
    if (f) Measure<QuaternaryHeapQueue>(n, seed, &quaternary);
    if (c) Measure<CalendarQueue>(n, seed, &calendar);
    if (s) MeasureSlots(n, seed, &slot);
  }
  if (b) Print(BinaryHeapQueue().Name(), n, binary);
  if (f) Print(QuaternaryHeapQueue().Name(), n, quaternary);
  if (c) Print(CalendarQueue().Name(), n, calendar);
  if (s) Print("slot", n, slot);
}

}  // namespace
}  // namespace raycell

int main(int argc, char** argv) {
  const std::size_t max_n = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 1000'000;
  const std::uint64_t seed = argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 1;
  const int reps = argc > 3 ? std::atoi(argv[3]) : 5;
  const std::size_t min_n = argc > 4 ? std::strtoull(argv[4], nullptr, 10) : 100;
  const std::string queues = argc > 5 ? argv[5] : "all";
  std::printf("hold model, delay uniform [0, 2000] ps, seed %llu, median of %d runs\n",
              (unsigned long long)seed, reps);
  std::printf("%-11s %10s %5s %14s %14s %10s %13s\n", "queue", "N", "runs", "queue Mev/s",
              "engine Mev/s", "ns/event", "queue share");
  for (std::size_t n = min_n; n <= max_n; n *= 10)
    raycell::Rows(n, seed, std::max(1, reps), queues);
  return 0;
}
