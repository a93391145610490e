// The replay configuration (DESIGN.md §2): typed structs with documented defaults, read from
// TOML (CONVENTIONS.md "Configuration read into typed structs with defaults"). Every key in a
// file must be read: an unknown key is an InputError naming FILE:LINE:COL, like pbrt's
// ReportUnused. Units are parsed once at load (replay/units.h). Each key is described once,
// in config.cpp's key tables (name, meaning, TOML type, parser, printer, the source of its
// default); the TOML reader and writer, --set/--vary overrides and --help derive from them.
//
// File layout (ToToml(DefaultConfig()) prints the full, commented form):
//
//   scheduler = "celltree"        # a name of SchedulerRegistry() (scheduling/scheduler.h)
//   seed = 1
//   granularity = "auto"          # ray | node | auto
//   [processors]
//   count = 1
//   time_per_sample = "10ns"
//   queue_record_bytes = 32       # or a size string, "32B"
//   prefetch = false
//   [[level]]                     # nearest first; present at all → replaces the default levels
//   name = "cache"
//   capacity = "1 cell"           # "N cell(s)" or a size, "256MiB"
//   bandwidth = "1.6GB/s"         # to the level below; "unlimited" allowed
//   latency = "40ns"              # to the level below
//   replacement = "lru"           # lru | fifo | min
//
// Default values model the GI-Cube board on the slides: a PCI board whose block processors
// are backed by Direct RDRAM, with host memory reached over PCI.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "engine/time.h"
#include "replay/units.h"

namespace raycell {

struct LevelConfig {
  enum class CapacityUnit { kBytes, kCells };
  enum class Replacement { kLru, kFifo, kMin };

  // Unique, [A-Za-z0-9_-]+ (it appears in override keys "level.NAME.KEY").
  std::string name;
  CapacityUnit capacity_unit = CapacityUnit::kCells;
  // In bytes or cells per capacity_unit; > 0.
  std::uint64_t capacity = 1;
  // To the level below (the level below the last is host memory, itself unlimited).
  Bandwidth bandwidth_below;
  SimTime latency_below;
  // Default LRU: with the default one-cell cache every policy behaves alike; MIN is Belady's
  // bound and needs the future schedule.
  Replacement replacement = Replacement::kLru;
};

struct ProcessorConfig {
  // Default 1 block processor (the paper's case). 1..1024.
  std::uint32_t count = 1;
  // Default 10ns: one sample per cycle of a 100 MHz pipeline (the Cube-5/GI-Cube design
  // point). > 0.
  SimTime time_per_sample = SimTime::Nanoseconds(10);
  // Default 32 bytes per queued ray: position, direction, colour/opacity, cell-tree node.
  std::uint64_t queue_record_bytes = 32;
  // Default false: no double buffering (fetch of the next scheduled cell while working).
  bool prefetch = false;
};

struct ReplayConfig {
  // kAuto: per node where that is exact (one processor), per ray segment otherwise.
  enum class Granularity { kRay, kNode, kAuto };

  // Nearest (on-chip cache) to farthest; the level below the last is host memory, unlimited.
  // Defaults (DefaultConfig()):
  //  "cache": the block processor's on-chip cell cache, capacity 1 cell ("cell size set to
  //           memory size", the paper's case); bandwidth to board memory 1.6GB/s (one Direct
  //           RDRAM PC800 channel: 2 bytes x 800 MT/s); latency 40ns (RDRAM row access).
  //  "board": board memory, capacity 256MiB; bandwidth to host 133MB/s (32-bit 33 MHz PCI);
  //           latency 1us (a PCI transaction).
  std::vector<LevelConfig> levels;
  ProcessorConfig processors;
  // Default "celltree" (the paper's Cell Tree scheduler); a name of SchedulerRegistry()
  // (scheduling/scheduler.h).
  std::string scheduler = "celltree";
  // Default 1: seeds the random scheduler and the planners' schedule searches
  // (scheduling/best_scheduler.h); any fixed value keeps replays deterministic.
  std::uint64_t seed = 1;
  // Default kAuto: per Cell Tree node (fast) where it gives exactly what per ray segment
  // gives, i.e. with one processor; per ray segment otherwise.
  Granularity granularity = Granularity::kAuto;
};

bool operator==(const LevelConfig& a, const LevelConfig& b);
bool operator!=(const LevelConfig& a, const LevelConfig& b);
bool operator==(const ProcessorConfig& a, const ProcessorConfig& b);
bool operator!=(const ProcessorConfig& a, const ProcessorConfig& b);
bool operator==(const ReplayConfig& a, const ReplayConfig& b);
bool operator!=(const ReplayConfig& a, const ReplayConfig& b);

// "lru" | "fifo" | "min"; "ray" | "node"; "bytes" | "cells".
std::string_view ToString(LevelConfig::Replacement r);
std::string_view ToString(ReplayConfig::Granularity g);
// The granularity a replay of `config` runs at: kAuto resolved.
ReplayConfig::Granularity EffectiveGranularity(const ReplayConfig& config);
std::string_view ToString(LevelConfig::CapacityUnit u);

// A level's capacity as written in files and overrides: "1 cell", "4 cells" or "256MiB".
std::string FormatCapacity(const LevelConfig& level);

// The GI-Cube defaults described above.
ReplayConfig DefaultConfig();

// DefaultConfig() overridden by the TOML file at `path`. InputError, naming FILE:LINE:COL, on a
// syntax error, an unknown key ("unknown key 'x' in [processors]"), a wrong type, a bad unit or
// value, or a config that fails ValidateConfig. A [[level]] array replaces the default levels.
ReplayConfig LoadConfig(const std::string& path);
// The same from text; `source` names it in messages (a path or "<string>").
ReplayConfig LoadConfigFromString(std::string_view toml, const std::string& source);

// Checks the invariants (at least one level, unique valid names, capacities > 0, 1..1024
// processors, time per sample > 0, a known scheduler). InputError prefixed with `where`.
void ValidateConfig(const ReplayConfig& config, const std::string& where);

// One override in the --set/--vary style: `key` is dotted ("processors.count",
// "level.board.bandwidth", "scheduler"), `value` is text as it would appear inside a TOML
// string ("1.6GB/s", "4", "true", "node"). The result is validated. InputError on an unknown
// key (the message lists the valid keys) or a bad value.
void ApplyOverride(ReplayConfig& config, const std::string& key, const std::string& value);
// The keys ApplyOverride accepts for `config` (level keys use its level names).
std::vector<std::string> OverrideKeys(const ReplayConfig& config);

// The full configuration as TOML, commented with each key's meaning and, for the defaults,
// where they come from. LoadConfigFromString(ToToml(c), ...) == c for every valid c.
std::string ToToml(const ReplayConfig& config);

// One line per key for --help: "  processors.time_per_sample = 10ns  (one sample per cycle of a
// 100 MHz pipeline, ...)".
std::string DefaultsHelp();

}  // namespace raycell
