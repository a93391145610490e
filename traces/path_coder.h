// Format version 8's coding of new paths (Batch.pathCode; see "Paths" in traces/trace.capnp and
// docs/design.md §3). A ray's path is its steps (version 5's step codes, the first from the cell
// PredictedFirstCell gives) and an end symbol. Each symbol is predicted from the ray's reference
// ray where it visits the same cell (its step out of that cell), else from the batch's last
// symbol of the same group leaving the same cell entered by the same two steps (PathTable), and
// range coded with version 6's coder: whether the prediction holds, under the group, the
// symbol's place on the path, the previous prediction's outcome and where the prediction came
// from; where it does not hold or there is none, the symbol by a bit tree under the group and
// the place (the second step's also under the step by which the parent entered the cell it
// spawned the ray in). Why: zstd saw these paths as short strings of step bytes (a path of 2 to
// 4 steps that differs from its reference's costs it nearly a byte a step), and most steps are
// those of the last ray through the same cell the same way.
//
// Writer and reader share this code. The decoder never reads outside its bytes and never loops
// more than a fixed number of steps per symbol, whatever the bytes.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "traces/cell_id.h"
#include "traces/columns.h"
#include "traces/ray_batch.h"
#include "traces/sample_coder.h"

namespace raycell {

// Version 8's path table: per batch, by the ray's group, the cell a step leaves, the class of
// the step that entered it (VisitTable::StepClass; kFromSpawn for a ray's first step) and of
// the step before (the parent's hint, PathPredictor, for the first two), the symbol of the
// last such step: a step code (0..kStepEscape) or kEnd. Direct-mapped on a hash of the key.
class PathTable {
 public:
  static constexpr unsigned kSlotBits = 14;
  static constexpr std::size_t kSlots = std::size_t{1} << kSlotBits;
  static constexpr unsigned kFromSpawn = 27;         // the entry class of a first step
  static constexpr unsigned kEnd = kStepEscape + 1;  // the symbol that ends a path
  static constexpr unsigned kSymbols = kEnd + 1;     // 0..kEnd
  static constexpr unsigned kNone = 255;             // no symbol known

  PathTable() : slots_(kSlots) {}
  void Clear() { std::fill(slots_.begin(), slots_.end(), Slot{}); }
  static std::uint64_t Key(unsigned group, std::uint32_t cell, unsigned in, unsigned before) {
    return ((std::uint64_t{cell} * 3 + group) * 28 + in) * 29 + before + 1;  // never 0 (empty)
  }
  std::size_t SlotOf(std::uint64_t key) const {
    return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> (64 - kSlotBits));
  }
  // The symbol last set under `key` at `slot`, or kNone.
  unsigned Find(std::size_t slot, std::uint64_t key) const {
    return slots_[slot].key == key ? slots_[slot].symbol : kNone;
  }
  void Set(std::size_t slot, std::uint64_t key, unsigned symbol) {
    slots_[slot] = {key, static_cast<std::uint8_t>(symbol)};
  }

 private:
  struct Slot {
    std::uint64_t key = 0;
    std::uint8_t symbol = 0;
  };
  std::vector<Slot> slots_;
};

// The class of the step by which ray `parent` of `b` entered the cell it spawned a ray in at its
// visit `spawn` (PathTable::kFromSpawn at its first visit), or kFromSpawn + 1 where that is not
// known (a primary ray, a parent outside the batch, a spawn past its visits).
unsigned ParentHint(const RayBatch& b, RayId parent, std::uint32_t spawn, const CellGrid& grid);

// The adaptive models of the path code: per context, whether the prediction holds (hit), and
// the symbol where it does not or there is none (a bit tree).
class PathModels {
 public:
  // Places of a step on its path: the first step, the second, later ones.
  static constexpr unsigned kPlaces = 3;
  // Outcomes of the previous prediction: none yet, held, failed, absent.
  static constexpr unsigned kOutcomes = 4;
  // Where the prediction came from: the table; the reference ray, the table differing or
  // having none; both agreeing.
  static constexpr unsigned kSources = 3;
  // Trees per group: the first step, the second by the parent's hint (29), later steps.
  static constexpr unsigned kTrees = 31;
  static constexpr unsigned kTreeSize = 128;  // a 7-bit tree over the kSymbols symbols

  PathModels()
      : hit_(3 * kPlaces * kOutcomes * kSources, kHalf), tree_(3 * kTrees * 2 * kTreeSize, kHalf) {}
  std::uint16_t& hit(unsigned index) { return hit_[index]; }
  std::uint16_t* tree(unsigned offset) { return &tree_[offset]; }

 private:
  static constexpr std::uint16_t kHalf = 1u << (SampleModels::kProbBits - 1);
  std::vector<std::uint16_t> hit_, tree_;
};

// What the encoder and the decoder of one path both know and predict, step by step: the cell
// the next step leaves, the classes of the steps into it and before it, the reference ray's
// visits, the previous prediction's outcome.
class PathPredictor {
 public:
  // A ray of group `group` (SampleGroup) whose first step starts from cell `from`; `hint` the
  // class of the step by which its parent entered the cell it was spawned in (kFromSpawn at
  // the parent's first visit, kFromSpawn + 1 where not known); its reference ray's cells
  // `ref[0..ref_count)`.
  PathPredictor(unsigned group, std::uint32_t from, unsigned hint, const CellId* ref,
                std::size_t ref_count);
  struct Prediction {
    std::uint64_t key;
    std::size_t slot;
    unsigned symbol;     // PathTable::kNone: none
    unsigned hit_model;  // PathModels::hit's index
    unsigned tree;       // PathModels::tree's offset
  };
  // The prediction of the next symbol (a step out of the current cell, or the end).
  Prediction Predict(const PathTable& table, const CellGrid& grid);
  // After the symbol predicted by `p` was `symbol` (below kSymbols).
  void After(const Prediction& p, unsigned symbol, PathTable& table);
  // After the step to cell `to`.
  void Step(std::uint32_t to, const CellGrid& grid);
  // The cell the next step leaves (the path's last cell so far).
  std::uint32_t at() const { return at_; }

 private:
  unsigned group_;
  std::uint32_t at_;
  unsigned hint_, in_ = PathTable::kFromSpawn, before_;
  const CellId* ref_;
  std::size_t ref_count_, next_ = 0;  // next_: the reference's visit after the last matched
  unsigned steps_ = 0, outcome_ = 0;
};

// Encodes the new paths of one batch (Batch.pathCode).
class PathEncoder {
 public:
  explicit PathEncoder(const CellGrid& grid) : grid_(grid) {}
  // The path of a ray: the cells `cells[0..count)`; the rest as PathPredictor's.
  void Add(unsigned group, std::uint32_t from, const CellId* cells, std::size_t count,
           unsigned hint, const CellId* ref, std::size_t ref_count);
  void Finish() { code_.Finish(); }
  const std::vector<std::uint8_t>& code() const { return code_.code(); }
  std::size_t bytes() const { return code_.bytes(); }

 private:
  void Symbol(PathPredictor& state, unsigned symbol);

  CellGrid grid_;
  SampleEncoder code_{3};  // escapes' axis values under one context per axis
  PathModels models_;
  PathTable table_;
};

// Decodes the new paths of one batch from its Batch.pathCode.
class PathDecoder {
 public:
  PathDecoder(const std::uint8_t* data, std::size_t size, const CellGrid& grid)
      : grid_(grid), code_(data, size, 3, "pathCode") {}
  // Reads a ray's path (arguments as PathEncoder::Add's) into `cells` (cleared first), at most
  // `max_count` cells; false where a step leaves the grid, a symbol is not one, or the path is
  // longer.
  bool Next(unsigned group, std::uint32_t from, unsigned hint, const CellId* ref,
            std::size_t ref_count, std::size_t max_count, std::vector<std::uint32_t>& cells);
  void Finish() const { code_.Finish(); }

 private:
  unsigned Symbol(PathPredictor& state);

  CellGrid grid_;
  SampleDecoder code_;
  PathModels models_;
  PathTable table_;
};

}  // namespace raycell
