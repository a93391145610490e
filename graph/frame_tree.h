// A frame's Cell Tree read from a trace (docs/design.md §1 "Cell Tree"): the batches of one
// frame streamed through CellTreeBuilder, so the frame's rays are never all in memory.
#pragma once

#include <cstddef>

#include "graph/cell_tree.h"
#include "traces/trace_reader.h"

namespace raycell {

// Builds frame `frame_index`'s Cell Tree by streaming its batches.
CellTree BuildFrameTree(const TraceReader& reader, std::size_t frame_index);

}  // namespace raycell
