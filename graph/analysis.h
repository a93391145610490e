// What `raycell analyze` reports for one frame's Cell Tree: its size, the maxGen bound, the
// Peel schedule and, for small trees, the exact optimum. Printers live with the command.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "graph/cell_tree.h"
#include "traces/trace_reader.h"

namespace raycell {

struct AnalyzeOptions {
  bool exact = false;  // also search for the optimum (small trees only)
  std::uint64_t max_states = 2'000'000;
  double max_seconds = 10;
  std::size_t max_nodes = 4096;
};

struct FrameAnalysis {
  std::int32_t frame = 0;
  std::uint64_t rays = 0, nodes = 0;
  std::uint64_t bound = 0;  // sum over cells of maxGen
  std::vector<CellId> peel_schedule;
  std::uint64_t splits = 0;                     // split peels
  std::optional<std::uint64_t> optimum;         // set only when proved optimal
  std::string optimum_status = "not computed";  // or "optimal", "unknown: ...", ...
  double seconds = 0;  // building the tree, Peel and (if asked) the exact search
  double rays_per_node() const { return nodes ? double(rays) / double(nodes) : 0.0; }
  std::uint64_t peel_length() const { return peel_schedule.size(); }
};

// Builds frame `frame_index`'s Cell Tree by streaming its batches.
CellTree BuildFrameTree(const TraceReader& reader, std::size_t frame_index);

// Bound and Peel (and the optimum when options.exact) of a tree; `seconds` covers only
// this analysis, the caller adds the time it took to build the tree.
FrameAnalysis AnalyzeTree(const CellTree& tree, const AnalyzeOptions& options);

}  // namespace raycell
