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
// Writer and reader share this code. The decoder never reads outside its bytes and never
// loops more than a fixed number of steps per value, whatever the bytes; a code that does
// not end exactly at its last byte is BadTraceData.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "traces/columns.h"

namespace raycell {

// The context of a ray's visits, visit by visit: construct per ray, Of() for each visit,
// Next() after it.
class SampleContext {
 public:
  // 3 groups x residual or not x 7 sizes x last or not x 8 previous values x new path or not.
  static constexpr unsigned kCount = 3 * 2 * 7 * 2 * 8 * 2;

  // `kind` as in a head byte (0 primary, 1 reflection, 2 refraction, 3 shadow); `new_path`
  // the ray's new-path bit.
  SampleContext(unsigned kind, bool new_path)
      : base_((kind == 0   ? 0u
               : kind == 3 ? 2u
                           : 1u) *
                  2 +
              new_path) {}
  // The context of a visit: `matched` when its value is a residual against `predicted`
  // samples; `last` when it is the ray's last visit.
  unsigned Of(bool matched, std::uint64_t predicted, bool last) const {
    const std::uint64_t size = matched ? predicted : previous_samples_;
    return (((base_ * 2 + matched) * 7 + SizeClass(size)) * 2 + last) * 8 + previous_;
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

  SampleModels();
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
  void Add(unsigned context, std::uint64_t value);
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
  std::uint64_t low_ = 0;
  std::uint32_t range_ = 0xFFFFFFFF;
  std::uint8_t cache_ = 0;
  std::uint64_t cache_size_ = 1;
  std::vector<std::uint8_t> out_;
};

// Decodes the values of one batch from its Batch.sampleCode.
class SampleDecoder {
 public:
  SampleDecoder(const std::uint8_t* data, std::size_t size);
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
  std::size_t size_, pos_ = 0;  // pos_ > size_: read past the end
  std::uint32_t range_ = 0xFFFFFFFF, code_ = 0;
};

}  // namespace raycell
