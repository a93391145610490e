// Parameter sweeps: one replay of a trace per combination of varied configuration
// keys, one CSV row per combination.
//
// Combinations are numbered 0..K-1 row-major over the Vary list in the order given (the last
// key varies fastest). A shard I/N (0-based, 0 <= I < N) runs the indices with
// index % N == I; MergeSweepShards joins the N shard files into the bytes an unsharded run
// writes.
//
// The output file starts with a comment line that names the sweep exactly, then the header:
//
//   # raycell sweep schema="raycell-sweep/1" trace="a.rct" config="gicube.toml" config_hash=...
//     vary="scheduler=..."
//     frames="all" combinations=6 shard="all"                       (one line)
//   index,scheduler,processors.count,fetches,bound,time_ps,work_ps,stall_ps,idle_ps,
//     utilisation,peak_queued_rays,peak_queued_bytes,rays,segments,samples
//   0,maxwork,1,...
//
// Values are totals over the selected frames, as `raycell replay` prints them; `bound` is
// empty where it does not hold. Rows are written in index order whatever the number of
// worker threads, so the file is byte-identical for any --jobs.
//
// Resuming: rows are appended to OUT.partial, one flushed write per row, as soon as all
// rows before them are done; OUT.partial is renamed to OUT when every row is written. An
// interrupted sweep (Ctrl-C, a crash) leaves OUT.partial, and running the same sweep again
// keeps its rows and runs only the rest. A .partial whose comment line or header differs
// (another trace, config, vary list, frames or shard) is an InputError, never reused.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "replay/config.h"
#include "replay/replayer.h"
#include "traces/trace_reader.h"

namespace raycell {

// One --vary option: a configuration key (as ApplyOverride takes it) and its values.
struct Vary {
  std::string key;
  std::vector<std::string> values;

  // "KEY=V1,V2,..." (values may hold spaces; each is trimmed). InputError naming `option`
  // ("--vary") when '=' is missing, the key is empty or a value is empty.
  static Vary Parse(const std::string& text, const std::string& option = "--vary");
  // "KEY=V1,V2,...", the canonical form Parse reads back.
  std::string ToString() const;
};

// The shard of a sweep a run computes: indices with index % count == index.
struct Shard {
  std::size_t index = 0, count = 1;

  // "I/N" with 0 <= I < N; InputError naming `option` otherwise.
  static Shard Parse(const std::string& text, const std::string& option = "--shard");
  // "I/N", or "all" for the whole sweep (0/1).
  std::string ToString() const;
  bool Owns(std::size_t combination) const { return combination % count == index; }
};

// The number of combinations (the product of the value counts; 1 for no Vary).
// InputError when it exceeds 10^7.
std::size_t CombinationCount(const std::vector<Vary>& varies);
// The values of combination `index`, one per Vary in order.
std::vector<std::string> CombinationValues(const std::vector<Vary>& varies, std::size_t index);
// `base` with combination `index` applied (InputError from ApplyOverride).
ReplayConfig CombinationConfig(const ReplayConfig& base, const std::vector<Vary>& varies,
                               std::size_t index);
// Applies every value alone, then every combination, to `base`, so that a bad --vary fails
// before any work: InputError naming the option, key and value. Also rejects a key varied
// twice.
void ValidateVaries(const ReplayConfig& base, const std::vector<Vary>& varies);

struct SweepSpec {
  std::string trace;   // path as given (named in the comment line)
  std::string config;  // path as given; empty: the defaults
  ReplayConfig base;   // the loaded configuration
  std::vector<Vary> varies;
  std::string frames;                      // --frames as given; empty: all
  std::vector<std::size_t> frame_indices;  // into reader.frames(), increasing
  Shard shard;
};

struct SweepOptions {
  unsigned jobs = 1;  // worker threads, >= 1
  // Told the fraction of this shard's rows done (called under a lock, from any thread).
  std::function<void(double)> progress;
  // Asked after each row written; returning true stops the sweep as an interruption would
  // (rows written so far stay in OUT.partial). For tests.
  std::function<bool(std::size_t rows_written)> stop;
};

struct SweepOutcome {
  std::size_t resumed = 0;  // rows kept from an existing OUT.partial
  std::size_t ran = 0;      // rows computed by this run
  bool complete = false;    // OUT written (false: stopped, OUT.partial left)
};

// The comment line (with '\n') and the CSV header line (with '\n') of `spec`.
std::string SweepComment(const SweepSpec& spec);
std::string SweepHeader(const std::vector<Vary>& varies);
// One row (with '\n'): index, the combination's values (one per Vary), the totals' columns
// (replay/result_table.h, kSweepColumns).
std::string SweepRow(std::size_t index, const std::vector<Vary>& varies,
                     const std::vector<std::string>& values, const ReplayResult& total);
// The combination indices `shard` owns, increasing.
std::vector<std::size_t> ShardIndices(std::size_t combinations, const Shard& shard);

// Runs the sweep into `out` (via out + ".partial", resumed when present). Validates the
// varies first. InputError on bad input or a .partial from another sweep.
SweepOutcome RunSweep(const TraceReader& reader, const SweepSpec& spec, const std::string& out,
                      const SweepOptions& options = {});

// Joins the files of shards I/N (each exactly once, any order) into `out` (tmp + rename),
// byte-identical to the unsharded run. InputError when the shards come from different
// sweeps, overlap, miss indices or are incomplete.
void MergeSweepShards(const std::string& out, const std::vector<std::string>& shards);

}  // namespace raycell
