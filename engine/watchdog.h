// The watchdog of a discrete-event run (ChampSim): a run that handles this many events in a
// row without progress (a unit done, for the replay) is stalled, and stops with a dump of its
// state instead of spinning. One limit for every loop: the replay's batch core
// (replay/replayer.cpp Board::Run) and the reference engine it is checked against
// (tests/oracle/simulator.h SimulatorOptions::watchdog_events).
#pragma once

#include <cstdint>
#include <stdexcept>

namespace raycell {

// Events without progress before a run is declared stalled.
inline constexpr std::uint64_t kWatchdogEvents = 10'000'000;

// Thrown when the watchdog fires, or when no event is pending while work remains. The message
// names the reason, the time and the state of what was being simulated.
class SimulationStalled : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace raycell
