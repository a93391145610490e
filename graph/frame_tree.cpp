#include "graph/frame_tree.h"

namespace raycell {

CellTree BuildFrameTree(const TraceReader& reader, std::size_t frame_index) {
  CellTreeBuilder builder;
  reader.ForEachBatch(frame_index, [&](const RayBatch& b) { builder.AddBatch(b); });
  return builder.Finish();
}

}  // namespace raycell
