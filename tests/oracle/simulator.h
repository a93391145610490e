// The simulation loop (docs/design.md §2): pops events in (time, priority, insertion order),
// CHECKs that time never goes backwards, counts events, and runs a watchdog (ChampSim) that
// stops with a dump of every component's state when nothing progresses.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "base/check.h"
#include "base/checked.h"
#include "engine/time.h"
#include "engine/watchdog.h"
#include "tests/oracle/calendar_queue.h"
#include "tests/oracle/component.h"
#include "tests/oracle/event_queue.h"

namespace raycell {

// Simulator::Run throws SimulationStalled (engine/watchdog.h) when the watchdog fires; the
// message names the reason, the time, the queue size and every component's Name(),
// HasWork() and DumpState().

struct SimulatorOptions {
  // The watchdog fires after this many consecutive events with no NoteProgress() call.
  // 0 disables this check (the empty-queue-with-work check always runs).
  std::uint64_t watchdog_events = kWatchdogEvents;  // the replay's (engine/watchdog.h)
};

enum class RunStatus {
  kQueueEmpty,    // every event was handled
  kReachedUntil,  // the next event lies after `until`; now() == until
  kStopped,       // a component called Stop()
};
const char* ToString(RunStatus status);
inline std::ostream& operator<<(std::ostream& os, RunStatus s) { return os << ToString(s); }

class Simulator {
 public:
  // The default queue is the calendar queue, the fastest at every size measured
  // (tools/bench/engine_hold.cpp).
  explicit Simulator(SimulatorOptions options = {},
                     std::unique_ptr<EventQueue> queue = std::make_unique<CalendarQueue>());
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;

  // Registers a component, which must outlive every Run(). Ids are 0, 1, 2, ...
  ComponentId Add(Component& component);
  std::size_t component_count() const { return components_.size(); }

  // Delivers an event to `target` at now() + delay. Returns the event's seq.
  std::uint64_t Schedule(ComponentId target, SimTime delay, std::uint32_t kind,
                         std::uint64_t payload = 0, std::int32_t priority = 0) {
    return ScheduleAt(target, now_ + delay, kind, payload, priority);
  }
  // Delivers an event at absolute time `when`; CHECK-fails if when < now() (the past).
  // Inline, with Schedule: every event passes here.
  std::uint64_t ScheduleAt(ComponentId target, SimTime when, std::uint32_t kind,
                           std::uint64_t payload = 0, std::int32_t priority = 0) {
    RAYCELL_CHECK_LE(now_, when);  // no event in the past
    RAYCELL_CHECK_LT(target, components_.size());
    const std::uint64_t seq = next_seq_;
    next_seq_ = CheckedAdd(next_seq_, 1);
    const Event event{when, priority, seq, target, kind, payload};
    if (calendar_ != nullptr) {
      calendar_->Push(event);  // a direct, inline call: CalendarQueue is final
    } else {
      queue_->Push(event);
    }
    ++pending_;
    return seq;
  }

  // Handles events up to and including time `until`. Throws SimulationStalled when the
  // watchdog fires.
  RunStatus Run(SimTime until = SimTime::Max());
  // Ends the current Run() after the event being handled.
  void Stop() { stop_requested_ = true; }
  // Components call this when they complete real work (a sample, a fetch); it resets the
  // watchdog.
  void NoteProgress() { events_since_progress_ = 0; }
  // Called with every event just before it is handled (traces, debugging); empty to clear.
  void SetObserver(std::function<void(const Event&)> observer) { observer_ = std::move(observer); }

  SimTime now() const { return now_; }
  std::uint64_t events_handled() const { return events_handled_; }
  std::uint64_t events_scheduled() const { return next_seq_; }
  std::size_t pending() const { return queue_->Size(); }
  const EventQueue& queue() const { return *queue_; }

  // Every component's id, name, HasWork() and DumpState(), one block each.
  std::string DumpComponents() const;

 private:
  template <typename Queue>
  RunStatus RunOn(Queue& queue, SimTime until);
  void Dispatch(const Event& event);
  void CheckQueueDryWithoutWork() const;
  [[noreturn]] void Stall(const std::string& reason) const;

  SimulatorOptions options_;
  std::unique_ptr<EventQueue> queue_;
  // queue_ when it is a CalendarQueue (the default), else null: the loop calls it without
  // a virtual call per push and pop.
  CalendarQueue* calendar_ = nullptr;
  std::vector<Component*> components_;  // not owned
  std::function<void(const Event&)> observer_;
  SimTime now_;
  std::uint64_t next_seq_ = 0;
  std::uint64_t events_handled_ = 0;
  std::uint64_t events_since_progress_ = 0;
  std::size_t pending_ = 0;  // events in queue_, which only Schedule and Run change
  bool stop_requested_ = false;
};

}  // namespace raycell
