// The cells a memory level of coarser cells holds, and every level's units (level.NAME.cells;
// docs/design.md §2 "Levels of coarser cells"), made from a regroupable capture's stored fine grid
// (TraceReader::SubdivideFineGrid): the units of replay/memory.h LevelUnits.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "replay/config.h"
#include "replay/memory.h"
#include "traces/cell_id.h"
#include "traces/trace_reader.h"

namespace raycell {

// A level's coarser cells over the replay's cells.
struct LevelCells {
  // Per cell of the replay (the reader's view), the coarse cell holding it (an empty cell,
  // never fetched: 0).
  std::vector<CellId> of_cell;
  // Per coarse cell, its footprint (its fine cells' leaves, each once).
  std::vector<std::uint64_t> bytes;
};

// The cells of `cells` (a SPEC, traces/subdivision.h, not dynamic) over the cells of
// `reader`'s view, for a memory level that holds coarser cells. InputError prefixed with
// `what` (the key, "level.NAME.cells") when the trace is not a regroupable capture opened
// regrouped (TraceReader::Open), is shown as a dynamic subdivision, `cells` is a bad or
// dynamic SPEC or one the fine grid cannot make, or a cell of the view is not inside one
// coarse cell.
LevelCells CoarserLevelCells(const TraceReader& reader, const std::string& cells,
                             const std::string& what);

// What each level of `config` stores and moves on `reader`'s cells (replay/memory.h
// LevelUnits): empty when every level holds the replay's cells. InputError naming the key
// (level.NAME.cells) when a level's cells cannot be made (level_units.h CoarserLevelCells: not a
// regroupable capture, cells that are not unions of the replay's) or do not nest in the cells
// of the level below it.
MemoryUnits LevelUnitsOf(const ReplayConfig& config, const TraceReader& reader);

}  // namespace raycell
