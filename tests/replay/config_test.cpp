#include "replay/config.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <limits>
#include <string>

#include "base/check.h"
#include "replay/replacement.h"
#include "scheduling/scheduler.h"
#include "tests/test_util.h"

namespace raycell {
namespace {

using testing::ErrorOf;

std::string LoadError(const std::string& toml) {
  return ErrorOf([&] { LoadConfigFromString(toml, "replay.toml"); });
}

std::string WriteTemp(const std::string& name, const std::string& text) {
  const std::string path = testing::TempPath("config", name);
  std::ofstream(path) << text;
  return path;
}

TEST(DefaultConfig, ModelsTheGiCubeBoard) {
  const ReplayConfig c = DefaultConfig();
  ASSERT_EQ(c.levels.size(), 2u);
  const LevelConfig& cache = c.levels[0];
  EXPECT_EQ(cache.name, "cache");
  EXPECT_EQ(cache.capacity_unit, LevelConfig::CapacityUnit::kCells);
  EXPECT_EQ(cache.capacity, 1u);
  EXPECT_EQ(cache.bandwidth_below, ParseBandwidth("1.6GB/s", "t"));
  EXPECT_EQ(cache.latency_below, SimTime::Nanoseconds(40));
  EXPECT_EQ(cache.replacement, &kLruReplacement);
  const LevelConfig& board = c.levels[1];
  EXPECT_EQ(board.name, "board");
  EXPECT_EQ(board.capacity_unit, LevelConfig::CapacityUnit::kBytes);
  EXPECT_EQ(board.capacity, std::uint64_t(256) << 20);
  EXPECT_EQ(board.bandwidth_below, ParseBandwidth("133MB/s", "t"));
  EXPECT_EQ(board.latency_below, SimTime::Microseconds(1));
  EXPECT_EQ(c.processors.count, 1u);
  EXPECT_EQ(c.processors.time_per_sample, SimTime::Nanoseconds(10));
  EXPECT_EQ(c.processors.queue_record_bytes, 32u);
  EXPECT_FALSE(c.processors.prefetch);
  EXPECT_STREQ(c.scheduler_name(), "celltree");
  EXPECT_EQ(c.seed, 1u);
  EXPECT_EQ(c.granularity, ReplayConfig::Granularity::kAuto);
  EXPECT_NO_THROW(ValidateConfig(c, "defaults"));
}

TEST(DefaultConfig, EveryDefaultNamesItsSource) {
  const std::string toml = ToToml(DefaultConfig());
  for (const char* source :
       {"Direct RDRAM PC800", "RDRAM row access", "32-bit 33 MHz PCI", "a PCI transaction",
        "100 MHz pipeline", "colour/opacity", "cell size set to memory size", "Cell Tree"}) {
    EXPECT_NE(toml.find(source), std::string::npos) << source;
  }
  const std::string help = DefaultsHelp();
  for (const char* line : {"level.board.bandwidth = 133MB/s", "level.cache.capacity = 1 cell",
                           "processors.time_per_sample = 10ns", "scheduler = celltree"}) {
    EXPECT_NE(help.find(line), std::string::npos) << line << "\n" << help;
  }
  // Every help line has a non-empty source in parentheses.
  EXPECT_EQ(help.find("()"), std::string::npos) << help;
}

TEST(LoadConfig, EmptyFileGivesDefaults) {
  EXPECT_EQ(LoadConfigFromString("", "replay.toml"), DefaultConfig());
  EXPECT_EQ(LoadConfig(WriteTemp("empty.toml", "# nothing\n")), DefaultConfig());
}

TEST(LoadConfig, FullFileOverridesEverything) {
  const std::string path = WriteTemp("full.toml", R"(
scheduler = "maxwork"
seed = 42
granularity = "node"

[processors]
count = 16
time_per_sample = "2.5ns"
queue_record_bytes = "48B"
prefetch = true

[[level]]
name = "cache"
capacity = "4 cells"
bandwidth = "3.2GB/s"
latency = "20ns"
replacement = "fifo"

[[level]]
name = "board"
capacity = "1GiB"
bandwidth = "10Gb/s"
latency = "500ns"
replacement = "min"
)");
  const ReplayConfig c = LoadConfig(path);
  EXPECT_STREQ(c.scheduler_name(), "maxwork");
  EXPECT_EQ(c.seed, 42u);
  EXPECT_EQ(c.granularity, ReplayConfig::Granularity::kNode);
  EXPECT_EQ(c.processors.count, 16u);
  EXPECT_EQ(c.processors.time_per_sample, SimTime::Picoseconds(2500));
  EXPECT_EQ(c.processors.queue_record_bytes, 48u);
  EXPECT_TRUE(c.processors.prefetch);
  ASSERT_EQ(c.levels.size(), 2u);
  EXPECT_EQ(c.levels[0].capacity_unit, LevelConfig::CapacityUnit::kCells);
  EXPECT_EQ(c.levels[0].capacity, 4u);
  EXPECT_EQ(c.levels[0].bandwidth_below, Bandwidth::BytesPerSecond(3200000000));
  EXPECT_EQ(c.levels[0].latency_below, SimTime::Nanoseconds(20));
  EXPECT_EQ(c.levels[0].replacement, &kFifoReplacement);
  EXPECT_EQ(c.levels[1].capacity_unit, LevelConfig::CapacityUnit::kBytes);
  EXPECT_EQ(c.levels[1].capacity, std::uint64_t(1) << 30);
  EXPECT_EQ(c.levels[1].bandwidth_below, Bandwidth::BitsPerSecond(10000000000));
  EXPECT_EQ(c.levels[1].latency_below, SimTime::Nanoseconds(500));
  EXPECT_EQ(c.levels[1].replacement, &kMinReplacement);
  std::remove(path.c_str());
}

TEST(LoadConfig, PartialSectionsKeepOtherDefaults) {
  const ReplayConfig c = LoadConfigFromString("[processors]\ncount = 4\n", "replay.toml");
  ReplayConfig expected = DefaultConfig();
  expected.processors.count = 4;
  EXPECT_EQ(c, expected);
}

TEST(LoadConfig, LevelArrayReplacesDefaultLevels) {
  const ReplayConfig c = LoadConfigFromString(R"(
[[level]]
name = "l1"
capacity = "64KiB"
bandwidth = "unlimited"
latency = "0ns"
)",
                                              "replay.toml");
  ASSERT_EQ(c.levels.size(), 1u);
  EXPECT_EQ(c.levels[0].name, "l1");
  EXPECT_EQ(c.levels[0].capacity, 65536u);
  EXPECT_TRUE(c.levels[0].bandwidth_below.unlimited());
  EXPECT_EQ(c.levels[0].latency_below, SimTime::Zero());
  EXPECT_EQ(c.levels[0].replacement, &kLruReplacement);
  EXPECT_EQ(c.processors, DefaultConfig().processors);
}

TEST(LoadConfig, DefaultNamedLevelStartsFromItsDefaults) {
  const ReplayConfig c =
      LoadConfigFromString("[[level]]\nname = \"board\"\ncapacity = \"64MiB\"\n", "replay.toml");
  ASSERT_EQ(c.levels.size(), 1u);
  LevelConfig expected = DefaultConfig().levels[1];
  expected.capacity = 64 << 20;
  EXPECT_EQ(c.levels[0], expected);
}

TEST(LoadConfig, NewLevelNeedsEveryValue) {
  EXPECT_EQ(LoadError("[[level]]\nname = \"l2\"\ncapacity = \"1MiB\"\nlatency = \"1ns\"\n"),
            "replay.toml:1:1: level 'l2' missing required key 'bandwidth'");
  EXPECT_EQ(LoadError("[[level]]\ncapacity = \"1MiB\"\n"),
            "replay.toml:1:1: level #1 missing required key 'name'");
}

TEST(LoadConfig, UnknownKeyNamesFileLineColumnAndKey) {
  EXPECT_EQ(LoadError("seed = 3\nsceduler = \"peel\"\n"),
            "replay.toml:2:1: unknown key 'sceduler' in the top-level table (valid keys: "
            "granularity, level, memory, processors, scheduler, seed)");
  const std::string e = LoadError("[processors]\ncount = 2\n  time_per_sampel = \"1ns\"\n");
  EXPECT_EQ(e.rfind("replay.toml:3:3: unknown key 'time_per_sampel' in [processors]", 0), 0u) << e;
  const std::string l = LoadError(
      "[[level]]\nname = \"cache\"\n\n[[level]]\nname = \"board\"\nbandwith = \"1GB/s\"\n");
  EXPECT_EQ(l.rfind("replay.toml:6:1: unknown key 'bandwith' in [[level]] 'board'", 0), 0u) << l;
  EXPECT_EQ(
      LoadError("[memory]\nsize = 1\n").rfind("replay.toml:2:1: unknown key 'size' in [memory]", 0),
      0u);
  EXPECT_EQ(LoadError("[memory]\nacross_frames = \"tepid\"\n"),
            "replay.toml:2:17: memory.across_frames: unknown memory.across_frames 'tepid' "
            "(expected warm or cold)");
  EXPECT_EQ(LoadError("[mem]\n").rfind("replay.toml:1:2: unknown key 'mem'", 0), 0u);
  // The first unknown key in the file is reported, whatever the table order.
  EXPECT_EQ(LoadError("zzz = 1\naaa = 2\n").rfind("replay.toml:1:1: unknown key 'zzz'", 0), 0u);
}

TEST(LoadConfig, WrongTypeNamesFileAndLine) {
  EXPECT_EQ(LoadError("[processors]\ncount = \"4\"\n"),
            "replay.toml:2:9: processors.count: expected an integer, got a string");
  EXPECT_EQ(LoadError("[processors]\ncount = 4.0\n"),
            "replay.toml:2:9: processors.count: expected an integer, got a floating-point number");
  EXPECT_EQ(LoadError("[processors]\ntime_per_sample = 10\n"),
            "replay.toml:2:19: processors.time_per_sample: expected a duration string such as "
            "\"10ns\", got an integer");
  EXPECT_EQ(LoadError("[processors]\nprefetch = 1\n"),
            "replay.toml:2:12: processors.prefetch: expected true or false, got an integer");
  EXPECT_EQ(LoadError("processors = 3\n"),
            "replay.toml:1:14: processors: expected a [processors] table, got an integer");
  EXPECT_EQ(LoadError("level = 3\n"),
            "replay.toml:1:9: level: expected [[level]] tables, got an integer");
  EXPECT_EQ(LoadError("level = []\n"), "replay.toml:1:9: level: at least one level is required");
  EXPECT_EQ(LoadError("[[level]]\nname = \"a\"\ncapacity = 4\n"),
            "replay.toml:3:12: level 'a' capacity: expected a string such as \"1 cell\" or "
            "\"256MiB\", got an integer");
}

TEST(LoadConfig, BadUnitsAndValuesNameFileAndLine) {
  EXPECT_EQ(LoadError("[processors]\ntime_per_sample = \"10 parsecs\"\n"),
            "replay.toml:2:19: processors.time_per_sample: unknown unit 'parsecs' (expected ps, "
            "ns, us, ms or s): '10 parsecs'");
  EXPECT_EQ(LoadError("[processors]\ntime_per_sample = \"0ns\"\n"),
            "replay.toml:2:19: processors.time_per_sample: must be greater than zero: '0ns'");
  EXPECT_EQ(LoadError("[[level]]\nname = \"board\"\nbandwidth = \"0MB/s\"\n"),
            "replay.toml:3:13: level 'board' bandwidth: bandwidth must be greater than zero: "
            "'0MB/s'");
  EXPECT_EQ(LoadError("[[level]]\nname = \"board\"\ncapacity = \"0 cells\"\n"),
            "replay.toml:3:12: level 'board' capacity (cells): must be in "
            "1..18446744073709551615, got 0");
  EXPECT_EQ(LoadError("[[level]]\nname = \"board\"\ncapacity = \"0B\"\n"),
            "replay.toml:3:12: level 'board' capacity: capacity must be greater than zero: '0B'");
  EXPECT_EQ(LoadError("[processors]\ncount = 0\n"),
            "replay.toml:2:9: processors.count: must be in 1..1024, got 0");
  EXPECT_EQ(LoadError("[processors]\ncount = 1025\n"),
            "replay.toml:2:9: processors.count: must be in 1..1024, got 1025");
  EXPECT_EQ(LoadError("seed = -1\n"),
            "replay.toml:1:8: seed: must be in 0..18446744073709551615, got -1");
  EXPECT_EQ(LoadError("scheduler = \"fastest\"\n"),
            "replay.toml:1:13: scheduler: unknown scheduler 'fastest' (expected maxwork, "
            "roundrobin, random, peel, celltree, best, celltree-best, celltree-union, affinity, "
            "partition, steal, partition-steal, share, balanced, celltree-2level, "
            "celltree-2level-best, balanced-critical, balanced-adaptive, celltree-adaptive, "
            "celltree-dag, celltree-dag-oracle or auto)");
  EXPECT_EQ(
      LoadError("granularity = \"cell\"\n"),
      "replay.toml:1:15: granularity: unknown granularity 'cell' (expected ray, node or auto)");
  EXPECT_EQ(LoadError("[[level]]\nname = \"cache\"\nreplacement = \"mru\"\n"),
            "replay.toml:3:15: level 'cache' replacement: unknown replacement 'mru' (expected "
            "lru, fifo or min)");
  EXPECT_EQ(LoadError("[[level]]\nname = \"a.b\"\n"),
            "replay.toml:2:8: level #1 name: 'a.b' is not a valid level name (use [A-Za-z0-9_-]+)");
  EXPECT_EQ(LoadError("[[level]]\nname = \"cache\"\n[[level]]\nname = \"cache\"\n"),
            "replay.toml:3:1: level: duplicate level name 'cache' (first at replay.toml:1:1)");
}

TEST(LoadConfig, NanAndInfinityAreRejected) {
  // TOML's nan and inf are floats: rejected where a duration string or an integer is expected.
  EXPECT_EQ(LoadError("[processors]\ntime_per_sample = nan\n"),
            "replay.toml:2:19: processors.time_per_sample: expected a duration string such as "
            "\"10ns\", got a floating-point number");
  EXPECT_EQ(LoadError("[processors]\ncount = nan\n"),
            "replay.toml:2:9: processors.count: expected an integer, got a floating-point number");
  EXPECT_EQ(LoadError("seed = inf\n"),
            "replay.toml:1:8: seed: expected an integer, got a floating-point number");
  EXPECT_EQ(LoadError("[processors]\nqueue_record_bytes = -inf\n"),
            "replay.toml:2:22: processors.queue_record_bytes: expected an integer, got a "
            "floating-point number");
  EXPECT_EQ(LoadError("[[level]]\nname = \"cache\"\nlatency = nan\n")
                .rfind("replay.toml:3:11: level 'cache' latency: expected a duration string", 0),
            0u);
  // And inside strings.
  EXPECT_EQ(LoadError("[processors]\ntime_per_sample = \"nan\"\n"),
            "replay.toml:2:19: processors.time_per_sample: not a finite number: 'nan'");
  EXPECT_EQ(LoadError("[[level]]\nname = \"cache\"\nbandwidth = \"nan GB/s\"\n"),
            "replay.toml:3:13: level 'cache' bandwidth: not a finite number: 'nan GB/s'");
}

TEST(LoadConfig, SyntaxErrorsAndMissingFiles) {
  const std::string e = LoadError("seed = \n");
  EXPECT_EQ(e.rfind("replay.toml:1:", 0), 0u) << e;
  const std::string m = ErrorOf([] { LoadConfig("/nonexistent/replay.toml"); });
  EXPECT_EQ(m, "/nonexistent/replay.toml: cannot open the replay configuration");
  // A folder opens as a stream that reads nothing: it must not pass for an empty (all
  // defaults) configuration.
  const std::string d = ErrorOf([] { LoadConfig("/tmp"); });
  EXPECT_EQ(d, "/tmp: cannot open the replay configuration");
}

ReplayConfig Unusual() {
  ReplayConfig c = DefaultConfig();
  c.scheduler = &SchedulerByName("random", "test");
  c.seed = std::numeric_limits<std::uint64_t>::max();
  c.granularity = ReplayConfig::Granularity::kNode;
  c.processors.count = 1024;
  c.processors.time_per_sample = SimTime::Picoseconds(1234567);
  c.processors.queue_record_bytes = std::numeric_limits<std::uint64_t>::max();
  c.processors.prefetch = true;
  c.levels[0].capacity = 3;
  c.levels[0].replacement = &kMinReplacement;
  c.levels[1].bandwidth_below = Bandwidth::BitsPerSecond(10000000001);
  c.levels[1].latency_below = SimTime::Zero();
  LevelConfig l3;
  l3.name = "host-cache_3";
  l3.capacity_unit = LevelConfig::CapacityUnit::kBytes;
  l3.capacity = 123456789;
  l3.bandwidth_below = Bandwidth::Unlimited();
  l3.latency_below = SimTime::Max();
  l3.replacement = &kFifoReplacement;
  l3.cells = "kd:budget:1MiB";
  c.levels[1].cells = "3x3x3";
  c.levels.push_back(l3);
  return c;
}

// A level of coarser cells (issue 23): a SPEC, checked and printed canonically; "same" is the
// replay's cells; only shared levels; not dynamic.
TEST(LoadConfig, LevelCellsAreASpecOfASharedLevel) {
  ReplayConfig c = LoadConfigFromString(
      "[[level]]\nname = \"cache\"\n[[level]]\nname = \"board\"\ncells = \"kd:27:footprint\"\n",
      "x");
  EXPECT_EQ(c.levels[0].cells, "");
  EXPECT_EQ(c.levels[1].cells, "kd:27:footprint");
  EXPECT_NE(ToToml(c).find("cells = \"kd:27:footprint\""), std::string::npos);
  ApplyOverride(c, "level.board.cells", "same");
  EXPECT_EQ(c, DefaultConfig());
  EXPECT_EQ(LoadError("[[level]]\nname = \"cache\"\ncells = \"3x3x3\"\n"),
            "replay.toml: level 'cache' cells = '3x3x3': the first level holds the cells the "
            "processors work; only a shared level may hold coarser ones");
  EXPECT_EQ(ErrorOf([&] { ApplyOverride(c, "level.board.cells", "dynamic:8"); }),
            "override 'level.board.cells': 'dynamic:8': a memory level's cells stay the same "
            "over the frames; dynamic subdivisions are for --cells");
  EXPECT_EQ(ErrorOf([&] { ApplyOverride(c, "level.board.cells", "auto:27"); }),
            "override 'level.board.cells': 'auto:27': a memory level's cells stay the same "
            "over the frames; dynamic subdivisions are for --cells");
  EXPECT_EQ(ErrorOf([&] {
              ApplyOverride(c, "level.board.cells", "3x3");
            }).rfind("override 'level.board.cells': ", 0),
            0u);
  EXPECT_EQ(c, DefaultConfig());  // a refused override changes nothing
}

TEST(ToToml, RoundTripsExactly) {
  for (const ReplayConfig& c : {DefaultConfig(), Unusual()}) {
    const std::string toml = ToToml(c);
    EXPECT_EQ(LoadConfigFromString(toml, "printed.toml"), c) << toml;
    const std::string path = WriteTemp("roundtrip.toml", toml);
    EXPECT_EQ(LoadConfig(path), c);
    EXPECT_EQ(ToToml(LoadConfig(path)), toml);
    std::remove(path.c_str());
  }
  EXPECT_NE(DefaultConfig(), Unusual());
}

TEST(ToToml, PrintsUnitsAndComments) {
  const std::string toml = ToToml(DefaultConfig());
  EXPECT_NE(toml.find("bandwidth = \"1.6GB/s\"\n"), std::string::npos) << toml;
  EXPECT_NE(toml.find("bandwidth = \"133MB/s\"\n"), std::string::npos);
  EXPECT_NE(toml.find("capacity = \"256MiB\"\n"), std::string::npos);
  EXPECT_NE(toml.find("capacity = \"1 cell\"\n"), std::string::npos);
  EXPECT_NE(toml.find("latency = \"1us\"\n"), std::string::npos);
  EXPECT_NE(toml.find("time_per_sample = \"10ns\"\n"), std::string::npos);
  EXPECT_NE(toml.find("# Default \"1.6GB/s\": one Direct RDRAM PC800 channel"), std::string::npos);
}

TEST(ApplyOverride, SetsTypedValues) {
  ReplayConfig c = DefaultConfig();
  ApplyOverride(c, "processors.count", "8");
  ApplyOverride(c, "processors.time_per_sample", "2.5ns");
  ApplyOverride(c, "processors.queue_record_bytes", "64");
  ApplyOverride(c, "processors.prefetch", "true");
  ApplyOverride(c, "level.cache.capacity", "2 cells");
  ApplyOverride(c, "level.board.capacity", "1GiB");
  ApplyOverride(c, "level.board.bandwidth", "266MB/s");
  ApplyOverride(c, "level.cache.latency", "0ns");
  ApplyOverride(c, "level.board.replacement", "min");
  ApplyOverride(c, "scheduler", "peel");
  ApplyOverride(c, "granularity", "node");
  ApplyOverride(c, "seed", "18446744073709551615");
  EXPECT_EQ(c.processors.count, 8u);
  EXPECT_EQ(c.processors.time_per_sample, SimTime::Picoseconds(2500));
  EXPECT_EQ(c.processors.queue_record_bytes, 64u);
  EXPECT_TRUE(c.processors.prefetch);
  EXPECT_EQ(c.levels[0].capacity, 2u);
  EXPECT_EQ(c.levels[1].capacity_unit, LevelConfig::CapacityUnit::kBytes);
  EXPECT_EQ(c.levels[1].capacity, std::uint64_t(1) << 30);
  EXPECT_EQ(c.levels[1].bandwidth_below, Bandwidth::BytesPerSecond(266000000));
  EXPECT_EQ(c.levels[0].latency_below, SimTime::Zero());
  EXPECT_EQ(c.levels[1].replacement, &kMinReplacement);
  EXPECT_STREQ(c.scheduler_name(), "peel");
  EXPECT_EQ(c.granularity, ReplayConfig::Granularity::kNode);
  EXPECT_EQ(c.seed, std::numeric_limits<std::uint64_t>::max());
  ApplyOverride(c, "level.board.capacity", "16 cells");
  EXPECT_EQ(c.levels[1].capacity_unit, LevelConfig::CapacityUnit::kCells);
  EXPECT_EQ(LoadConfigFromString(ToToml(c), "x"), c);
}

TEST(ApplyOverride, ErrorsNameTheKeyAndLeaveTheConfigUnchanged) {
  ReplayConfig c = DefaultConfig();
  const auto err = [&](const char* key, const char* value) {
    return ErrorOf([&] { ApplyOverride(c, key, value); });
  };
  const std::string unknown = err("processors.cores", "4");
  EXPECT_EQ(unknown.rfind("override 'processors.cores': unknown key (valid keys: scheduler, seed, "
                          "granularity, processors.count, ",
                          0),
            0u)
      << unknown;
  EXPECT_NE(unknown.find("level.board.bandwidth"), std::string::npos);
  EXPECT_EQ(err("level.l3.capacity", "1MiB"),
            "override 'level.l3.capacity': no level named 'l3' (levels: cache, board)");
  EXPECT_EQ(err("level.cache.size", "1MiB"),
            "override 'level.cache.size': unknown level key 'size' (expected capacity, "
            "bandwidth, latency, replacement or cells)");
  EXPECT_EQ(err("processors.count", "0"), "override 'processors.count': must be in 1..1024, got 0");
  EXPECT_EQ(err("processors.count", "four"),
            "override 'processors.count': expected a whole number, got 'four'");
  EXPECT_EQ(err("processors.time_per_sample", "nan"),
            "override 'processors.time_per_sample': not a finite number: 'nan'");
  EXPECT_EQ(err("processors.time_per_sample", "10"),
            "override 'processors.time_per_sample': missing unit (expected ps, ns, us, ms or s): "
            "'10'");
  EXPECT_EQ(err("level.board.bandwidth", "0GB/s"),
            "override 'level.board.bandwidth': bandwidth must be greater than zero: '0GB/s'");
  EXPECT_EQ(err("processors.prefetch", "yes"),
            "override 'processors.prefetch': expected true or false, got 'yes'");
  EXPECT_EQ(err("scheduler", "fastest"),
            "override 'scheduler': unknown scheduler 'fastest' (expected maxwork, roundrobin, "
            "random, peel, celltree, best, celltree-best, celltree-union, affinity, partition, "
            "steal, partition-steal, share, balanced, celltree-2level, "
            "celltree-2level-best, balanced-critical, balanced-adaptive, celltree-adaptive, "
            "celltree-dag, celltree-dag-oracle or auto)");
  EXPECT_EQ(c, DefaultConfig());
}

TEST(OverrideKeys, ListsLevelKeysByName) {
  const std::vector<std::string> keys = OverrideKeys(DefaultConfig());
  EXPECT_EQ(keys.size(), 8u + 2 * 5);
  EXPECT_EQ(keys.back(), "level.board.cells");
}

TEST(ValidateConfig, Invariants) {
  ReplayConfig c = DefaultConfig();
  c.levels.clear();
  EXPECT_EQ(ErrorOf([&] { ValidateConfig(c, "cfg"); }), "cfg: at least one level is required");
  c = DefaultConfig();
  c.levels[1].name = "cache";
  EXPECT_EQ(ErrorOf([&] { ValidateConfig(c, "cfg"); }), "cfg: duplicate level name 'cache'");
  c = DefaultConfig();
  c.levels[0].capacity = 0;
  EXPECT_EQ(ErrorOf([&] { ValidateConfig(c, "cfg"); }),
            "cfg: level 'cache' capacity must be greater than zero");
  c = DefaultConfig();
  c.processors.count = 2000;
  EXPECT_EQ(ErrorOf([&] { ValidateConfig(c, "cfg"); }),
            "cfg: processors.count must be in 1..1024, got 2000");
  c = DefaultConfig();
  c.processors.time_per_sample = SimTime::Zero();
  EXPECT_EQ(ErrorOf([&] { ValidateConfig(c, "cfg"); }),
            "cfg: processors.time_per_sample must be greater than zero");
  c = DefaultConfig();
  c.scheduler = nullptr;
  EXPECT_EQ(ErrorOf([&] { ValidateConfig(c, "cfg"); }), "cfg: no scheduler");
}

}  // namespace
}  // namespace raycell

namespace raycell {
namespace {

// The scheduler list is derived from the registry (scheduling/scheduler.h) everywhere: every
// registered name is accepted by overrides and files and named in the printed configuration.
TEST(ConfigKeys, EverySchedulerOfTheRegistryIsAcceptedAndDocumented) {
  const std::string toml = ToToml(DefaultConfig());
  for (const std::string& name : SchedulerNames()) {
    ReplayConfig c = DefaultConfig();
    ApplyOverride(c, "scheduler", name);
    EXPECT_EQ(c.scheduler_name(), name);
    EXPECT_EQ(LoadConfigFromString("scheduler = \"" + name + "\"\n", "x.toml").scheduler_name(),
              name);
    EXPECT_NE(toml.find(name), std::string::npos) << name;
  }
}

// Every override key reads back from the TOML the writer prints for it: one descriptor serves
// the reader, the writer and the overrides.
TEST(ConfigKeys, EveryOverrideKeyAppearsInThePrintedConfigurationAndInTheHelp) {
  const ReplayConfig d = DefaultConfig();
  const std::string toml = ToToml(d), help = DefaultsHelp();
  for (const std::string& key : OverrideKeys(d)) {
    const std::string table_key = key.substr(key.rfind('.') + 1);
    EXPECT_NE(toml.find("\n" + table_key + " = "), std::string::npos) << key;
    EXPECT_NE(help.find("  " + key + " = "), std::string::npos) << key;
  }
}

}  // namespace
}  // namespace raycell
