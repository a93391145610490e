#include "engine/time.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <sstream>
#include <type_traits>

#include "base/checked.h"

namespace raycell {
namespace {

constexpr std::uint64_t kTrillion = 1000'000'000'000;

// Typed and explicit: no conversion from or to plain integers.
static_assert(!std::is_convertible_v<std::uint64_t, SimTime>);
static_assert(!std::is_convertible_v<int, SimTime>);
static_assert(!std::is_constructible_v<SimTime, std::uint64_t>);
static_assert(!std::is_convertible_v<SimTime, std::uint64_t>);

TEST(SimTime, UnitConstructorsScaleToPicosecondsAndCompareByValue) {
  EXPECT_EQ(SimTime::Nanoseconds(3).picoseconds(), 3000u);
  EXPECT_EQ(SimTime::Microseconds(3).picoseconds(), 3000'000u);
  EXPECT_EQ(SimTime::Milliseconds(3).picoseconds(), 3000'000'000u);
  EXPECT_EQ(SimTime::Seconds(3).picoseconds(), 3 * kTrillion);
  EXPECT_EQ(SimTime::Zero(), SimTime());
  EXPECT_LT(SimTime::Picoseconds(1), SimTime::Picoseconds(2));
  EXPECT_GE(SimTime::Nanoseconds(1), SimTime::Picoseconds(1000));
  EXPECT_EQ(SimTime::Nanoseconds(5) - SimTime::Nanoseconds(2), SimTime::Picoseconds(3000));
}

TEST(SimTime, PrintsAsWholePicoseconds) {
  EXPECT_EQ(SimTime::Nanoseconds(12).ToString(), "12000ps");
  std::ostringstream s;
  s << SimTime::Picoseconds(7);
  EXPECT_EQ(s.str(), "7ps");
}

TEST(SimTime, FromSecondsRoundsToNearestPicosecond) {
  EXPECT_EQ(SimTime::FromSeconds(1.0), SimTime::Seconds(1));
  EXPECT_EQ(SimTime::FromSeconds(1e-12), SimTime::Picoseconds(1));
  EXPECT_EQ(SimTime::FromSeconds(2.5e-9), SimTime::Picoseconds(2500));
  EXPECT_EQ(SimTime::FromSeconds(0.0), SimTime::Zero());
  EXPECT_EQ(SimTime::FromSeconds(1e6), SimTime::Seconds(1000'000));
}

TEST(SimTime, TryFromSecondsRejectsUnrepresentable) {
  EXPECT_FALSE(SimTime::TryFromSeconds(-1e-12).has_value());
  EXPECT_FALSE(SimTime::TryFromSeconds(std::numeric_limits<double>::quiet_NaN()).has_value());
  EXPECT_FALSE(SimTime::TryFromSeconds(std::numeric_limits<double>::infinity()).has_value());
  EXPECT_FALSE(SimTime::TryFromSeconds(1.9e7).has_value());  // 1.9e19 ps > 2^64 - 1
  EXPECT_TRUE(SimTime::TryFromSeconds(1.8e7).has_value());   // 1.8e19 ps < 2^64 - 1
}

// docs/design.md: simulated time for 10^12 samples at 1 ps each is exact.
TEST(SimTime, TrillionOnePicosecondSamplesAreExact) {
  const SimTime sample = SimTime::Picoseconds(1);
  EXPECT_EQ((sample * kTrillion).picoseconds(), kTrillion);
  // The same by repeated adds: 10^6 adds of 1 ps make a block, 10^6 blocks make the total.
  SimTime block;
  for (int i = 0; i < 1000'000; ++i) block += sample;
  SimTime total;
  for (int i = 0; i < 1000'000; ++i) total += block;
  EXPECT_EQ(total, SimTime::Seconds(1));
  EXPECT_EQ(total.picoseconds(), kTrillion);
  // Headroom: 10^12 samples of 18 us each (1.8e19 ps) still fit in 64 bits.
  EXPECT_EQ((SimTime::Microseconds(18) * kTrillion).picoseconds(), 18'000'000 * kTrillion);
}

TEST(SimTimeDeathTest, AddOverflowIsDetected) {
  EXPECT_DEATH(SimTime::Max() + SimTime::Picoseconds(1), "CheckedAdd overflow");
}

TEST(SimTimeDeathTest, MultiplyOverflowIsDetected) {
  EXPECT_DEATH(SimTime::Microseconds(19) * kTrillion, "CheckedMul overflow");
  EXPECT_DEATH(SimTime::Seconds(20'000'000), "CheckedMul overflow");
}

TEST(SimTimeDeathTest, NegativeDifferenceIsDetected) {
  EXPECT_DEATH(SimTime::Picoseconds(1) - SimTime::Picoseconds(2), "CheckedSub underflow");
}

TEST(SimTimeDeathTest, FromSecondsChecks) {
  EXPECT_DEATH(SimTime::FromSeconds(-1.0), "FromSeconds");
  EXPECT_DEATH(SimTime::FromSeconds(std::numeric_limits<double>::quiet_NaN()), "FromSeconds");
  EXPECT_DEATH(SimTime::FromSeconds(1e30), "FromSeconds");
}

TEST(Checked, ExactNearTheLimit) {
  const std::uint64_t max = std::numeric_limits<std::uint64_t>::max();
  EXPECT_EQ(CheckedAdd(max - 1, 1), max);
  EXPECT_EQ(CheckedMul(max / 3, 3), max);
  std::uint64_t counter = max - 2;
  CheckedIncrement(counter);
  CheckedIncrement(counter);
  EXPECT_EQ(counter, max);
}

TEST(CheckedDeathTest, CounterOverflowIsDetected) {
  std::uint64_t counter = std::numeric_limits<std::uint64_t>::max();
  EXPECT_DEATH(CheckedIncrement(counter), "CheckedAdd overflow.*18446744073709551615 vs 1");
  EXPECT_DEATH(CheckedMul(std::uint64_t(1) << 32, std::uint64_t(1) << 32), "CheckedMul overflow");
  EXPECT_DEATH(CheckedSub(0, 1), "CheckedSub underflow");
}

}  // namespace
}  // namespace raycell
