#include "replay/units.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <random>
#include <string>

#include "base/check.h"
#include "tests/test_util.h"

namespace raycell {
namespace {

constexpr std::uint64_t kMax = std::numeric_limits<std::uint64_t>::max();

using testing::ErrorOf;

TEST(ParseDuration, EveryUnit) {
  EXPECT_EQ(ParseDuration("250ps", "t"), SimTime::Picoseconds(250));
  EXPECT_EQ(ParseDuration("10ns", "t"), SimTime::Nanoseconds(10));
  EXPECT_EQ(ParseDuration("1.5 us", "t"), SimTime::Nanoseconds(1500));
  EXPECT_EQ(ParseDuration("1.5\xC2\xB5s", "t"), SimTime::Nanoseconds(1500));
  EXPECT_EQ(ParseDuration("1.5\xCE\xBCs", "t"), SimTime::Nanoseconds(1500));
  EXPECT_EQ(ParseDuration("2ms", "t"), SimTime::Milliseconds(2));
  EXPECT_EQ(ParseDuration("0.5s", "t"), SimTime::Milliseconds(500));
  EXPECT_EQ(ParseDuration("  40ns  ", "t"), SimTime::Nanoseconds(40));
  EXPECT_EQ(ParseDuration("0ns", "t"), SimTime::Zero());
  EXPECT_EQ(ParseDuration(".5ns", "t"), SimTime::Picoseconds(500));
  EXPECT_EQ(ParseDuration("1.000000000000000000000000000000ns", "t"), SimTime::Nanoseconds(1));
  EXPECT_EQ(ParseDuration("0.001ns", "t"), SimTime::Picoseconds(1));
  EXPECT_EQ(ParseDuration("18446744073709551615ps", "t"), SimTime::Max());
  EXPECT_EQ(ParseDuration("18446744.073709551615s", "t"), SimTime::Max());
}

TEST(ParseDuration, Errors) {
  const std::string what = "replay.toml:3:19: processors.time_per_sample";
  const auto err = [&](const char* text) { return ErrorOf([&] { ParseDuration(text, what); }); };
  EXPECT_EQ(err("10"), what + ": missing unit (expected ps, ns, us, ms or s): '10'");
  EXPECT_EQ(err("10 parsecs"),
            what + ": unknown unit 'parsecs' (expected ps, ns, us, ms or s): '10 parsecs'");
  EXPECT_EQ(err("-1ns"), what + ": negative values are not allowed: '-1ns'");
  EXPECT_EQ(err("+1ns"), what + ": a sign is not allowed: '+1ns'");
  EXPECT_EQ(err("nan"), what + ": not a finite number: 'nan'");
  EXPECT_EQ(err("NaNns"), what + ": not a finite number: 'NaNns'");
  EXPECT_EQ(err("inf"), what + ": not a finite number: 'inf'");
  EXPECT_EQ(err("-inf s"), what + ": not a finite number: '-inf s'");
  EXPECT_EQ(err("1e3ns"), what + ": exponents are not supported; use a unit prefix: '1e3ns'");
  EXPECT_EQ(err("0.0001ns"), what + ": not a whole number of picoseconds: '0.0001ns'");
  EXPECT_EQ(err("18446744073709551616ps"), what + ": value too large: '18446744073709551616ps'");
  EXPECT_EQ(err("1000000000s"), what + ": value too large: '1000000000s'");
  EXPECT_EQ(err(""), what + ": expected a number with a unit: ''");
  EXPECT_EQ(err("ns"), what + ": expected a number: 'ns'");
  EXPECT_EQ(err("."), what + ": expected a number: '.'");
  EXPECT_EQ(err("1.2.3ns"),
            what + ": unknown unit '.3ns' (expected ps, ns, us, ms or s): '1.2.3ns'");
  EXPECT_NE(err("99999999999999999999999999999999999999999999ps").find("too many"),
            std::string::npos);
}

TEST(FormatDuration, LargestExactUnit) {
  EXPECT_EQ(FormatDuration(SimTime::Zero()), "0ns");
  EXPECT_EQ(FormatDuration(SimTime::Picoseconds(250)), "250ps");
  EXPECT_EQ(FormatDuration(SimTime::Nanoseconds(10)), "10ns");
  EXPECT_EQ(FormatDuration(SimTime::Nanoseconds(40)), "40ns");
  EXPECT_EQ(FormatDuration(SimTime::Nanoseconds(1500)), "1.5us");
  EXPECT_EQ(FormatDuration(SimTime::Microseconds(1)), "1us");
  EXPECT_EQ(FormatDuration(SimTime::Picoseconds(1234567)), "1.234567us");
  EXPECT_EQ(FormatDuration(SimTime::Milliseconds(500)), "500ms");
  EXPECT_EQ(FormatDuration(SimTime::Seconds(3)), "3s");
  EXPECT_EQ(FormatDuration(SimTime::Max()), "18446744.073709551615s");
}

TEST(FormatDuration, RoundTripsExactly) {
  std::mt19937_64 rng(7);
  for (int i = 0; i < 20000; ++i) {
    // Spread over all magnitudes, with round values mixed in.
    std::uint64_t ps = rng() >> (rng() % 64);
    if (i % 3 == 0) ps -= ps % 1000;
    const SimTime t = SimTime::Picoseconds(ps);
    ASSERT_EQ(ParseDuration(FormatDuration(t), "t"), t) << FormatDuration(t);
  }
}

TEST(ParseBytes, EveryPrefix) {
  EXPECT_EQ(ParseBytes("512B", "b"), Bytes(512));
  EXPECT_EQ(ParseBytes("0B", "b"), Bytes(0));
  EXPECT_EQ(ParseBytes("2kB", "b"), Bytes(2000));
  EXPECT_EQ(ParseBytes("3MB", "b"), Bytes(3000000));
  EXPECT_EQ(ParseBytes("1.5GB", "b"), Bytes(1500000000));
  EXPECT_EQ(ParseBytes("2TB", "b"), Bytes(2000000000000));
  EXPECT_EQ(ParseBytes("4KiB", "b"), Bytes(4096));
  EXPECT_EQ(ParseBytes("64MiB", "b"), Bytes(64 << 20));
  EXPECT_EQ(ParseBytes("1.5 GiB", "b"), Bytes(std::uint64_t(3) << 29));
  EXPECT_EQ(ParseBytes("1TiB", "b"), Bytes(std::uint64_t(1) << 40));
  EXPECT_EQ(ParseBytes("0.5KiB", "b"), Bytes(512));
  EXPECT_EQ(ParseBytes("18446744073709551615B", "b"), Bytes(kMax));
}

TEST(ParseBytes, Errors) {
  const std::string what = "replay.toml:9:12: level 'board' capacity";
  const auto err = [&](const char* text) { return ErrorOf([&] { ParseBytes(text, what); }); };
  EXPECT_EQ(err("512"), what +
                            ": missing unit (expected B, kB, MB, GB, TB, KiB, MiB, GiB or TiB): "
                            "'512'");
  EXPECT_EQ(err("4KB"), what + ": ambiguous unit 'KB': use k (1000) or Ki (1024): '4KB'");
  EXPECT_EQ(err("4XB"), what +
                            ": unknown unit 'XB' (expected B, kB, MB, GB, TB, KiB, MiB, GiB or "
                            "TiB): '4XB'");
  EXPECT_EQ(err("4 cells"), what +
                                ": unknown unit 'cells' (expected B, kB, MB, GB, TB, KiB, MiB, "
                                "GiB or TiB): '4 cells'");
  EXPECT_EQ(err("64Mb"), what + ": a size is in bytes (B), not bits (b): '64Mb'");
  EXPECT_EQ(err("1.5B"), what + ": not a whole number of bytes: '1.5B'");
  EXPECT_EQ(err("0.0001KiB"), what + ": not a whole number of bytes: '0.0001KiB'");
  EXPECT_EQ(err("-1B"), what + ": negative values are not allowed: '-1B'");
  EXPECT_EQ(err("nan"), what + ": not a finite number: 'nan'");
  EXPECT_EQ(err("16777216TiB"), what + ": value too large: '16777216TiB'");
  EXPECT_EQ(err("18446744073709551616B"), what + ": value too large: '18446744073709551616B'");
}

TEST(Bytes, FormatsShortestExactForm) {
  EXPECT_EQ(Bytes(0).ToString(), "0B");
  EXPECT_EQ(Bytes(32).ToString(), "32B");
  EXPECT_EQ(Bytes(512).ToString(), "512B");
  EXPECT_EQ(Bytes(1000).ToString(), "1kB");
  EXPECT_EQ(Bytes(1024).ToString(), "1KiB");
  EXPECT_EQ(Bytes(1500000000).ToString(), "1.5GB");
  EXPECT_EQ(Bytes(std::uint64_t(256) << 20).ToString(), "256MiB");
  EXPECT_EQ(Bytes(1234).ToString(), "1234B");
}

TEST(Bytes, RoundTripsExactly) {
  std::mt19937_64 rng(11);
  for (int i = 0; i < 20000; ++i) {
    std::uint64_t n = rng() >> (rng() % 64);
    if (i % 4 == 0) n -= n % 1000;
    if (i % 4 == 1) n &= ~std::uint64_t(0) << 20;
    ASSERT_EQ(ParseBytes(Bytes(n).ToString(), "b"), Bytes(n)) << Bytes(n).ToString();
  }
  EXPECT_EQ(ParseBytes(Bytes(kMax).ToString(), "b"), Bytes(kMax));
}

TEST(ParseBandwidth, BytesAndBits) {
  EXPECT_EQ(ParseBandwidth("1.6GB/s", "bw"), Bandwidth::BytesPerSecond(1600000000));
  EXPECT_EQ(ParseBandwidth("133MB/s", "bw"), Bandwidth::BytesPerSecond(133000000));
  EXPECT_EQ(ParseBandwidth("800MiB/s", "bw"), Bandwidth::BytesPerSecond(800 << 20));
  EXPECT_EQ(ParseBandwidth("10Gb/s", "bw"), Bandwidth::BitsPerSecond(10000000000));
  EXPECT_EQ(ParseBandwidth("10Gb/s", "bw"), ParseBandwidth("1.25GB/s", "bw"));
  EXPECT_EQ(ParseBandwidth("1b/s", "bw"), Bandwidth::BitsPerSecond(1));
  EXPECT_EQ(ParseBandwidth("1B/s", "bw"), Bandwidth::BitsPerSecond(8));
  EXPECT_EQ(ParseBandwidth("3kb/s", "bw"), Bandwidth::BitsPerSecond(3000));
  EXPECT_EQ(ParseBandwidth("3Kib/s", "bw"), Bandwidth::BitsPerSecond(3072));
  EXPECT_EQ(ParseBandwidth("2 TB/s", "bw"), Bandwidth::BytesPerSecond(2000000000000));
  EXPECT_EQ(ParseBandwidth("1TiB/s", "bw"), Bandwidth::BytesPerSecond(std::uint64_t(1) << 40));
  EXPECT_EQ(ParseBandwidth("1 GiB /s", "bw"), Bandwidth::BytesPerSecond(1 << 30));
  EXPECT_TRUE(ParseBandwidth("inf", "bw").unlimited());
  EXPECT_TRUE(ParseBandwidth("unlimited", "bw").unlimited());
  EXPECT_TRUE(ParseBandwidth(" Unlimited ", "bw").unlimited());
  EXPECT_EQ(ParseBandwidth("1.6GB/s", "bw").bytes_per_second(), 1.6e9);
}

TEST(ParseBandwidth, Errors) {
  const std::string what = "replay.toml:12:13: level 'board' bandwidth";
  const auto err = [&](const char* text) { return ErrorOf([&] { ParseBandwidth(text, what); }); };
  EXPECT_EQ(err("0GB/s"), what + ": bandwidth must be greater than zero: '0GB/s'");
  EXPECT_EQ(err("0b/s"), what + ": bandwidth must be greater than zero: '0b/s'");
  EXPECT_EQ(err("nan"), what + ": not a finite number: 'nan'");
  EXPECT_EQ(err("-inf"), what + ": not a finite number: '-inf'");
  EXPECT_EQ(err("-1GB/s"), what + ": negative values are not allowed: '-1GB/s'");
  EXPECT_NE(err("1.6GB").find("unknown unit 'GB'"), std::string::npos);
  EXPECT_NE(err("1.6").find("missing unit"), std::string::npos);
  EXPECT_NE(err("1.6GX/s").find("unknown unit 'GX'"), std::string::npos);
  EXPECT_NE(err("1.6KB/s").find("ambiguous unit 'KB'"), std::string::npos);
  EXPECT_EQ(err("0.1b/s"), what + ": not a whole number of bits per second: '0.1b/s'");
  EXPECT_EQ(err("3000000TiB/s"), what + ": value too large: '3000000TiB/s'");
  for (const char* text : {"0GB/s", "nan", "1.6GX/s", "3000000TiB/s"}) {
    EXPECT_EQ(err(text).rfind(what, 0), 0u) << text;
    EXPECT_NE(err(text).find(text), std::string::npos) << text;
  }
}

TEST(Bandwidth, FormatsShortestExactForm) {
  EXPECT_EQ(Bandwidth::BytesPerSecond(1600000000).ToString(), "1.6GB/s");
  EXPECT_EQ(Bandwidth::BytesPerSecond(133000000).ToString(), "133MB/s");
  EXPECT_EQ(Bandwidth::BytesPerSecond(800 << 20).ToString(), "800MiB/s");
  EXPECT_EQ(Bandwidth::BitsPerSecond(10000000000).ToString(), "1.25GB/s");
  EXPECT_EQ(Bandwidth::BitsPerSecond(10000000001).ToString(), "10000000001b/s");
  EXPECT_EQ(Bandwidth::BitsPerSecond(1).ToString(), "1b/s");
  EXPECT_EQ(Bandwidth::Unlimited().ToString(), "unlimited");
}

TEST(Bandwidth, RoundTripsExactly) {
  std::mt19937_64 rng(13);
  for (int i = 0; i < 20000; ++i) {
    std::uint64_t bits = (rng() >> (rng() % 64)) | 1;
    if (i % 2 == 0) bits = (bits >> 3 << 3) | 8;
    if (i % 5 == 0) bits = (bits / 8000 + 1) * 8000;
    const Bandwidth b = Bandwidth::BitsPerSecond(bits);
    ASSERT_EQ(ParseBandwidth(b.ToString(), "bw"), b) << b.ToString();
  }
  EXPECT_EQ(ParseBandwidth(Bandwidth::BitsPerSecond(kMax).ToString(), "bw"),
            Bandwidth::BitsPerSecond(kMax));
  EXPECT_EQ(ParseBandwidth(Bandwidth::Unlimited().ToString(), "bw"), Bandwidth::Unlimited());
}

TEST(Bandwidth, TransferTimeRoundsUp) {
  const Bandwidth gb = ParseBandwidth("1GB/s", "bw");  // 1 byte per ns
  EXPECT_EQ(gb.TransferTime(0), SimTime::Zero());
  EXPECT_EQ(gb.TransferTime(1), SimTime::Nanoseconds(1));
  EXPECT_EQ(gb.TransferTime(64), SimTime::Nanoseconds(64));
  const Bandwidth pci = ParseBandwidth("133MB/s", "bw");
  // 1 byte in 10^12/133e6 ps = 7518.79... ps → 7519 ps.
  EXPECT_EQ(pci.TransferTime(1), SimTime::Picoseconds(7519));
  // 133 bytes in exactly 1 us.
  EXPECT_EQ(pci.TransferTime(133), SimTime::Microseconds(1));
  EXPECT_EQ(pci.TransferTime(134), SimTime::Picoseconds(1007519));
  const Bandwidth rdram = ParseBandwidth("1.6GB/s", "bw");
  EXPECT_EQ(rdram.TransferTime(16), SimTime::Nanoseconds(10));
  EXPECT_EQ(rdram.TransferTime(1), SimTime::Picoseconds(625));
  const Bandwidth slow = ParseBandwidth("3b/s", "bw");
  EXPECT_EQ(slow.TransferTime(1), SimTime::Picoseconds(2666666666667));  // 8/3 s rounded up
}

TEST(Bandwidth, TransferTimeExactOnBigValues) {
  const Bandwidth one_byte_per_ps = ParseBandwidth("1TB/s", "bw");
  EXPECT_EQ(one_byte_per_ps.TransferTime(1000000000000), SimTime::Seconds(1));
  EXPECT_EQ(one_byte_per_ps.TransferTime(1000000000001), SimTime::Picoseconds(1000000000001));
  EXPECT_EQ(one_byte_per_ps.TransferTime(kMax), SimTime::Max());
  // 10^12 bytes over PCI: 10^24 / 133e6 = 7518796992481203.0075... → rounds up.
  EXPECT_EQ(ParseBandwidth("133MB/s", "bw").TransferTime(1000000000000),
            SimTime::Picoseconds(7518796992481204));
  // A double would lose this: 2^60 + 1 bytes at 8 bit/ps is exactly 2^60 + 1 ps.
  EXPECT_EQ(ParseBandwidth("1TB/s", "bw").TransferTime((std::uint64_t(1) << 60) + 1),
            SimTime::Picoseconds((std::uint64_t(1) << 60) + 1));
}

TEST(Bandwidth, UnlimitedTakesNoTime) {
  EXPECT_EQ(Bandwidth::Unlimited().TransferTime(kMax), SimTime::Zero());
  EXPECT_EQ(Bandwidth().TransferTime(1), SimTime::Zero());
  EXPECT_TRUE(Bandwidth().unlimited());
  EXPECT_EQ(Bandwidth::Unlimited().bytes_per_second(), std::numeric_limits<double>::infinity());
}

TEST(BandwidthDeathTest, TransferTimeOverflowIsABug) {
  EXPECT_DEATH(ParseBandwidth("1b/s", "bw").TransferTime(kMax), "TransferTime");
}

}  // namespace
}  // namespace raycell
