// Lower bounds on the fewest fetches of any feasible schedule of a Cell Tree (one-cell cache),
// stronger than maxGen (docs/design.md §1 "Lower bounds beyond maxGen").
//
// For groups S of cells, the SCS of the tree's paths projected onto S (bounds/projection.h,
// bounds/scs.h) bounds the fetches of cells of S. The groups (pairs and triples of cells that
// share paths; blocks of neighbouring cells from the grid, or clusters of cells that share
// many paths without it; all cells when there are at most max_block_cells) are combined by an
// integer program over per-cell fetch counts x_c: x_c >= maxGen(c), sum_{c in S} x_c >= SCS(S)
// for every group, minimise sum x_c. Then cuts: when the program's counts restricted to a
// group admit no common supersequence of that group's projections (a budget search proves
// it), a constraint "some c in S has x_c >= u_c + 1" excludes them and every count vector
// below u (u: the counts, raised cell by cell while still not realisable, for groups of at
// most max_lift_cells), and the program is solved again. When no group cuts the counts,
// unions of two intersecting groups whose rows the counts meet with equality are tried. Every
// step keeps the count vector of an optimal schedule feasible, so the program's optimum never
// exceeds the optimal schedule length; the argument for each is beside its code in
// lower_bound.cpp.
//
// Cost: dominated by the SCS and budget searches, each limited in states, and all together by
// max_total_states (deterministic: no time limit). With the defaults, a 27-cell frame of
// ~2,700-3,600 nodes takes about 15-50 s of CPU and under 100 MB (BENCHMARKS.md "Lower
// bounds at 27 cells"); an 8-cell frame well under a second. The SCS heuristic's
// sub-searches (bounds/scs.h) are limited per sub-search, not counted in max_total_states. Trees
// with many cells and few nodes are cheap: pairs and triples are taken only among cells that share
// a root-to-leaf path (at most max_triples triples), blocks only where cells have nodes.
// Projections cost the group's nodes (bounds/projection.h TreeProjector); the program's
// branch and bound is limited in nodes and in nodes times rows (max_ip_work). On 512-cell
// frames of 316,718-375,820 nodes, `analyze --bracket --effort quick` (bound and search) took
// 113 s of CPU for 4 frames and 142 MB at most.
// Single-threaded.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "graph/cell_tree.h"

namespace raycell {

struct LowerBoundOptions {
  // The cell grid (nx, ny, nz), cell = x + nx*(y + ny*z), when known: blocks of neighbouring
  // cells are then taken from it. All zero: unknown; blocks are grown from cells that share
  // paths instead. A grid with fewer cells than tree.cell_count() is an InputError.
  std::array<std::uint32_t, 3> grid{0, 0, 0};
  bool pairs = true;    // every pair of cells sharing a path
  bool triples = true;  // triples of cells whose pairs interact
  bool blocks = true;   // blocks of neighbouring cells
  bool cuts = true;     // cuts for count vectors that a group cannot realise
  std::size_t max_triples = 3000;
  std::size_t max_blocks = 400;
  std::uint64_t max_group_states = 50'000;  // per SCS search
  // The SCS searches' heuristic merges pairs into parts of up to 4 cells (ScsSolver's
  // merge_parts) for groups of 8 cells or more: group bounds rise by 2-3 on 8-12-cell blocks
  // of a 27-cell frame, but the whole bound did not (BENCHMARKS.md "Lower bounds at 27
  // cells") and the cost varies a lot between frames, so it is off by default. Groups of at
  // least large_group_cells cells then get max_large_group_states states.
  bool merged_parts = false;
  std::size_t large_group_cells = 8;
  std::uint64_t max_large_group_states = 5'000;
  std::uint64_t max_cut_states = 20'000;       // per budget search (cuts)
  std::size_t max_cut_group_cells = 10;        // cuts only for groups of at most this many cells
  std::uint32_t max_block_cells = 12;          // blocks of at most this many cells
  std::size_t max_lift_cells = 4;              // cuts of larger groups are not lifted
  std::uint64_t max_total_states = 2'500'000;  // all searches together
  std::uint32_t max_cut_rounds = 200;          // solve-check-cut rounds
  std::uint64_t max_ip_nodes = 200'000;        // branch-and-bound nodes per program
  // And per program at most max_ip_work / rows nodes (rows: the program's): a node's LP costs
  // about its rows, and at hundreds of cells the pairs' program (thousands of rows, an LP
  // optimum of halves) would spend hours closing a gap of one. A program stopped by it reports
  // its best open node's bound, still a proof.
  std::uint64_t max_ip_work = 1'000'000;
};

// One group whose projection bounds its cells' fetches above the sum of their maxGen.
struct GroupBound {
  std::vector<CellId> cells;      // increasing
  std::uint32_t strings = 0;      // projected strings after dominance removal
  std::uint32_t max_gen_sum = 0;  // sum of maxGen over the cells
  std::uint32_t scs_lower = 0;    // proven lower bound on the SCS of the projection
  bool exact = false;             // scs_lower is the SCS
  std::uint64_t states = 0;
};

// The bound after each stage, in order; each is >= the one before.
struct LowerBoundStage {
  std::string name;  // "maxgen", "pairs matching", "ip(pairs,triples)", "+blocks", "+cuts"
  std::uint64_t value = 0;
  std::uint64_t states = 0;  // search states used up to and including this stage
  double seconds = 0;        // wall time up to and including this stage (not deterministic)
};

struct LowerBoundResult {
  std::uint64_t value = 0;    // the bound: >= max_gen, <= the optimum
  std::uint64_t max_gen = 0;  // Bound(tree)
  std::string method;         // the last stage that raised the bound, e.g. "ip(pairs,triples)+cuts"
  std::vector<LowerBoundStage> stages;
  std::vector<GroupBound> groups;  // groups above their maxGen sum, in the order computed
  std::size_t cuts = 0;            // cuts added
  // Pairs of cells on a common path, and of them those whose paths cross (some path has a
  // before b, some b before a): only those can gain over maxGen and are searched.
  std::size_t pairs_sharing = 0, pairs_conflicting = 0;
  std::size_t tiles = 0;  // blocks that tile the grid, searched first (more boxes than max_blocks)
  std::uint64_t states = 0;     // search states used in total
  bool limits_reached = false;  // some search or the program stopped at a limit
  // value is the optimum: a group held every cell with nodes and its SCS search was exact.
  bool optimal = false;
  // One line: "lower bound 79 (maxGen 63; ip(pairs,triples,blocks)+cuts; 214 groups, 31 cuts,
  // 1234567 states)".
  std::string ToString() const;
};

// A lower bound on the fewest fetches of any feasible schedule of `tree`, never below
// Bound(tree) and never above the optimum. Deterministic: the same tree and options give the
// same result (except the stages' seconds).
LowerBoundResult LowerBound(const CellTree& tree, const LowerBoundOptions& options = {});

}  // namespace raycell
