#include "traces/sample_coder.h"

#include "base/check.h"

namespace raycell {

namespace {

constexpr unsigned kProbBits = SampleModels::kProbBits;
constexpr unsigned kMoveBits = SampleModels::kMoveBits;
constexpr unsigned kTreeBits = SampleModels::kTreeBits;

unsigned LengthOf(std::uint64_t u) {  // floor(log2(u)), u >= 1
  unsigned e = 0;
  while (u >> (e + 1)) ++e;
  return e;
}

}  // namespace

SampleModels::SampleModels(unsigned contexts)
    : hot_(std::size_t{contexts} * kHot, 1u << (kProbBits - 1)),
      cold_(std::size_t{contexts} * kCold, 1u << (kProbBits - 1)) {}

// ---- Encoder -----------------------------------------------------------------------------

void SampleEncoder::ShiftLow() {
  if (static_cast<std::uint32_t>(low_) < 0xFF000000u || (low_ >> 32) != 0) {
    std::uint8_t carry = static_cast<std::uint8_t>(low_ >> 32);
    std::uint8_t byte = cache_;
    do {
      out_.push_back(static_cast<std::uint8_t>(byte + carry));
      byte = 0xFF;
    } while (--cache_size_ != 0);
    cache_ = static_cast<std::uint8_t>(low_ >> 24);
  }
  ++cache_size_;
  low_ = (low_ & 0x00FFFFFFu) << 8;
}

void SampleEncoder::Normalize() {
  while (range_ < (1u << 24)) {
    range_ <<= 8;
    ShiftLow();
  }
}

void SampleEncoder::Bit(std::uint16_t& p, unsigned bit) {
  const std::uint32_t bound = (range_ >> kProbBits) * p;
  if (bit == 0) {
    range_ = bound;
    p = static_cast<std::uint16_t>(p + (((1u << kProbBits) - p) >> kMoveBits));
  } else {
    low_ += bound;
    range_ -= bound;
    p = static_cast<std::uint16_t>(p - (p >> kMoveBits));
  }
  Normalize();
}

void SampleEncoder::Direct(std::uint64_t value, unsigned bits) {
  while (bits-- > 0) {
    range_ >>= 1;
    if ((value >> bits) & 1) low_ += range_;
    Normalize();
  }
}

void SampleEncoder::Add(unsigned context, std::uint64_t value) {
  RAYCELL_CHECK_LT(context, contexts_);
  RAYCELL_CHECK_LE(value, SampleModels::kMaxValue);
  // u = value + 1 >= 1: its length e (unary, adaptive), then its e bits below the leading
  // one: the first kTreeBits by a bit tree, the rest direct.
  const std::uint64_t u = value + 1;
  const unsigned e = LengthOf(u);
  for (unsigned i = 0; i < e; ++i) Bit(models_.length(context, i), 1);
  if (e < SampleModels::kMaxLength) Bit(models_.length(context, e), 0);
  const unsigned tree_bits = e < kTreeBits ? e : kTreeBits;
  std::uint16_t* tree = models_.tree(context, e);
  unsigned node = 1;
  for (unsigned i = 1; i <= tree_bits; ++i) {
    const unsigned bit = static_cast<unsigned>(u >> (e - i)) & 1;
    Bit(tree[node], bit);
    node = 2 * node + bit;
  }
  Direct(u, e - tree_bits);
}

void SampleEncoder::Finish() {
  for (int i = 0; i < 5; ++i) ShiftLow();
}

// ---- Decoder -----------------------------------------------------------------------------

SampleDecoder::SampleDecoder(const std::uint8_t* data, std::size_t size, unsigned contexts,
                             const char* name)
    : models_(contexts), data_(data), name_(name), size_(size) {
  for (; pos_ < 5; ++pos_) code_ = (code_ << 8) | (pos_ < size_ ? data_[pos_] : 0u);
}

void SampleDecoder::Finish() const {
  if (pos_ != size_) {
    throw BadTraceData(std::string(name_) + " of " + std::to_string(size_) +
                       " bytes ends at byte " + std::to_string(pos_));
  }
}

}  // namespace raycell
