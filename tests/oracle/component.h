// A simulated component (SST style): it reacts to events addressed to it and talks to other
// components only by scheduling events through the Simulator, never through pointers into
// them, so each can be tested alone against a fake neighbour.
#pragma once

#include <string>

#include "engine/event.h"

namespace raycell {

class Simulator;

class Component {
 public:
  virtual ~Component() = default;
  // Called once per event addressed to this component, in (time, priority, seq) order.
  virtual void Handle(const Event& event, Simulator& sim) = 0;
  // "processor 0", for logs and the watchdog dump.
  virtual std::string Name() const = 0;
  // A one-line or multi-line summary of the component's state for the watchdog dump.
  virtual std::string DumpState() const { return ""; }
  // True while the component has unfinished work (queued requests, rays waiting). If the
  // event queue runs dry while some component has work, the simulation is stalled.
  virtual bool HasWork() const { return false; }
};

}  // namespace raycell
