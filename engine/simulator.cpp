#include "engine/simulator.h"

#include <sstream>

#include "base/check.h"
#include "base/checked.h"

namespace raycell {

const char* ToString(RunStatus status) {
  switch (status) {
    case RunStatus::kQueueEmpty:
      return "queue-empty";
    case RunStatus::kReachedUntil:
      return "reached-until";
    case RunStatus::kStopped:
      return "stopped";
  }
  return "unknown";
}

Simulator::Simulator(SimulatorOptions options, std::unique_ptr<EventQueue> queue)
    : options_(options), queue_(std::move(queue)) {
  RAYCELL_CHECK(queue_ != nullptr);
  RAYCELL_CHECK(queue_->Empty());
}

ComponentId Simulator::Add(Component& component) {
  RAYCELL_CHECK_LT(components_.size(), std::size_t(UINT32_MAX));
  components_.push_back(&component);
  return ComponentId(components_.size() - 1);
}

std::uint64_t Simulator::Schedule(ComponentId target, SimTime delay, std::uint32_t kind,
                                  std::uint64_t payload, std::int32_t priority) {
  return ScheduleAt(target, now_ + delay, kind, payload, priority);
}

std::uint64_t Simulator::ScheduleAt(ComponentId target, SimTime when, std::uint32_t kind,
                                    std::uint64_t payload, std::int32_t priority) {
  RAYCELL_CHECK_LE(now_, when);  // no event in the past
  RAYCELL_CHECK_LT(target, components_.size());
  const std::uint64_t seq = next_seq_;
  next_seq_ = CheckedAdd(next_seq_, 1);
  queue_->Push(Event{when, priority, seq, target, kind, payload});
  return seq;
}

RunStatus Simulator::Run(SimTime until) {
  stop_requested_ = false;
  while (!queue_->Empty()) {
    if (queue_->Top().time > until) {
      now_ = until;
      return RunStatus::kReachedUntil;
    }
    Dispatch(queue_->Pop());
    if (stop_requested_) return RunStatus::kStopped;
  }
  CheckQueueDryWithoutWork();
  return RunStatus::kQueueEmpty;
}

void Simulator::Dispatch(const Event& event) {
  RAYCELL_CHECK_LE(now_, event.time);  // time never goes backwards
  now_ = event.time;
  events_handled_ = CheckedAdd(events_handled_, 1);
  ++events_since_progress_;  // cannot overflow: bounded by events_handled_
  if (observer_) observer_(event);
  components_[event.target]->Handle(event, *this);  // may call NoteProgress()
  if (options_.watchdog_events != 0 && events_since_progress_ >= options_.watchdog_events) {
    Stall(std::to_string(events_since_progress_) + " events without progress");
  }
}

void Simulator::CheckQueueDryWithoutWork() const {
  for (const Component* c : components_) {
    if (c->HasWork()) Stall("event queue empty while " + c->Name() + " has work");
  }
}

void Simulator::Stall(const std::string& reason) const {
  std::ostringstream s;
  s << "simulation stalled: " << reason << " at " << now_ << " after " << events_handled_
    << " events; " << queue_->Size() << " pending";
  if (!queue_->Empty()) s << ", next " << queue_->Top().ToString();
  s << "\n" << DumpComponents();
  throw SimulationStalled(s.str());
}

std::string Simulator::DumpComponents() const {
  std::ostringstream s;
  for (std::size_t i = 0; i < components_.size(); ++i) {
    const Component& c = *components_[i];
    s << "[" << i << "] " << c.Name() << (c.HasWork() ? " (has work)" : "") << ": " << c.DumpState()
      << "\n";
  }
  return s.str();
}

}  // namespace raycell
