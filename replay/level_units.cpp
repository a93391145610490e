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
  if (shown.rfind("dynamic:", 0) == 0) {
    throw InputError(what + ": '" + cells + "' cannot hold the cells of " + reader.path() +
                     " shown as a dynamic subdivision (--cells " + shown +
                     "): they are other boxes every frame");
  }
  const SubdivisionSpec spec = ParseSubdivisionSpec(cells, what);
  if (spec.kind == SubdivisionSpec::Kind::kDynamic) {
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

}  // namespace raycell
