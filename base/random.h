// splitmix64 (Steele, Lea, Flood 2014; Vigna's reference code): a small seeded generator whose
// outputs are the same with every compiler and standard library. It seeds the random
// scheduler's xoshiro256** (scheduling/random_scheduler.h) and drives the engine's benchmarks
// and tests.
#pragma once

#include <cstdint>

namespace raycell {

class SplitMix64 {
 public:
  explicit SplitMix64(std::uint64_t seed) : state_(seed) {}
  std::uint64_t Next() {
    std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }

 private:
  std::uint64_t state_;
};

}  // namespace raycell
