#include "tests/oracle/simulator.h"

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
  calendar_ = dynamic_cast<CalendarQueue*>(queue_.get());
}

ComponentId Simulator::Add(Component& component) {
  RAYCELL_CHECK_LT(components_.size(), std::size_t(UINT32_MAX));
  components_.push_back(&component);
  return ComponentId(components_.size() - 1);
}

RunStatus Simulator::Run(SimTime until) {
  if (calendar_ != nullptr) return RunOn(*calendar_, until);  // Push/Pop inline, not virtual
  return RunOn(*queue_, until);
}

template <typename Queue>
RunStatus Simulator::RunOn(Queue& queue, SimTime until) {
  stop_requested_ = false;
  const bool bounded = until != SimTime::Max();  // else no event can lie after `until`
  while (pending_ != 0) {  // the queue's size, without a virtual call per event
    if (bounded && queue.Top().time > until) {
      now_ = until;
      return RunStatus::kReachedUntil;
    }
    --pending_;
    Dispatch(queue.Pop());
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
