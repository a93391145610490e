#include "tests/oracle/simulator.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace raycell {
namespace {

// Records every event it receives as a string.
class Recorder : public Component {
 public:
  explicit Recorder(std::vector<std::string>* log) : log_(log) {}
  void Handle(const Event& e, Simulator& sim) override {
    log_->push_back(sim.now().ToString() + " p" + std::to_string(e.priority) + " k" +
                    std::to_string(e.kind));
    sim.NoteProgress();
  }
  std::string Name() const override { return "recorder"; }

 private:
  std::vector<std::string>* log_;
};

TEST(Simulator, DeliversInTimePriorityInsertionOrder) {
  std::vector<std::string> log;
  Recorder r(&log);
  Simulator sim;
  const ComponentId id = sim.Add(r);
  EXPECT_EQ(id, 0u);
  sim.Schedule(id, SimTime::Nanoseconds(1), 1);
  sim.Schedule(id, SimTime::Picoseconds(5), 2, 0, /*priority=*/1);
  sim.Schedule(id, SimTime::Picoseconds(5), 3, 0, /*priority=*/0);
  sim.Schedule(id, SimTime::Picoseconds(5), 4, 0, /*priority=*/1);
  EXPECT_EQ(sim.Run(), RunStatus::kQueueEmpty);
  EXPECT_EQ(log, (std::vector<std::string>{"5ps p0 k3", "5ps p1 k2", "5ps p1 k4", "1000ps p0 k1"}));
  EXPECT_EQ(sim.events_handled(), 4u);
  EXPECT_EQ(sim.now(), SimTime::Nanoseconds(1));
}

// Ties in time and priority go in insertion order, whichever component scheduled them and
// whenever: 64 events scheduled before the run at one time, then events each handler
// schedules with no delay (after everything already pending at that time). A queue that
// ordered by (time, priority) alone would hand equal events out in heap order.
class TieLogger : public Component {
 public:
  explicit TieLogger(std::vector<std::uint64_t>* log) : log_(log) {}
  void Handle(const Event& e, Simulator& sim) override {
    sim.NoteProgress();
    log_->push_back(e.payload);
    if (e.payload < 64) sim.Schedule(e.target, SimTime::Zero(), 0, e.payload + 1000);
  }
  std::string Name() const override { return "ties"; }

 private:
  std::vector<std::uint64_t>* log_;
};

TEST(Simulator, EqualTimeAndPriorityGoInInsertionOrder) {
  std::vector<std::uint64_t> log;
  TieLogger a(&log), b(&log);
  Simulator sim;
  sim.Add(a);
  sim.Add(b);
  for (std::uint64_t i = 0; i < 64; ++i) {
    sim.ScheduleAt(ComponentId(i % 2), SimTime::Picoseconds(7), 0, i);
  }
  sim.Run();
  std::vector<std::uint64_t> expected;
  for (std::uint64_t i = 0; i < 64; ++i) expected.push_back(i);
  for (std::uint64_t i = 0; i < 64; ++i) expected.push_back(i + 1000);
  EXPECT_EQ(log, expected);
  EXPECT_EQ(sim.now(), SimTime::Picoseconds(7));
}

TEST(Simulator, RunUntilStopsAtTheLimitAndResumes) {
  std::vector<std::string> log;
  Recorder r(&log);
  Simulator sim;
  sim.Add(r);
  sim.ScheduleAt(0, SimTime::Picoseconds(10), 1);
  sim.ScheduleAt(0, SimTime::Picoseconds(20), 2);
  EXPECT_EQ(sim.Run(SimTime::Picoseconds(10)), RunStatus::kReachedUntil);
  EXPECT_EQ(log.size(), 1u);
  EXPECT_EQ(sim.now(), SimTime::Picoseconds(10));
  EXPECT_EQ(sim.Run(SimTime::Picoseconds(15)), RunStatus::kReachedUntil);
  EXPECT_EQ(sim.now(), SimTime::Picoseconds(15));
  EXPECT_EQ(sim.Run(), RunStatus::kQueueEmpty);
  EXPECT_EQ(log.back(), "20ps p0 k2");
}

// Sends `count` pings to a peer through the engine, and stops the run when told.
class Pinger : public Component {
 public:
  void Handle(const Event& e, Simulator& sim) override {
    sim.NoteProgress();
    if (e.kind == 9) return sim.Stop();
    if (e.payload > 0) sim.Schedule(peer, SimTime::Picoseconds(3), 0, e.payload - 1);
  }
  std::string Name() const override { return "pinger"; }
  ComponentId peer = 0;
};

TEST(Simulator, ComponentsTalkThroughEventsAndCanStop) {
  Pinger a, b;
  Simulator sim;
  a.peer = sim.Add(b);
  b.peer = sim.Add(a);
  sim.Schedule(0, SimTime::Zero(), 0, 10);
  EXPECT_EQ(sim.Run(), RunStatus::kQueueEmpty);
  EXPECT_EQ(sim.events_handled(), 11u);  // payloads 10, 9, ..., 0
  EXPECT_EQ(sim.now(), SimTime::Picoseconds(30));
  sim.ScheduleAt(1, SimTime::Picoseconds(2000), 9);
  sim.ScheduleAt(1, SimTime::Picoseconds(3000), 0);
  EXPECT_EQ(sim.Run(), RunStatus::kStopped);
  EXPECT_EQ(sim.now(), SimTime::Picoseconds(2000));
  EXPECT_EQ(sim.pending(), 1u);
}

TEST(SimulatorDeathTest, SchedulingInThePastIsACheckFailure) {
  std::vector<std::string> log;
  Recorder r(&log);
  Simulator sim;
  sim.Add(r);
  sim.ScheduleAt(0, SimTime::Picoseconds(100), 0);
  sim.Run();
  EXPECT_DEATH(sim.ScheduleAt(0, SimTime::Picoseconds(99), 0), "CHECK failed: now_ <= when");
  EXPECT_DEATH(sim.Schedule(7, SimTime::Zero(), 0), "CHECK failed: target < ");
}

// A queue that hands out events in the wrong order: the loop must catch time going back.
class BrokenQueue final : public EventQueue {
 public:
  void Push(const Event& e) override { events_.push_back(e); }
  const Event& Top() const override { return events_.back(); }
  Event Pop() override {
    const Event e = events_.back();
    events_.pop_back();
    return e;
  }
  std::size_t Size() const override { return events_.size(); }
  std::string Name() const override { return "lifo"; }

 private:
  std::vector<Event> events_;
};

TEST(SimulatorDeathTest, TimeGoingBackwardsIsACheckFailure) {
  std::vector<std::string> log;
  Recorder r(&log);
  Simulator sim({}, std::make_unique<BrokenQueue>());
  sim.Add(r);
  sim.ScheduleAt(0, SimTime::Picoseconds(5), 0);
  sim.ScheduleAt(0, SimTime::Picoseconds(9), 0);
  EXPECT_DEATH(sim.Run(), "CHECK failed: now_ <= event.time");
}

// Reschedules itself forever without doing anything useful.
class Spinner : public Component {
 public:
  void Handle(const Event&, Simulator& sim) override {
    ++spins;
    sim.Schedule(0, SimTime::Nanoseconds(1), 0);
  }
  std::string Name() const override { return "spinner"; }
  std::string DumpState() const override { return "spins=" + std::to_string(spins); }
  std::uint64_t spins = 0;
};

TEST(SimulatorWatchdog, SpinningWithoutProgressStalls) {
  Spinner s;
  Simulator sim(SimulatorOptions{1000});
  sim.Add(s);
  sim.Schedule(0, SimTime::Zero(), 0);
  try {
    sim.Run();
    FAIL() << "no SimulationStalled";
  } catch (const SimulationStalled& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("1000 events without progress"), std::string::npos) << what;
    EXPECT_NE(what.find("[0] spinner: spins=1000"), std::string::npos) << what;
    EXPECT_NE(what.find("at 999000ps"), std::string::npos) << what;
  }
  EXPECT_EQ(s.spins, 1000u);
}

// Progress every `period` events keeps the watchdog quiet.
class SlowWorker : public Component {
 public:
  void Handle(const Event& e, Simulator& sim) override {
    if (e.payload % 500 == 0) sim.NoteProgress();
    if (e.payload > 0) sim.Schedule(0, SimTime::Nanoseconds(1), 0, e.payload - 1);
  }
  std::string Name() const override { return "slow"; }
};

TEST(SimulatorWatchdog, OccasionalProgressIsEnough) {
  SlowWorker w;
  Simulator sim(SimulatorOptions{1000});
  sim.Add(w);
  sim.Schedule(0, SimTime::Zero(), 0, 100'000);
  EXPECT_EQ(sim.Run(), RunStatus::kQueueEmpty);
  EXPECT_EQ(sim.events_handled(), 100'001u);
}

// Claims to hold work but never schedules anything to finish it.
class Stuck : public Component {
 public:
  void Handle(const Event&, Simulator& sim) override { sim.NoteProgress(); }
  std::string Name() const override { return "processor 3"; }
  std::string DumpState() const override { return "queued rays=17"; }
  bool HasWork() const override { return true; }
};

TEST(SimulatorWatchdog, EmptyQueueWithWorkStalls) {
  std::vector<std::string> log;
  Recorder r(&log);
  Stuck s;
  Simulator sim;
  sim.Add(r);
  sim.Add(s);
  sim.Schedule(1, SimTime::Picoseconds(42), 0);
  try {
    sim.Run();
    FAIL() << "no SimulationStalled";
  } catch (const SimulationStalled& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("event queue empty while processor 3 has work"), std::string::npos) << what;
    EXPECT_NE(what.find("[0] recorder: \n"), std::string::npos) << what;
    EXPECT_NE(what.find("[1] processor 3 (has work): queued rays=17"), std::string::npos) << what;
  }
}

// Many components exchanging events with random delays, priorities and targets drawn from
// a seeded generator; returns the observed trace.
class RandomNode : public Component {
 public:
  RandomNode(std::uint64_t seed, ComponentId count) : rng_(seed), count_(count) {}
  void Handle(const Event& e, Simulator& sim) override {
    sim.NoteProgress();
    if (e.payload == 0) return;
    for (int i = 1 + int(rng_() % 2); i > 0; --i) {  // 1.5 children on average
      sim.Schedule(ComponentId(rng_() % count_), SimTime::Picoseconds(rng_() % 4),
                   std::uint32_t(rng_() % 5), e.payload - 1, std::int32_t(rng_() % 3));
    }
  }
  std::string Name() const override { return "node"; }

 private:
  std::mt19937_64 rng_;
  ComponentId count_;
};

std::vector<std::string> RandomTrace() {
  constexpr ComponentId kNodes = 8;
  std::vector<RandomNode> nodes;
  for (ComponentId i = 0; i < kNodes; ++i) nodes.emplace_back(1000 + i, kNodes);
  Simulator sim;
  for (RandomNode& n : nodes) sim.Add(n);
  std::vector<std::string> trace;
  sim.SetObserver([&trace](const Event& e) { trace.push_back(e.ToString()); });
  for (ComponentId i = 0; i < kNodes; ++i) sim.Schedule(i, SimTime::Zero(), 0, 14);
  sim.Run();
  return trace;
}

TEST(Simulator, IdenticalRunsGiveIdenticalTraces) {
  const std::vector<std::string> a = RandomTrace();
  const std::vector<std::string> b = RandomTrace();
  EXPECT_GT(a.size(), 1000u);
  EXPECT_EQ(a, b);
}

}  // namespace
}  // namespace raycell
