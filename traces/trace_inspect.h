// A human-readable summary of a trace file (`raycell trace info`). The rays as JSON Lines
// (`raycell trace cat`) are in traces/jsonl.h.
#pragma once

#include <cstddef>
#include <ostream>
#include <string>

#include "traces/trace_reader.h"

namespace raycell {

// Header (format version, producer, scene, grids, box, cell grid, footprints, the frames'
// range and the camera path it is a range of, settings),
// then one table row per frame: rays by kind, visits, samples, compressed bytes and bytes
// per visit, and totals with the compression ratio against a naive uncompressed encoding
// of 24 bytes per ray and 16 per visit (stated in the output).
void PrintInfo(const TraceReader& reader, const std::string& path, std::ostream& out);

}  // namespace raycell
