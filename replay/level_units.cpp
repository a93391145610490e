#include "replay/level_units.h"

#include <utility>

#include "base/check.h"
#include "traces/subdivision.h"

namespace raycell {

LevelCells CoarserLevelCells(const TraceReader& reader, const std::string& cells,
                             const std::string& what) {
  if (!reader.regrouped()) {
    throw InputError(what + ": '" + cells + "' needs a regroupable capture (raycell record " +
                     "--regroupable): a coarse cell's footprint counts each leaf once, which " +
                     reader.path() + " cannot tell");
  }
  const std::string& shown = reader.header().subdivision.spec;  // the view's cells
  if (reader.header().subdivision.dynamic()) {
    throw InputError(what + ": '" + cells + "' cannot hold the cells of " + reader.path() +
                     " shown as a dynamic subdivision (--cells " + shown +
                     "): they are other boxes every frame");
  }
  const SubdivisionSpec spec = ParseSubdivisionSpec(cells, what);
  if (spec.per_frame()) {
    throw InputError(what + ": '" + cells + "': a memory level's cells stay the same over the " +
                     "frames");
  }
  FineSubdivision fine;
  try {
    fine = reader.SubdivideFineGrid(spec);
  } catch (const InputError& e) {
    throw InputError(what + ": " + e.what());
  }
  LevelCells out;
  out.bytes = std::move(fine.footprints);
  const std::vector<CellId>& view = fine.view_of_fine;
  const std::uint32_t n = std::uint32_t(reader.header().cell_count());
  std::vector<bool> seen(n, false);
  out.of_cell.assign(n, CellId(0));  // an empty cell, never fetched: 0
  for (std::size_t f = 0; f < view.size(); ++f) {
    if (view[f] == kNoCell) continue;
    const std::uint32_t v = view[f].value();
    const CellId c = fine.subdivision.coarse_of_fine[f];
    if (seen[v] && out.of_cell[v] != c) {
      throw InputError(what + ": '" + cells + "' does not hold whole cells of the replay (" +
                       (shown.empty() ? "the captured grid" : shown) + "): its cells " +
                       std::to_string(out.of_cell[v].value()) + " and " +
                       std::to_string(c.value()) + " share cell " + std::to_string(v) +
                       "; use a subdivision whose boundaries include the replay's");
    }
    seen[v] = true;
    out.of_cell[v] = c;
  }
  return out;
}

MemoryUnits LevelUnitsOf(const ReplayConfig& config, const TraceReader& reader) {
  MemoryUnits units(config.levels.size());
  bool any = false;
  for (std::size_t i = 0; i < config.levels.size(); ++i) {
    const LevelConfig& level = config.levels[i];
    if (level.cells.empty()) continue;
    LevelCells coarse = CoarserLevelCells(reader, level.cells, "level." + level.name + ".cells");
    units[i].unit_of_cell = std::move(coarse.of_cell);
    units[i].bytes = std::move(coarse.bytes);
    any = true;
  }
  // Each level's units lie in one unit of the level below it (a fetch that misses brings the
  // missing level's unit from the one below, which must hold all of it).
  const std::uint32_t cells = std::uint32_t(reader.header().cell_count());
  const auto unit = [&](std::size_t i, std::uint32_t c) {
    return units[i].identity() ? c : units[i].unit_of_cell[c].value();
  };
  for (std::size_t i = 2; any && i < config.levels.size(); ++i) {
    std::vector<std::uint32_t> below(UnitCount(&units, i - 1, cells), UINT32_MAX);
    for (std::uint32_t c = 0; c < cells; ++c) {
      std::uint32_t& b = below[unit(i - 1, c)];
      if (b != UINT32_MAX && b != unit(i, c)) {
        const LevelConfig &above = config.levels[i - 1], &level = config.levels[i];
        throw InputError("level." + level.name + ".cells: '" +
                         (level.cells.empty() ? "same" : level.cells) + "' splits cell " +
                         std::to_string(unit(i - 1, c)) + " of level." + above.name + ".cells '" +
                         above.cells +
                         "': a level's cells must be unions of the cells of the level above it");
      }
      b = unit(i, c);
    }
  }
  if (!any) units.clear();
  return units;
}

}  // namespace raycell
