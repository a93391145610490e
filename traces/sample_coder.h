// Format version 6's coding of a batch's samples (Batch.sampleCode; see "Samples" in
// traces/trace.capnp and docs/design.md §3): each visit's value (the zigzag residual against
// the reference ray's visit of the same cell, or the samples themselves when there is none)
// is coded by an adaptive binary range coder (LZMA's, 11-bit probabilities) under a context
// of what the decoder already knows: the ray's group (primary; reflection or refraction;
// shadow), whether the value is a residual, the size of the value it predicts from, whether
// the visit is the ray's last, the ray's previous residual and whether the ray has a path of
// its own. Order-0 coding (zstd's literals) cannot use these; measured over the suite's
// scenes, they take a sample's entropy down by a quarter to a third.
//
// Version 7 (VisitTable, PredictSamples) also predicts a visit's samples from the batch's
// last visit of the same cell entered and left by the same steps, in a batch whose
// Batch.visitTable is set, under 4 times the contexts.
//
// Writer and reader share this code. The decoder never reads outside its bytes and never
// loops more than a fixed number of steps per value, whatever the bytes; a code that does
// not end exactly at its last byte is BadTraceData.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "traces/columns.h"

namespace raycell {

// The group of a ray of kind `kind` (as in a head byte): 0 primary, 1 reflection or
// refraction, 2 shadow.
inline unsigned SampleGroup(unsigned kind) { return kind == 0 ? 0u : kind == 3 ? 2u : 1u; }

// The context of a ray's visits, visit by visit: construct per ray, Of() for each visit,
// Next() after it.
class SampleContext {
 public:
  // 3 groups x residual or not x 7 sizes x last or not x 8 previous values x new path or not.
  static constexpr unsigned kCount = 3 * 2 * 7 * 2 * 8 * 2;
  // Version 7: every context of version 6 times 4 predictors (the `predictor` of Of()): 0 as
  // version 6; 1 the visit table's value where the reference has no visit of the cell; 2 and 3
  // the visit table's value where the reference has one on another path, it differing (2) or
  // not (3) from the table's.
  static constexpr unsigned kPredictors = 4;
  static constexpr unsigned kCount7 = kCount * kPredictors;

  // `kind` as in a head byte (0 primary, 1 reflection, 2 refraction, 3 shadow); `new_path`
  // the ray's new-path bit.
  SampleContext(unsigned kind, bool new_path)
      : base_((kind == 0   ? 0u
               : kind == 3 ? 2u
                           : 1u) *
                  2 +
              new_path) {}
  // The context of a visit: `matched` when its value is a residual against `predicted`
  // samples; `last` when it is the ray's last visit; `predictor` (version 7) which prediction
  // the residual is against (see kPredictors).
  unsigned Of(bool matched, std::uint64_t predicted, bool last, unsigned predictor = 0) const {
    const std::uint64_t size = matched ? predicted : previous_samples_;
    return predictor * kCount + (((base_ * 2 + matched) * 7 + SizeClass(size)) * 2 + last) * 8 +
           previous_;
  }
  // After a visit coded with `value` (a zigzag residual when `matched`) and `samples`.
  void Next(bool matched, std::uint64_t value, std::uint64_t samples) {
    if (!matched) {
      previous_ = 1;
    } else {
      const std::int64_t r = UnZigZag(value);
      previous_ = static_cast<unsigned>((r < -2 ? -2 : r > 3 ? 3 : r) + 4);  // 2..7
    }
    previous_samples_ = samples;
  }

 private:
  // 0, 1, 2-3, 4-7, 8-15, 16-31, 32 and more -> 0..6.
  static unsigned SizeClass(std::uint64_t v) {
    const unsigned bits = v == 0 ? 0u : 64u - static_cast<unsigned>(__builtin_clzll(v));
    return bits < 6 ? bits : 6;
  }

  unsigned base_;                       // group * 2 + new path
  unsigned previous_ = 0;               // 0: first visit; 1: not a residual; 2..7: residual
  std::uint64_t previous_samples_ = 0;  // the previous visit's samples (0: none)
};

// Version 7's visit table (see "Samples" in trace.capnp): per batch, the samples of the last
// visit of each key: the ray's group, the cell, and the steps into and out of the cell (each
// axis's sign, or none at the ray's first or last visit), which bound the ray's chord through
// the cell. Direct-mapped on a hash of the key, kSlots slots: a slot holding another key is a
// miss, and the visit's key replaces it.
class VisitTable {
 public:
  static constexpr unsigned kSlotBits = 15;
  static constexpr std::size_t kSlots = std::size_t{1} << kSlotBits;
  static constexpr unsigned kNoStep = 27;  // the step class at a ray's first or last visit

  VisitTable() : slots_(kSlots) {}
  // Empties every slot (a new batch).
  void Clear() { std::fill(slots_.begin(), slots_.end(), Slot{}); }
  // A cell's coordinates (x, y, z) in `grid` (cell = x + nx * (y + ny * z)).
  using Coordinates = std::array<std::uint32_t, 3>;
  static Coordinates CoordinatesOf(std::uint32_t cell, const CellGrid& grid) {
    const std::uint32_t row = cell / grid[0];
    return {cell - row * grid[0], row % grid[1], row / grid[1]};
  }
  // The class of the step from the cell at `from` to the cell at `to`: the sign of each axis's
  // difference, (sx + 1) + 3 * (sy + 1) + 9 * (sz + 1), 0..26.
  static unsigned StepClass(const Coordinates& from, const Coordinates& to) {
    auto sign = [](std::uint32_t a, std::uint32_t b) { return a < b ? 2u : a == b ? 1u : 0u; };
    return sign(from[0], to[0]) + 3 * sign(from[1], to[1]) + 9 * sign(from[2], to[2]);
  }
  // The key of a visit of `cell` by a ray of group `group` (0..2) entered and left by steps
  // of classes `in` and `out` (0..kNoStep).
  static std::uint64_t Key(unsigned group, std::uint32_t cell, unsigned in, unsigned out) {
    return ((std::uint64_t{cell} * 3 + group) * 28 + in) * 28 + out + 1;  // never 0 (empty)
  }
  // The key of visit v of a ray of group `group` whose `count` visits have the cells at
  // `path[0..count)`: its cell, entered and left by the steps from the visit before and to the
  // one after (kNoStep at the first and last). The writer and the reader both key by this.
  static std::uint64_t KeyOfVisit(unsigned group, std::uint32_t cell, const Coordinates* path,
                                  std::size_t v, std::size_t count) {
    const unsigned in = v == 0 ? kNoStep : StepClass(path[v - 1], path[v]);
    const unsigned out = v + 1 == count ? kNoStep : StepClass(path[v], path[v + 1]);
    return Key(group, cell, in, out);
  }
  // The slot of `key`; Find() gives its samples if it holds that key.
  std::size_t SlotOf(std::uint64_t key) const {
    return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> (64 - kSlotBits));
  }
  bool Find(std::size_t slot, std::uint64_t key, std::uint64_t& samples) const {
    if (slots_[slot].key != key) return false;
    samples = slots_[slot].samples;
    return true;
  }
  void Set(std::size_t slot, std::uint64_t key, std::uint32_t samples) {
    slots_[slot] = {key, samples};
  }

 private:
  struct Slot {  // a key and its samples in one cache line
    std::uint64_t key = 0;
    std::uint32_t samples = 0;
  };
  std::vector<Slot> slots_;
};

// What version 7 codes a visit's samples against (see "Samples" in trace.capnp): with
// `matched` and `reference` the version 6 prediction (the reference ray's visit of the
// cell), `new_path` the ray's bit, and `hit` and `table` the visit table's.
struct SamplePrediction {
  bool residual;            // the value is zigzag(samples - predicted)
  std::uint64_t predicted;  // 0 when not a residual
  unsigned predictor;       // SampleContext::Of's
};
inline SamplePrediction PredictSamples(bool matched, std::uint64_t reference, bool new_path,
                                       bool hit, std::uint64_t table) {
  if (hit && !matched) return {true, table, 1};
  if (hit && new_path) return {true, table, reference == table ? 3u : 2u};
  return {matched, matched ? reference : 0, 0};
}

// The adaptive models of every context: per context, the bits of a value's length (unary)
// and the top 3 bits below its leading one (a bit tree per length). What most values use (the
// first 12 length bits, the trees of lengths 1 to 3) is one 64-byte line per context.
class SampleModels {
 public:
  // Values are at most kMaxValue (2^40 - 2): the length is at most kMaxLength.
  static constexpr unsigned kMaxLength = 40;
  static constexpr std::uint64_t kMaxValue = (std::uint64_t{1} << kMaxLength) - 2;
  static constexpr unsigned kTreeBits = 3;      // bits below the leading one in the tree
  static constexpr unsigned kTreeLengths = 12;  // lengths with their own tree (more share one)
  // LZMA's bit model: the probability of a 0 in kProbBits bits, moved 1/2^kMoveBits of the
  // way to each bit seen (so it stays within 15..2033 of 2048).
  static constexpr unsigned kProbBits = 11;
  static constexpr unsigned kMoveBits = 4;

  // The models of `contexts` contexts (SampleContext::kCount, or kCount7 for version 7).
  explicit SampleModels(unsigned contexts = SampleContext::kCount);
  // The model of length bit i (is the length more than i?).
  std::uint16_t& length(unsigned context, unsigned i) {
    return i < kHotLengths ? hot_[context * kHot + i] : cold_[context * kCold + (i - kHotLengths)];
  }
  // The tree of `length` (1..kMaxLength): entries [1, 2^min(length, kTreeBits)).
  std::uint16_t* tree(unsigned context, unsigned length) {
    if (length <= kTreeBits)
      return &hot_[context * kHot + kHotLengths - 2 + (1u << length) - length];
    const unsigned t = length < kTreeLengths ? length : kTreeLengths;
    return &cold_[context * kCold + (kMaxLength - kHotLengths) + 8 * (t - kTreeBits - 1)];
  }

 private:
  // hot: length bits 0..11, then the trees of lengths 1, 2, 3 (1 + 3 + 7 entries, tree(1)[1]
  // at 12, tree(2)[1..3] at 13..15, tree(3)[1..7] at 16..22); cold: length bits 12..39, then
  // 8 entries per tree of lengths 4..kTreeLengths (entry 0 unused).
  static constexpr unsigned kHotLengths = 12;
  static constexpr unsigned kHot = 32;
  static constexpr unsigned kCold = (kMaxLength - kHotLengths) + 8 * (kTreeLengths - kTreeBits);
  std::vector<std::uint16_t> hot_, cold_;
};

// Encodes the values of one batch.
class SampleEncoder {
 public:
  explicit SampleEncoder(unsigned contexts = SampleContext::kCount)
      : models_(contexts), contexts_(contexts) {}
  void Add(unsigned context, std::uint64_t value);
  // Codes one bit under the model `p` (a probability as SampleModels' are); for coders of other
  // symbols on the same code (traces/path_coder.h).
  void AddBit(std::uint16_t& p, unsigned bit) { Bit(p, bit); }
  // Ends the code; call once, before code().
  void Finish();
  const std::vector<std::uint8_t>& code() const { return out_; }
  std::size_t bytes() const { return out_.size() + 5; }

 private:
  void Bit(std::uint16_t& p, unsigned bit);
  void Direct(std::uint64_t value, unsigned bits);
  void Normalize();
  void ShiftLow();

  SampleModels models_;
  unsigned contexts_;
  std::uint64_t low_ = 0;
  std::uint32_t range_ = 0xFFFFFFFF;
  std::uint8_t cache_ = 0;
  std::uint64_t cache_size_ = 1;
  std::vector<std::uint8_t> out_;
};

// Decodes the values of one batch from its Batch.sampleCode.
class SampleDecoder {
 public:
  // `contexts` as the encoder's; every context Next() is given must be below it. `name` (a
  // string literal) names the code in messages.
  SampleDecoder(const std::uint8_t* data, std::size_t size,
                unsigned contexts = SampleContext::kCount, const char* name = "sampleCode");
  std::uint64_t Next(unsigned context) {
    // The coder's state in locals (registers) while a value is decoded.
    State s{range_, code_, pos_};
    unsigned e = 0;
    while (e < SampleModels::kMaxLength && Bit(s, models_.length(context, e)) == 1) ++e;
    const unsigned tree_bits = e < SampleModels::kTreeBits ? e : SampleModels::kTreeBits;
    std::uint16_t* tree = models_.tree(context, e);
    unsigned node = 1;
    for (unsigned i = 0; i < tree_bits; ++i) node = 2 * node + Bit(s, tree[node]);
    // node is now the leading one and the tree's bits.
    std::uint64_t u = node;
    for (unsigned i = tree_bits; i < e; ++i) u = (u << 1) | Direct(s);
    range_ = s.range, code_ = s.code, pos_ = s.pos;
    return u - 1;
  }
  // The bit AddBit coded under the model `p`.
  unsigned NextBit(std::uint16_t& p) {
    State s{range_, code_, pos_};
    const unsigned bit = Bit(s, p);
    range_ = s.range, code_ = s.code, pos_ = s.pos;
    return bit;
  }
  // Throws BadTraceData unless the code ended exactly at its last byte.
  void Finish() const;

 private:
  struct State {
    std::uint32_t range, code;
    std::size_t pos;
  };
  void Normalize(State& s) const {
    if (s.range < (1u << 24)) {
      s.range <<= 8;
      // Past the end: zeros, counted by pos beyond size_ (which Finish refuses).
      s.code = (s.code << 8) | (s.pos < size_ ? data_[s.pos] : 0u);
      ++s.pos;
    }
  }
  unsigned Bit(State& s, std::uint16_t& p) const {
    constexpr unsigned kBits = SampleModels::kProbBits, kMove = SampleModels::kMoveBits;
    // Written without branches on the bit (a misprediction costs more than the arithmetic).
    const std::uint32_t bound = (s.range >> kBits) * p;
    const unsigned bit = s.code >= bound;
    const std::uint32_t mask = 0u - bit;
    s.code -= bound & mask;
    s.range = (bound & ~mask) | ((s.range - bound) & mask);
    const unsigned up = p + (((1u << kBits) - p) >> kMove), down = p - (p >> kMove);
    p = static_cast<std::uint16_t>(bit ? down : up);
    Normalize(s);
    return bit;
  }
  unsigned Direct(State& s) const {
    s.range >>= 1;
    const unsigned bit = s.code >= s.range;
    s.code -= s.range & (0u - bit);
    Normalize(s);
    return bit;
  }

  SampleModels models_;
  const std::uint8_t* data_;
  const char* name_;
  std::size_t size_, pos_ = 0;  // pos_ > size_: read past the end
  std::uint32_t range_ = 0xFFFFFFFF, code_ = 0;
};

}  // namespace raycell
