// A lower bound on a frame's simulated time that holds for any scheduler (issue 22): how far a
// replay is from what no schedule of the same work on the same board can beat. The largest of
// four terms, each a property of the work graph, the footprints and the configuration alone:
//
//  (a) work: ceil(W / P), W = sum over units of samples x time_per_sample, P processors.
//      Every unit is worked by one processor for samples x time_per_sample, and each
//      processor's work, stall and idle add up to the time T, so W <= P x T; T is a whole
//      number of picoseconds, hence T >= ceil(W / P).
//  (b) links: the busiest link's least transfer time. Every unit is worked only after its
//      processor fetched its cell, so every cell some unit has (a used cell) is fetched at
//      least once. A cell enters a level only through a transfer across the link below it, so
//      the first transfer of a used cell that no level <= i holds at the start (`held_at_start`)
//      crosses the link below level i, at a cost of latency_below + TransferTime(footprint) of
//      level i, whatever the replacement does later.
//       - Shared link below level i >= 1 (one transfer at a time): those first transfers are
//         disjoint intervals on the link, starting at 0 or later and ending by the end of the
//         fetch that made them, itself at most T; so T >= their sum. A fetch that finds the
//         cell in a shared level waits for its arrival there (replay/memory.h), so with
//         prefetch too every use of a cell ends after its first crossing of each link above
//         where it came from.
//       - The links below level 0, one per processor: the worker's first fetch of a cell that
//         no level-0 copy holds at the start either crosses its own link, or finds the cell in
//         its cache, brought there by its own earlier fetch or prefetch, which crossed that link
//         and ended before the worker's fetch did. So each such cell has one transfer across
//         some processor's link that ends by T; the P links carry at most P x T of transfers,
//         and T >= ceil(sum / P).
//      A cell held at the start is taken to be there at time 0 (the warm memory of issue 22).
//      A level of coarser cells (level.NAME.cells, replay/memory.h LevelUnits) stores and
//      moves units: a used cell that no nearer level holds at the start reaches the caches
//      only through a lookup of its unit at level i, so its unit, unless level i holds it at
//      the start, crosses the link below level i at least once, at the unit's bytes; each
//      such unit is counted once.
//  (c) chain: the longest path of the work graph from a root, summing samples x
//      time_per_sample. A unit is released only when its predecessor is done, and takes its
//      samples x time_per_sample, so the units of a path are worked one after the other.
//  (d) busy: without prefetch, ceil((W + F) / P), F the least transfer time over the links
//      below level 0 of (b) (each cell that no cache holds at the start, once). A processor's
//      link carries only its own fetches (and prefetches, here off), and a fetch's transfers
//      end by the fetch's end (ready), so every crossing of p's link lies inside one of p's
//      fetches, from its call to ready: time p stalls, not working. So p's work plus the
//      crossings of its link are at most T; summed over processors, W + F <= P x T. With
//      prefetch a crossing may overlap work, and the term is (a)'s.
//
// Each term is at most the replay's time under every scheduler of the registry
// (tests/replay/time_bound_test.cpp, on random frames and configurations).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/time.h"
#include "replay/config.h"
#include "replay/memory.h"
#include "replay/work.h"

namespace raycell {

// The four terms of the bound; value() is the bound.
struct TimeBoundTerms {
  SimTime work;   // (a) ceil(total work / processors)
  SimTime links;  // (b) the largest over the links: shared ones and those below level 0
  SimTime chain;  // (c) the longest chain of dependent work
  SimTime busy;   // (d) ceil((work + caches' least fetches) / processors); (a) with prefetch
  SimTime value() const;
  // "work 37ps, links 2400ps, chain 500ps, busy 42ps".
  std::string ToString() const;
};

// The terms for `work` (any of its three forms: columns, packed or compact) on a board of
// `config` with `footprints` (one per cell). `held_at_start`, when given, has one vector per
// level (config.levels' order) of one flag per unit of the level (HeldAnywhere): some copy of
// the level holds it when the frame starts; null: every level starts empty. `units` (null:
// every level holds the cells) as ReplayFrame takes them. Linear in the units, without
// recursion.
TimeBoundTerms TimeLowerBoundTerms(const WorkGraph& work,
                                   const std::vector<std::uint64_t>& footprints,
                                   const ReplayConfig& config,
                                   const std::vector<std::vector<bool>>* held_at_start = nullptr,
                                   const MemoryUnits* units = nullptr);

// The longest chain and the used cells, the walk the terms need (WorkGraph::Shape).
WorkGraph::Shape ShapeOf(const WorkGraph& work);

// The bound: the largest of the terms.
SimTime TimeLowerBound(const WorkGraph& work, const std::vector<std::uint64_t>& footprints,
                       const ReplayConfig& config,
                       const std::vector<std::vector<bool>>* held_at_start = nullptr,
                       const MemoryUnits* units = nullptr);

}  // namespace raycell
