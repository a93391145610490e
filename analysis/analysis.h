// What `raycell analyze` reports for one frame's Cell Tree: its size, the maxGen bound, the
// Peel schedule and, for small trees, the exact optimum. Printers live with the command.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "bounds/lower_bound.h"
#include "graph/cell_tree.h"
#include "search/best_schedule.h"

namespace raycell {

// How hard --bracket works on a frame: the budgets of the lower bound and of the schedule
// search, every one counted in states, windows or work (never seconds), so every machine
// reports the same numbers. BracketEffort names the presets.
struct BracketOptions {
  LowerBoundOptions lower;
  BestScheduleOptions best;
  // The lower bound (single-threaded) on a thread of its own while the search runs: the same
  // results, in about the longer of the two times on two cores instead of their sum.
  bool overlap = true;
};
// "quick" (raycell study's default: about a tenth of the work), "default" (analyze
// --bracket: within about a minute per 27-cell frame on 2 cores) or "thorough" (about four
// times the default). InputError naming the option otherwise.
BracketOptions BracketEffort(const std::string& name);

// The board-level split of a cell grid (nx, ny, nz; cell = x + nx*(y + ny*z)) that the
// bracket's schedule search decomposes by (BestScheduleOptions::coarse_of): each cell's 2x2x2
// box of the grid, boxes numbered in the order of their corners. Empty for an unknown grid
// (a zero).
std::vector<CellId> BoardCells(const std::array<std::uint32_t, 3>& grid);

struct AnalyzeOptions {
  bool exact = false;  // also search for the optimum (small trees only)
  std::uint64_t max_states = 2'000'000;
  double max_seconds = 10;
  std::size_t max_nodes = 4096;
  // Also bracket the optimum: the best lower bound and the best schedule found.
  bool bracket = false;
  BracketOptions bracket_options = BracketEffort("default");
};

struct FrameAnalysis {
  std::int32_t frame = 0;
  std::uint64_t rays = 0, nodes = 0;
  std::uint64_t bound = 0;  // sum over cells of maxGen
  std::vector<CellId> peel_schedule;
  std::uint64_t splits = 0;                     // split peels
  std::optional<std::uint64_t> optimum;         // set only when proved optimal
  std::string optimum_status = "not computed";  // or "optimal", "unknown: ...", ...
  // With --bracket (docs/design.md §1 "Lower bounds beyond maxGen"): the optimum lies in
  // [lower_bound, best_length]; optimum is set when they meet or a search proves it.
  std::optional<std::uint64_t> lower_bound;  // the best proven lower bound, >= bound
  std::string lower_bound_method;            // e.g. "ip(pairs,triples,blocks)+cuts"
  std::optional<std::uint64_t> best_length;  // the shortest feasible schedule found
  std::vector<CellId> best_schedule;         // that schedule, checked feasible
  std::string best_method;                   // e.g. "beam(256)+lns(4x20000)"
  // (best_length - lower_bound) / lower_bound; 0 for an empty tree.
  std::optional<double> gap() const;
  double seconds = 0;  // building the tree, Peel and (if asked) the exact search
  double rays_per_node() const { return nodes ? double(rays) / double(nodes) : 0.0; }
  std::uint64_t peel_length() const { return peel_schedule.size(); }
};

// Bound and Peel (and the optimum when options.exact) of a tree; `seconds` covers only
// this analysis, the caller adds the time it took to build the tree.
FrameAnalysis AnalyzeTree(const CellTree& tree, const AnalyzeOptions& options);

}  // namespace raycell
