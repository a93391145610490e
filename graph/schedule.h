// Schedules and feasibility (docs/design.md §1 "Schedule and feasibility"). Independent of
// Peel: this is the checker Peel's output is tested against.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "graph/cell_tree.h"

namespace raycell {

struct ScheduleRun {
  bool feasible = false;            // every node was processed
  std::size_t processed_nodes = 0;  // without the root
  std::size_t useful_fetches = 0;   // entries that processed at least one node
  // "feasible, 7/7 nodes, 5 useful fetches".
  std::string ToString() const;
};

// Runs `schedule` on `tree`: at each entry c, every unprocessed node of cell c whose parent
// is processed (the root counts as processed) is processed. Cells >= tree.cell_count() are
// allowed and process nothing. O(nodes + schedule length). With `fetch_of`, also per node the
// useful fetch that processed it, numbered from 0 in schedule order (kNoFetch: unprocessed,
// and the root).
inline constexpr std::uint32_t kNoFetch = ~std::uint32_t{0};
ScheduleRun RunSchedule(const CellTree& tree, const std::vector<CellId>& schedule,
                        std::vector<std::uint32_t>* fetch_of = nullptr);
inline bool IsFeasible(const CellTree& tree, const std::vector<CellId>& schedule) {
  return RunSchedule(tree, schedule).feasible;
}

}  // namespace raycell
