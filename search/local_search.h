// Local search for short schedules: improves a feasible schedule by re-solving windows of it
// (a large-neighbourhood search).
//
// A window is entries i..j-1 of the schedule; the rest stays fixed. Which nodes the window
// must process is exact (graph/forest.h, ScheduleTimes): the sub-forest
// D = {n : i <= earliest[n], latest[n] < j}, and any feasible schedule of D may replace the
// window, no other. So a window is a problem of its own:
//  - windows of at most exact_window entries are solved exactly (search/optimum.h
//    FindShorter, schedules no longer than the window, ties broken by a fresh seed): a
//    shorter schedule shortens the whole one; one of the same length (a plateau move)
//    changes which nodes later windows hold, which lets the search walk between schedules
//    of one length until a shorter one appears;
//  - longer windows, and windows whose exact search ran out of states, by a beam search of
//    D (search/beam_search.h, a fresh seed each time, schedules no longer than the window).
// One window in large_every on average (a random draw) is a large one, of large_min to
// large_max entries, always given to the beam search. Measured in node visits on frame 0 of
// the 27-cell study capture: an exact window of 20 entries costs ~12 times one of 16, of 24
// entries ~130 times; a beam window of 20-30 entries ~20 times. Large windows move work
// across a longer stretch (two fetches of one cell are often 20-30 entries apart) and reach
// schedules that the short exact windows, plateau moves and kicks do not: on the study's
// 27-cell frames 0, 5, 10, 15, 20 four chains of 10^9 node visits each gave 84 87 88 85 89
// without them (on 0, 5, 10 the same with four times the work), 83 86 87 84 89 with one in two
// large (BestSchedule mixes chains with and without them: search/best_schedule.cpp).
// After every change, entries that no node needs (no node has earliest == latest == p) are
// deleted, one at a time.
//
// Kicks: after kick_after windows without a shorter schedule, kick_size fetches of random
// cells are inserted at random places (the schedule stays feasible, a little longer), and
// the walk goes on from there; a walk more than kick_slack entries above the best schedule
// found restarts from that best. The best schedule found is returned.
//
// Deterministic: windows, seeds and kicks are drawn from a seeded std::mt19937_64 with our
// own bounded draw (search/search_util.h), and every limit counts windows or work, never
// time.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "graph/cell_tree.h"
#include "graph/forest.h"
#include "search/late_bound.h"

namespace raycell {

struct LocalSearchOptions {
  std::uint64_t seed = 1;
  std::uint64_t max_windows = 20000;  // windows re-solved: the iteration limit
  // Work limit, in node visits (window searches, re-timing the schedule after a change), so
  // that huge trees stop early instead of running for hours: a 27-cell frame of the study
  // (3,400 nodes) needs 2e8-1e9 for 20000 windows, a tree of 10^5 nodes 2e9 for its
  // re-timings alone.
  std::uint64_t max_work = 1'000'000'000;
  // Re-timings of the whole schedule (each a pass over every node: after the start, after
  // every change and every deletion): the search stops when they reach this, and so does the
  // deletion of idle entries (the schedule stays feasible). On large trees they are most of
  // the cost (scheduling/best_scheduler.h PlanEffort). Default: no limit.
  std::uint64_t max_retimes = ~std::uint64_t{0};
  // Memory of one window's exact search (its states and open list); past it the window goes
  // to the beam.
  std::size_t exact_bytes = std::size_t{64} << 20;
  std::size_t min_window = 10, max_window = 16;  // window lengths, drawn uniformly
  std::size_t exact_window = 16;                 // longest window solved exactly
  std::uint64_t exact_states = 20000;            // states per exact window search
  std::size_t beam_width = 64;  // windows too long or too hard for the exact search
  // Large windows (see above): one window in large_every on average (0: none, 1: all).
  std::uint64_t large_every = 2;
  std::size_t large_min = 20, large_max = 30;
  std::uint64_t kick_after = 2000;  // 0: no kicks
  std::size_t kick_size = 3;
  std::uint64_t kick_slack = 1;
  // Stop as soon as the schedule is this short (a known lower bound: then it is optimal).
  std::uint64_t lower_bound = 0;
  // Or as short as a bound published while the search runs (search/late_bound.h); null: none.
  const LateBound* late_lower_bound = nullptr;
};

struct LocalSearchResult {
  std::vector<CellId> schedule;     // feasible, never longer than the input
  std::uint64_t windows = 0;        // windows re-solved
  std::uint64_t large_windows = 0;  // of them, large ones (LocalSearchOptions::large_every)
  std::uint64_t improvements = 0, plateau_moves = 0, deletions = 0, kicks = 0;
  std::uint64_t work = 0;     // node visits
  std::uint64_t retimes = 0;  // re-timings of the whole schedule
  // "84 entries after 20000 windows (10000 large; 5 shorter, 19000 plateau moves, 10
  // deletions, 9 kicks)".
  std::string ToString() const;
};

// Improves `schedule`, which must be feasible for `forest` (RAYCELL_CHECK). InputError when
// the window lengths are inconsistent (min_window 0 or above max_window, the same for
// large_min and large_max when large_every is not 0).
LocalSearchResult ImproveSchedule(const CellForest& forest, std::vector<CellId> schedule,
                                  const LocalSearchOptions& options = {});

}  // namespace raycell
