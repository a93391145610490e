#include "traces/format.h"

#include "base/check.h"
#include "traces/trace_header.h"

namespace raycell {

std::string TraceCellGridProblem(const std::array<std::uint32_t, 3>& cells) {
  const std::string grid = "cell grid " + std::to_string(cells[0]) + "x" +
                           std::to_string(cells[1]) + "x" + std::to_string(cells[2]);
  if (cells[0] == 0 || cells[1] == 0 || cells[2] == 0) {
    return grid + ": every dimension must be at least 1";
  }
  const std::uint64_t n = TraceCellCount(cells);
  if (n > kTraceMaxCells) {
    return grid + " = " + std::to_string(n) + " cells exceeds the trace format's limit of " +
           std::to_string(kTraceMaxCells) + " cells (kTraceMaxCells, e.g. 256x256x256)";
  }
  return "";
}

namespace {

std::string TextProblem(const std::string& text, const std::string& field) {
  if (text.size() <= kTraceMaxTextBytes) return "";
  return field + " has " + std::to_string(text.size()) + " bytes, more than the trace format's " +
         "limit of " + std::to_string(kTraceMaxTextBytes) + " (kTraceMaxTextBytes)";
}

}  // namespace

std::string TraceHeaderProblem(const TraceHeader& h) {
  std::string problem = TraceCellGridProblem(h.cells);
  if (!problem.empty()) return problem;
  if (h.cameras.size() > kTraceMaxFrames) {
    return std::to_string(h.cameras.size()) + " cameras (frames) exceed the trace format's " +
           "limit of " + std::to_string(kTraceMaxFrames) + " (kTraceMaxFrames)";
  }
  if (h.path.keys.size() > kTraceMaxFrames) {
    return "a camera path of " + std::to_string(h.path.keys.size()) + " key frames exceeds the " +
           "trace format's limit of " + std::to_string(kTraceMaxFrames) + " (kTraceMaxFrames)";
  }
  if (h.grids.size() > kTraceMaxGrids) {
    return std::to_string(h.grids.size()) + " grids exceed the trace format's limit of " +
           std::to_string(kTraceMaxGrids) + " (kTraceMaxGrids)";
  }
  for (const auto& [text, field] :
       {std::pair{&h.producer, "the producer"}, std::pair{&h.scene, "the scene"},
        std::pair{&h.footprint_mode, "the footprint mode"},
        std::pair{&h.path.kind, "the camera path's kind"},
        std::pair{&h.subdivision.spec, "the subdivision's SPEC"}}) {
    if (!(problem = TextProblem(*text, field)).empty()) return problem;
  }
  for (const GridInfo& g : h.grids) {
    for (const std::string* text : {&g.name, &g.role, &g.source}) {
      if (!(problem = TextProblem(*text, "a grid's name, role or source")).empty()) return problem;
    }
  }
  if (h.leaves.bytes.size() > kTraceMaxLeaves || h.leaves.leaves.size() > kTraceMaxLeafRefs) {
    return std::to_string(h.leaves.bytes.size()) + " leaves and " +
           std::to_string(h.leaves.leaves.size()) + " (cell, leaf) pairs exceed the trace " +
           "format's limits of " + std::to_string(kTraceMaxLeaves) + " and " +
           std::to_string(kTraceMaxLeafRefs) + " (kTraceMaxLeaves, kTraceMaxLeafRefs)";
  }
  if (h.subdivision.boxes.size() > kTraceMaxBoxes) {
    return "a subdivision of " + std::to_string(h.subdivision.boxes.size()) + " boxes exceeds " +
           "the trace format's limit of " + std::to_string(kTraceMaxBoxes) + " (kTraceMaxBoxes)";
  }
  return "";
}

void CheckTraceCellGrid(const std::array<std::uint32_t, 3>& cells, const std::string& what) {
  const std::string problem = TraceCellGridProblem(cells);
  if (!problem.empty()) throw InputError(what + ": " + problem);
}

}  // namespace raycell
