// Regrouping a regroupable capture into a subdivision and writing it as a trace of its own
// (`raycell trace regroup`; docs/design.md §1 "Subdivisions").
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace raycell {

struct RegroupSummary {
  std::size_t frames = 0;
  std::uint32_t cells = 0;                    // of the subdivision
  std::uint64_t fine_visits = 0, visits = 0;  // stored in the input, written to the output
  std::uint64_t rays = 0, bytes = 0;          // written
};

// Writes to `out` the capture `in` (recorded with `raycell record --regroupable`) regrouped
// into the subdivision `spec` (traces/subdivision.h; empty: its own grid, its visits to empty
// cells dropped): the trace a capture recorded on those cells would be, with the subdivision
// in its header (TraceHeader::subdivision). InputError for an input that is not a complete,
// intact regroupable capture, a bad SPEC, or `out` naming the input; nothing is written then:
// the output has no name until it is complete.
RegroupSummary RegroupTrace(const std::string& in, const std::string& spec, const std::string& out);

}  // namespace raycell
