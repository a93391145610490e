// Human- and tool-readable views of a trace file: a summary (`raycell trace info`) and one JSON
// object per ray (`raycell trace cat`).
#pragma once

#include <cstddef>
#include <optional>
#include <ostream>
#include <string>

#include "traces/trace_reader.h"

namespace raycell {

// Header (format version, producer, scene, grids, box, cell grid, footprints, settings),
// then one table row per frame: rays by kind, visits, samples, compressed bytes and bytes
// per visit, and totals with the compression ratio against a naive uncompressed encoding
// of 24 bytes per ray and 16 per visit (stated in the output).
void PrintInfo(const TraceReader& reader, const std::string& path, std::ostream& out);

// One ray per line, exactly (no spaces):
//   {"id":7,"parent":3,"spawn":2,"kind":"reflection","pixel":[x,y],"cells":[5,4,1],"samples":[12,30,2]}
// with "parent":null,"spawn":null for primary rays. Ids are frame-local. With a frame index,
// writes that frame; without, writes every frame in file order, and when the file has more
// than one frame each line starts with the frame number: {"frame":150,"id":7,...}.
// t_enter/t_exit are not written. Throws InputError for unreadable frames.
void WriteJsonl(const TraceReader& reader, std::optional<std::size_t> frame_index,
                std::ostream& out);

}  // namespace raycell
