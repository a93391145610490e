// What the schedule searches (beam, local and exact search) share: bitsets of processed
// nodes (one bit per forest node in 64-bit words) and their hash, and a seeded random draw.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <random>
#include <vector>

#include "base/check.h"

namespace raycell {

using Word = std::uint64_t;

inline std::size_t WordsFor(std::size_t bits) { return (bits + 63) / 64; }
inline bool TestBit(const Word* bits, std::size_t n) { return (bits[n / 64] >> (n % 64)) & 1; }
inline void SetBit(Word* bits, std::size_t n) { bits[n / 64] |= Word{1} << (n % 64); }
inline void SetBit(std::vector<Word>& bits, std::size_t n) { SetBit(bits.data(), n); }

// splitmix64's finalizer: a bijection of 64-bit words that mixes every bit.
inline std::uint64_t MixBits(std::uint64_t x) {
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

inline std::uint64_t HashBits(const Word* bits, std::size_t words) {
  std::uint64_t h = words;
  for (std::size_t i = 0; i < words; ++i) h = MixBits(h ^ bits[i]);
  return h;
}

// The smallest k with 2^k >= n.
inline unsigned CeilLog2(std::size_t n) {
  unsigned k = 0;
  while ((std::size_t{1} << k) < n) ++k;
  return k;
}

// Sets of words, stored flat, found by hash (open addressing).
class BitsTable {
 public:
  using Id = std::uint32_t;
  static constexpr Id kNone = 0xffffffffu;

  explicit BitsTable(std::size_t words) : words_(words), table_(64, kNone) {}
  std::size_t size() const { return hash_.size(); }
  const Word* bits(Id s) const { return bits_.data() + std::size_t(s) * words_; }
  Id Find(const Word* bits, std::uint64_t hash) const {
    for (std::size_t i = hash & (table_.size() - 1);; i = (i + 1) & (table_.size() - 1)) {
      const Id s = table_[i];
      if (s == kNone) return kNone;
      if (hash_[s] == hash && std::equal(bits, bits + words_, this->bits(s))) return s;
    }
  }
  Id Add(const Word* bits, std::uint64_t hash) {
    RAYCELL_CHECK_LT(size(), std::size_t{kNone});
    const auto s = Id(size());
    bits_.insert(bits_.end(), bits, bits + words_);
    hash_.push_back(hash);
    if (2 * size() > table_.size()) {
      table_.assign(2 * table_.size(), kNone);
      for (Id t = 0; t < size(); ++t) Place(t);
    } else {
      Place(s);
    }
    return s;
  }
  std::size_t bytes() const {
    return size() * (words_ * sizeof(Word) + sizeof(std::uint64_t)) + table_.size() * sizeof(Id);
  }

 private:
  void Place(Id s) {
    std::size_t i = hash_[s] & (table_.size() - 1);
    while (table_[i] != kNone) i = (i + 1) & (table_.size() - 1);
    table_[i] = s;
  }
  std::size_t words_;
  std::vector<Word> bits_;
  std::vector<std::uint64_t> hash_;
  std::vector<Id> table_;  // power-of-two size, at most half full
};

// Seeded random numbers that are the same on every platform: std::mt19937_64 is specified
// exactly, std::uniform_int_distribution is not, so bounded draws are our own (rejection
// sampling: uniform and exact).
class SeededRandom {
 public:
  explicit SeededRandom(std::uint64_t seed) : rng_(seed) {}
  std::uint64_t Next() { return rng_(); }
  // Uniform in 0 .. bound-1; bound > 0.
  std::uint64_t Below(std::uint64_t bound) {
    const std::uint64_t limit = ~std::uint64_t{0} - (~std::uint64_t{0} % bound);
    for (;;) {
      const std::uint64_t x = rng_();
      if (x < limit) return x % bound;
    }
  }
  // Uniform in lo .. hi (inclusive); lo <= hi.
  std::uint64_t Between(std::uint64_t lo, std::uint64_t hi) { return lo + Below(hi - lo + 1); }

 private:
  std::mt19937_64 rng_;
};

}  // namespace raycell
