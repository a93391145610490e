#include "graph/analysis.h"

#include <chrono>

#include "graph/optimum.h"
#include "graph/peel.h"

namespace raycell {

CellTree BuildFrameTree(const TraceReader& reader, std::size_t frame_index) {
  CellTreeBuilder builder;
  reader.ForEachBatch(frame_index, [&](const RayBatch& b) { builder.AddBatch(b); });
  return builder.Finish();
}

FrameAnalysis AnalyzeTree(const CellTree& tree, const AnalyzeOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  FrameAnalysis a;
  a.rays = tree.rays();
  a.nodes = tree.node_count();
  a.bound = Bound(tree);
  PeelResult peel = Peel(tree);
  a.peel_schedule = std::move(peel.schedule);
  a.splits = peel.split_peels;
  if (options.exact) {
    OptimumLimits limits;
    limits.max_states = options.max_states;
    limits.max_seconds = options.max_seconds;
    limits.max_nodes = options.max_nodes;
    const OptimumResult r = ExactOptimum(tree, limits);
    if (r.status == OptimumResult::kOptimal) {
      a.optimum = r.length;
      a.optimum_status = "optimal";
    } else {
      a.optimum_status =
          (r.status == OptimumResult::kTooLarge ? "too large: " : "unknown: ") + r.reason;
    }
  }
  a.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return a;
}

}  // namespace raycell
