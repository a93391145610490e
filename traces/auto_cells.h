// auto:N, the recommended subdivision into N cells (issue 42; docs/design.md §1
// "Subdivisions", "auto:N"): per frame, from the frames before it only, either the baseline
// (the uniform grid of N cells nearest a cube, CubicGrid) or an adaptive candidate, whichever
// the frames seen estimate cheaper, the cells changing only when what the change saved on the
// latest frames seen pays for it (ChooseAutoRule). Fed a fine capture's frames in order (AddBatch,
// EndFrame), it gives each next frame's cells (next()) from them alone, so the same frames give the
// same cells on every machine, and frame i's cells do not depend on the frames after it.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "traces/cell_id.h"
#include "traces/ray_batch.h"
#include "traces/regroup.h"
#include "traces/subdivision.h"

namespace raycell {

// One frame's rays in the cells of a subdivision, as paths of cells (the coarse rays a
// RayRegrouper gives), and the two estimates of what they cost in bytes moved into a
// processor's cache that auto:N compares subdivisions by.
class CellPaths {
 public:
  // Appends a batch of coarse rays; batches come in ray order, the first starting at id 0.
  void Add(const RayBatch& coarse);
  std::size_t rays() const { return parent_.size(); }
  // The bytes one processor under Max Work (docs/design.md §1 "Max Work": the cell with the
  // most queued rays, lowest on ties; rays spawned in the loaded cell worked there) fetches
  // into an LRU cache of `capacity` bytes, cold at the start (a cell larger than the cache
  // passes through it). `fp` gives each cell's bytes.
  double MaxWorkBytes(const std::vector<std::uint64_t>& fp, std::uint64_t capacity) const;
  // Sum over cells of maxGen(c) fp(c): the bytes of the fewest fetches any schedule needs with
  // a cache of one cell (docs/design.md §1 "Generation and bound"), what a schedule following
  // the tree (Cell Tree scheduling) comes near.
  double TreeBytes(const std::vector<std::uint64_t>& fp) const;

 private:
  std::vector<std::uint64_t> begin_{0};  // per ray, where its visits start in cell_
  std::vector<std::uint32_t> cell_;
  std::vector<std::uint32_t> parent_;  // kNone for a primary ray
  std::vector<std::uint32_t> spawn_;
  static constexpr std::uint32_t kNone = ~std::uint32_t{0};
  std::uint32_t cells_ = 0;  // 1 + the largest cell seen
};

// auto:N's choice for the next frame (docs/design.md §1 "auto:N", the switching rule), from
// every rule's estimate over the baseline's on each frame seen (`ratio[i][t]`, NaN where rule i
// had no cells for frame t; rule 0 is the baseline, 1 throughout), what changing the cells to
// rule i would cost (`switch_cost[i]`, in frames of the baseline: a frame whose cells changed is
// scheduled with no earlier tree) and the rule of the frame before (`current`). Rule j replaces
// `current` when it was cheaper than `current` on each of the last w >= 2 frames seen and
// what it saved over them adds up to its switch cost; of such rules, the least ratio on the
// last frame wins (ties to the lowest). Otherwise `current` stays.
std::size_t ChooseAutoRule(const std::vector<std::vector<double>>& ratio,
                           const std::vector<double>& switch_cost, std::size_t current);

class AutoCells {
 public:
  // What auto:N decided for one frame: the rule its cells come from ("uniform": the baseline;
  // else a SPEC and what it was made from: "kd:27:footprint" and "grid:1x3x9" from nothing
  // but the footprints, "kd:27:sqrt@0" from frame 0's samples, "kd:27:sqrt@seen" from every
  // frame seen) and, per rule evaluated on that frame, the ratio of its estimate to the
  // baseline's (the larger of the two estimates' ratios).
  struct Frame {
    std::string rule;
    std::vector<std::pair<std::string, double>> ratios;
  };

  // auto:`cells` on the fine grid `fine` (its grid and union_footprint; the rest unused).
  // InputError "WHAT: ..." when no grid of `cells` cells fits the fine grid or there are more
  // cells than fine cells.
  AutoCells(std::uint32_t cells, FineCells fine, const std::string& what);
  ~AutoCells();

  // The cells of the next frame (frame frames().size()), from the frames given so far.
  const Subdivision& next() const;
  // Each fine batch of the next frame, in ray order; then EndFrame.
  void AddBatch(const RayBatch& fine);
  void EndFrame();
  // Per frame given, what was decided for it.
  const std::vector<Frame>& frames() const { return frames_; }

 private:
  struct Rule;
  // Remakes every rule's cells for the next frame from the frames given, and chooses.
  void Prepare();

  std::uint32_t cells_;
  FineCells fine_;
  std::string what_;
  std::uint64_t capacity_ = 0;  // the baseline's median non-empty footprint
  std::vector<std::unique_ptr<Rule>> rules_;
  std::size_t chosen_ = 0;  // the rule whose cells next() gives
  // The frames given: per frame the samples per fine cell.
  std::vector<std::vector<std::uint64_t>> samples_;
  std::vector<std::uint64_t> frame_samples_;
  // Per frame given: the baseline's Max Work estimate over its tree estimate.
  std::vector<double> base_mw_over_tree_;

  std::vector<Frame> frames_;
};

}  // namespace raycell
