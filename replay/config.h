// The replay configuration (docs/design.md §2 "Configuration"): typed structs read from TOML
// (CONTRIBUTING.md: configuration read into typed structs with defaults). Every key in a file
// must be read: an unknown key is an InputError naming FILE:LINE:COL, like pbrt's
// ReportUnused. Units are parsed once at load (replay/units.h). Each key is described once,
// in config.cpp's key tables: name, meaning, TOML type, parser, printer, its default and where
// the default comes from; DefaultConfig(), the TOML reader and writer, --set/--vary overrides
// and --help derive from them. `raycell replay --print-config` prints the whole file with the
// defaults and their sources: the GI-Cube board on the slides, a PCI board whose block
// processors are backed by Direct RDRAM, with host memory reached over PCI.
//
// A value-initialised struct below is not a configuration: start from DefaultConfig().
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "engine/time.h"
#include "replay/units.h"

namespace raycell {

struct SchedulerEntry;    // scheduling/scheduler.h
struct ReplacementEntry;  // replay/replacement.h
extern const ReplacementEntry kLruReplacement;

// The processor count's range, 1..kMaxProcessors: the one place it is stated (the key's
// parser and meaning, ValidateConfig, --help and --print-config read it).
inline constexpr std::uint32_t kMaxProcessors = 1024;

struct LevelConfig {
  enum class CapacityUnit { kBytes, kCells };

  // Unique, [A-Za-z0-9_-]+ (it appears in override keys "level.NAME.KEY").
  std::string name;
  CapacityUnit capacity_unit = CapacityUnit::kCells;
  // In bytes or cells per capacity_unit; > 0.
  std::uint64_t capacity = 0;
  // To the level below (the level below the last is host memory, itself unlimited).
  Bandwidth bandwidth_below;
  SimTime latency_below;
  // An entry of ReplacementRegistry() (replay/replacement.h), resolved from its name once,
  // where the configuration is read; a level a file adds without naming its replacement gets
  // LRU.
  const ReplacementEntry* replacement = &kLruReplacement;
  // What the level stores and moves (docs/design.md §2 "Levels of coarser cells"): empty
  // ("same" in files and overrides), the replay's cells; else a SPEC of a regroupable capture's
  // fine grid (traces/subdivision.h, not dynamic) whose cells are unions of the replay's, e.g. a
  // board of 3x3x3 cells for caches of 6x6x6 ones. Only shared levels (not the first); checked
  // against the trace when a replay starts (replay/level_units.h CoarserLevelCells).
  std::string cells;
};

struct ProcessorConfig {
  std::uint32_t count = 0;               // block processors, 1..kMaxProcessors
  SimTime time_per_sample;               // > 0
  std::uint64_t queue_record_bytes = 0;  // per queued ray
  bool prefetch = false;  // double buffering: fetch the next scheduled cell while working
};

// What the memory levels hold when a frame starts (docs/design.md §2 "Memory").
struct MemoryConfig {
  // kWarm: what the previous frame's replay left (frame 0: empty); kCold: empty, the paper's
  // model of every frame on its own.
  enum class AcrossFrames { kWarm, kCold };
  AcrossFrames across_frames = AcrossFrames::kWarm;
};
inline bool operator==(const MemoryConfig& a, const MemoryConfig& b) {
  return a.across_frames == b.across_frames;
}

struct ReplayConfig {
  // kAuto: per node where that is exact (one processor), per ray segment otherwise.
  enum class Granularity { kRay, kNode, kAuto };

  // Nearest (on-chip cache) to farthest; the level below the last is host memory, unlimited.
  std::vector<LevelConfig> levels;
  ProcessorConfig processors;
  MemoryConfig memory;
  // An entry of SchedulerRegistry() (scheduling/scheduler.h), resolved from its name once,
  // where the configuration is read; never null in a valid configuration.
  const SchedulerEntry* scheduler = nullptr;
  // Seeds the random scheduler and the planners' schedule searches; any fixed value keeps
  // replays deterministic.
  std::uint64_t seed = 0;
  Granularity granularity = Granularity::kAuto;

  // The scheduler's name ("celltree").
  const char* scheduler_name() const;
};

bool operator==(const LevelConfig& a, const LevelConfig& b);
bool operator!=(const LevelConfig& a, const LevelConfig& b);
bool operator==(const ProcessorConfig& a, const ProcessorConfig& b);
bool operator!=(const ProcessorConfig& a, const ProcessorConfig& b);
bool operator==(const ReplayConfig& a, const ReplayConfig& b);
bool operator!=(const ReplayConfig& a, const ReplayConfig& b);

// "ray" | "node" | "auto"; "warm" | "cold"; "bytes" | "cells" (a level's replacement is named by
// its entry, ReplacementEntry::name).
std::string_view ToString(ReplayConfig::Granularity g);
std::string_view ToString(MemoryConfig::AcrossFrames a);
// The granularity a replay of `config` runs at: kAuto resolved.
ReplayConfig::Granularity EffectiveGranularity(const ReplayConfig& config);
std::string_view ToString(LevelConfig::CapacityUnit u);

// A level's capacity as written in files and overrides: "1 cell", "4 cells" or "256MiB".
std::string FormatCapacity(const LevelConfig& level);

// The defaults of config.cpp's key tables: the GI-Cube board.
ReplayConfig DefaultConfig();

// DefaultConfig() overridden by the TOML file at `path`. InputError, naming FILE:LINE:COL, on a
// syntax error, an unknown key ("unknown key 'x' in [processors]"), a wrong type, a bad unit or
// value, or a config that fails ValidateConfig. A [[level]] array replaces the default levels.
ReplayConfig LoadConfig(const std::string& path);
// The same from text; `source` names it in messages (a path or "<string>").
ReplayConfig LoadConfigFromString(std::string_view toml, const std::string& source);

// Checks the invariants (at least one level, unique valid names, capacities > 0,
// 1..kMaxProcessors processors, time per sample > 0, a scheduler). InputError prefixed with
// `where`.
void ValidateConfig(const ReplayConfig& config, const std::string& where);

// One override in the --set/--vary style: `key` is dotted ("processors.count",
// "level.board.bandwidth", "scheduler"), `value` is text as it would appear inside a TOML
// string ("1.6GB/s", "4", "true", "node"). The result is validated. InputError on an unknown
// key (the message lists the valid keys) or a bad value, prefixed with `what` (default
// "override 'KEY'"; a command's own flag names itself, "--scheduler").
void ApplyOverride(ReplayConfig& config, const std::string& key, const std::string& value,
                   const std::string& what = "");
// The keys ApplyOverride accepts for `config` (level keys use its level names).
std::vector<std::string> OverrideKeys(const ReplayConfig& config);

// The full configuration as TOML, commented with each key's meaning and, for the defaults,
// where they come from. LoadConfigFromString(ToToml(c), ...) == c for every valid c.
std::string ToToml(const ReplayConfig& config);

// One line per key for --help: "  processors.time_per_sample = 10ns  (one sample per cycle of a
// 100 MHz pipeline, ...)".
std::string DefaultsHelp();

}  // namespace raycell
