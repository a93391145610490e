#include "graph/schedule.h"

#include <utility>

#include "base/check.h"

namespace raycell {

std::string ScheduleRun::ToString() const {
  return std::string(feasible ? "feasible" : "infeasible") + ", " +
         std::to_string(processed_nodes) + " nodes processed, " + std::to_string(useful_fetches) +
         " useful fetches";
}

namespace {

// ready[c]: unprocessed nodes of cell c whose parent is processed.
void MakeReady(const CellTree& tree, NodeId parent, std::vector<std::vector<NodeId>>& ready) {
  for (NodeId c = tree.first_child(parent); c != kNoNode; c = tree.next_sibling(c)) {
    ready[tree.cell(c).value()].push_back(c);
  }
}

}  // namespace

// One pass per entry is enough: the nodes of cell c processed at an entry have no children
// of cell c (a ray's consecutive visits are to different cells, so the builder never makes
// a child with its parent's cell; checked below), so processing them makes no further node
// of c ready within the same entry.
ScheduleRun RunSchedule(const CellTree& tree, const std::vector<CellId>& schedule,
                        std::vector<std::uint32_t>* fetch_of) {
  std::vector<std::vector<NodeId>> ready(tree.cell_count());
  MakeReady(tree, kRootNode, ready);
  ScheduleRun run;
  if (fetch_of != nullptr) fetch_of->assign(tree.size(), kNoFetch);
  std::vector<NodeId> batch;
  for (CellId c : schedule) {
    if (c.value() >= tree.cell_count() || ready[c.value()].empty()) continue;
    batch.clear();
    std::swap(batch, ready[c.value()]);
    if (fetch_of != nullptr) {
      for (NodeId n : batch) (*fetch_of)[n.index()] = std::uint32_t(run.useful_fetches);
    }
    ++run.useful_fetches;
    run.processed_nodes += batch.size();
    for (NodeId n : batch) MakeReady(tree, n, ready);
    RAYCELL_CHECK(ready[c.value()].empty());
  }
  run.feasible = run.processed_nodes == tree.node_count();
  return run;
}

}  // namespace raycell
