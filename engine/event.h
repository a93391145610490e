// An event of the discrete-event core (docs/design.md §2): a small plain struct, no callable per
// event, so millions of pending events cost 40 bytes each. The engine knows nothing of what
// `kind` and `payload` mean; the target component does.
#pragma once

#include <cstdint>
#include <string>

#include "engine/time.h"

namespace raycell {

// Index of a component in its Simulator, in registration order.
using ComponentId = std::uint32_t;

struct Event {
  SimTime time;               // when it is delivered
  std::int32_t priority = 0;  // lower first among events at the same time
  std::uint64_t seq = 0;      // insertion order, assigned by the Simulator; last tie-break
  ComponentId target = 0;
  std::uint32_t kind = 0;     // meaning defined by the target component
  std::uint64_t payload = 0;  // meaning defined by the target component

  // "t=10ps prio=0 seq=3 target=1 kind=2 payload=7".
  std::string ToString() const;
};

// The engine's total order: (time, priority, seq). seq is unique per simulator, so no two
// events compare equal and a run is deterministic.
inline bool EventBefore(const Event& a, const Event& b) {
  if (a.time != b.time) return a.time < b.time;
  if (a.priority != b.priority) return a.priority < b.priority;
  return a.seq < b.seq;
}

}  // namespace raycell
