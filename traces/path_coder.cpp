#include "traces/path_coder.h"

#include "traces/format.h"

namespace raycell {

namespace {

constexpr unsigned kSymbolBits = 7;  // PathModels::kTreeSize == 1 << kSymbolBits
static_assert(PathTable::kSymbols <= (1u << kSymbolBits));

// The class of the step from cell `from` to cell `to` (VisitTable::StepClass).
unsigned StepClassOf(std::uint32_t from, std::uint32_t to, const CellGrid& grid) {
  return VisitTable::StepClass(VisitTable::CoordinatesOf(from, grid),
                               VisitTable::CoordinatesOf(to, grid));
}

}  // namespace

unsigned ParentHint(const RayBatch& b, RayId parent, std::uint32_t spawn, const CellGrid& grid) {
  if (parent == kNoParent || parent < b.first_id()) return PathTable::kFromSpawn + 1;
  const std::size_t p = parent - b.first_id();
  const std::size_t begin = b.visit_begin(p), count = b.visit_end(p) - begin;
  if (spawn >= count) return PathTable::kFromSpawn + 1;
  if (spawn == 0) return PathTable::kFromSpawn;
  return StepClassOf(b.cells()[begin + spawn - 1].value(), b.cells()[begin + spawn].value(), grid);
}

// ---- What the encoder and the decoder both predict ---------------------------------------

PathPredictor::PathPredictor(unsigned group, std::uint32_t from, unsigned hint, const CellId* ref,
                             std::size_t ref_count)
    : group_(group), at_(from), hint_(hint), before_(hint), ref_(ref), ref_count_(ref_count) {}

PathPredictor::Prediction PathPredictor::Predict(const PathTable& table, const CellGrid& grid) {
  Prediction p;
  const unsigned place = steps_ < 2 ? steps_ : 2u;
  p.key = PathTable::Key(group_, at_, in_, before_);
  p.slot = table.SlotOf(p.key);
  const unsigned in_table = table.Find(p.slot, p.key);
  p.symbol = in_table;
  // The reference's step out of the same cell (as samples are matched: from its visit after
  // the last matched, at most kSampleMatchWindow on), from the ray's second step on.
  unsigned source = 0;
  if (steps_ > 0) {
    const std::size_t end = std::min(ref_count_, next_ + kSampleMatchWindow);
    std::size_t k = next_;
    while (k < end && ref_[k].value() != at_) ++k;
    if (k < end) {
      next_ = k + 1;
      std::uint64_t escape[3];
      const unsigned from_ref =
          k + 1 == ref_count_ ? PathTable::kEnd : StepCode(at_, ref_[k + 1].value(), grid, escape);
      source = in_table == from_ref ? 2 : 1;
      p.symbol = from_ref;
    }
  }
  p.hit_model = ((group_ * PathModels::kPlaces + place) * PathModels::kOutcomes + outcome_) *
                    PathModels::kSources +
                source;
  const unsigned tree = place == 0 ? 0u : place == 1 ? 1 + hint_ : PathModels::kTrees - 1;
  p.tree = ((group_ * PathModels::kTrees + tree) * 2 + (p.symbol != PathTable::kNone)) *
           PathModels::kTreeSize;
  return p;
}

void PathPredictor::After(const Prediction& p, unsigned symbol, PathTable& table) {
  table.Set(p.slot, p.key, symbol);
  outcome_ = p.symbol == PathTable::kNone ? 3u : symbol == p.symbol ? 1u : 2u;
}

void PathPredictor::Step(std::uint32_t to, const CellGrid& grid) {
  before_ = in_ == PathTable::kFromSpawn ? hint_ : in_;
  in_ = StepClassOf(at_, to, grid);
  at_ = to;
  ++steps_;
}

// ---- Encoder -----------------------------------------------------------------------------

void PathEncoder::Symbol(PathPredictor& state, unsigned symbol) {
  const PathPredictor::Prediction p = state.Predict(table_, grid_);
  const bool held = p.symbol != PathTable::kNone && symbol == p.symbol;
  if (p.symbol != PathTable::kNone) code_.AddBit(models_.hit(p.hit_model), held ? 0u : 1u);
  if (!held) {
    std::uint16_t* tree = models_.tree(p.tree);
    unsigned node = 1;
    for (unsigned i = kSymbolBits; i-- > 0;) {
      const unsigned bit = (symbol >> i) & 1;
      code_.AddBit(tree[node], bit);
      node = 2 * node + bit;
    }
  }
  state.After(p, symbol, table_);
}

void PathEncoder::Add(unsigned group, std::uint32_t from, const CellId* cells, std::size_t count,
                      unsigned hint, const CellId* ref, std::size_t ref_count) {
  PathPredictor state(group, from, hint, ref, ref_count);
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint32_t to = cells[i].value();
    std::uint64_t escape[3];
    const unsigned step = StepCode(state.at(), to, grid_, escape);
    Symbol(state, step);
    if (step == kStepEscape) {
      for (unsigned axis = 0; axis < 3; ++axis) code_.Add(axis, escape[axis]);
    }
    state.Step(to, grid_);
  }
  Symbol(state, PathTable::kEnd);
}

// ---- Decoder -----------------------------------------------------------------------------

unsigned PathDecoder::Symbol(PathPredictor& state) {
  const PathPredictor::Prediction p = state.Predict(table_, grid_);
  unsigned symbol = p.symbol;
  const bool held = p.symbol != PathTable::kNone && code_.NextBit(models_.hit(p.hit_model)) == 0;
  if (!held) {
    std::uint16_t* tree = models_.tree(p.tree);
    unsigned node = 1;
    for (unsigned i = 0; i < kSymbolBits; ++i) node = 2 * node + code_.NextBit(tree[node]);
    symbol = node - (1u << kSymbolBits);
  }
  if (symbol < PathTable::kSymbols) state.After(p, symbol, table_);
  return symbol;
}

bool PathDecoder::Next(unsigned group, std::uint32_t from, unsigned hint, const CellId* ref,
                       std::size_t ref_count, std::size_t max_count,
                       std::vector<std::uint32_t>& cells) {
  cells.clear();
  PathPredictor state(group, from, hint, ref, ref_count);
  for (;;) {
    const unsigned step = Symbol(state);
    if (step == PathTable::kEnd) return true;
    if (step > PathTable::kEnd || cells.size() == max_count) return false;
    std::uint64_t escape[3] = {0, 0, 0};
    if (step == kStepEscape) {
      for (unsigned axis = 0; axis < 3; ++axis) escape[axis] = code_.Next(axis);
    }
    const std::uint32_t to = StepTo(state.at(), step, escape, grid_);
    if (to == kBadStep) return false;
    state.Step(to, grid_);
    cells.push_back(to);
  }
}

}  // namespace raycell
