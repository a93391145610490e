// Joining captures of consecutive frame ranges of one camera path into one trace
// (`raycell trace concat`; docs/design.md §3 "Joining captures").
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace raycell {

struct ConcatSummary {
  std::size_t inputs = 0, frames = 0;
  std::int32_t first_frame = 0, last_frame = 0;
  std::uint64_t bytes = 0;  // of the output
};

// Writes to `out` the trace of the frames of `inputs` (given in any order) as one capture
// of their union would be, byte for byte: the inputs must be complete captures (intact
// index) of format version 3 or later, equal in everything but their frames (scene, grids,
// box, cell grid, footprints, settings, camera path, producer), whose frame ranges are
// consecutive once sorted. Each frame's zstd frame is checked (ReadEncodedFrame) and copied
// as it is; only the header and the index are written anew. Anything else is an InputError
// naming the input(s) and the difference, and nothing is written: the output has no name
// until it is complete (then OUT.tmp, renamed to OUT).
ConcatSummary ConcatTraces(const std::vector<std::string>& inputs, const std::string& out);

}  // namespace raycell
