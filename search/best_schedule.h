// The shortest schedule we can find for a Cell Tree (docs/design.md §1 "Schedule and
// feasibility"), far shorter than Peel's on real frames: Peel, a beam search
// (search/beam_search.h), for small trees the exact search (search/optimum.h) with the best
// schedule so far as its incumbent (it proves it optimal or brackets the optimum), then
// several seeded local-search chains from the best schedule (search/local_search.h), and
// the exact search again if they shortened it. Each step is skipped once the best schedule
// meets the lower bound (then it is optimal).
//
// Every schedule returned is checked with the independent checker (graph/schedule.h
// IsFeasible) before it is returned. Deterministic: every limit counts states, windows or
// work; chains have seeds derived from `seed` and their own RNGs, and the best chain wins
// (shortest, then lowest chain number), so the result is the same for any thread count.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "graph/cell_tree.h"
#include "search/late_bound.h"
#include "search/local_search.h"

namespace raycell {

struct BestScheduleOptions {
  std::uint64_t seed = 1;
  std::size_t beam_width = 256;                      // 0: no beam search
  std::uint64_t beam_max_node_visits = 500'000'000;  // BeamOptions::max_node_visits
  // Local search: `chains` independent chains (0: none), each with `local` (its seed is
  // derived from `seed` and the chain number).
  std::size_t chains = 4;
  LocalSearchOptions local;
  // Chain i's windows are shifted by -4, -2, 0, +2 entries (i % 4; at least 1 entry), and
  // only the odd chains have large windows (LocalSearchOptions::large_every): a portfolio of
  // neighbourhoods.
  bool vary_windows = true;
  std::size_t threads = 0;  // chains run at once; 0: the hardware's threads
  // Exact search with the best schedule as incumbent, on trees of at most exact_max_nodes
  // nodes (0 states: never).
  // The default runs it on the 8-cell frames of the study (300-450 nodes), not on the
  // 27-cell ones (3,000-3,600 nodes), where it proves nothing and holds ~400 MiB.
  std::uint64_t exact_states = 50000;
  std::size_t exact_max_nodes = 1000;
  // A board-level split (empty: none): per cell of the tree, the coarser cell holding it (e.g.
  // the 2x2x2 boxes of the cell grid). When the beam's work limit would cut its width on the
  // whole tree (width x Peel's length x nodes above beam_max_node_visits, as on frames of
  // hundreds of cells), a two-level schedule (graph/peel.h TwoLevelSchedule) is offered too,
  // after Peel: the coarse cells ordered by a beam search of the contracted tree, each entry's
  // forest by a beam search of its own, each with the full width and a share of
  // beam_max_node_visits in proportion to its nodes, so its cost grows with the tree about
  // linearly; the local search then starts from the shorter of it and the whole tree's beam.
  std::vector<CellId> coarse_of;
  // A known lower bound on the optimum (0: none): the search stops as soon as a schedule
  // meets it (that schedule is then optimal).
  std::uint64_t lower_bound = 0;
  // Or one published by another thread while the search runs (null: none): the search stops
  // once a schedule meets the value known at the time, waits for it before the exact search
  // and at the end (it is then part of `lower`), and returns what it would have returned with
  // the value given as lower_bound (search/late_bound.h says why).
  const LateBound* late_lower_bound = nullptr;
};

struct BestScheduleResult {
  std::vector<CellId> schedule;  // the shortest found; feasible
  std::size_t length = 0;
  // How it was found: "peel", "beam(256)", "beam(256)+lns(4x20000)", "...+exact".
  std::string method;
  std::size_t peel_length = 0, beam_length = 0, local_length = 0;  // 0: not run
  std::size_t two_level_length = 0;  // the two-level schedule's (coarse_of); 0: not run
  std::uint64_t bound = 0;           // maxGen bound
  // The optimum is in [lower, length]: lower is the largest of the bound, the given lower
  // bound and what the exact search proved. optimal when lower == length.
  std::uint64_t lower = 0;
  bool optimal = false;
  // Or the exact search's last answer: "optimal 22 (55 states): ..." or
  // "unknown in [71, 83] (50000 states): ...".
  std::string exact_status = "not run";
  std::uint64_t beam_states = 0, windows = 0, work = 0, exact_states = 0;
  std::uint64_t large_windows = 0;  // of the windows, large ones (LocalSearchOptions)
  // "84 (beam(256)+lns(4x20000); Peel 114, beam 99, local search 84, bound 63, lower 63)".
  std::string ToString() const;
};

BestScheduleResult BestSchedule(const CellTree& tree, const BestScheduleOptions& options = {});

}  // namespace raycell
