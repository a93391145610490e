// Choosing a trace's frames on the command line (--frames A..B), for replay and sweep.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "traces/trace_reader.h"

namespace raycell {

// Indices into reader.frames() of the frames whose numbers lie in `range` ("A..B", "A-B"
// or "A"; empty: every frame). InputError if the range is malformed or selects none.
std::vector<std::size_t> SelectFrameRange(const TraceReader& reader, const std::string& range);

}  // namespace raycell
