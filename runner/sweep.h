// Parameter sweeps: one replay of a trace per combination of varied configuration
// keys, one CSV row per combination.
//
// Combinations are numbered 0..K-1 row-major over the Vary list in the order given (the last
// key varies fastest). A shard I/N (0-based, 0 <= I < N) runs the indices with
// index % N == I.
//
// The output file starts with a comment line that names the sweep exactly, then the header:
//
//   # raycell sweep schema="raycell-sweep/1" trace="a.rct" config="gicube.toml" config_hash=...
//     vary="scheduler=..."
//     frames="all" combinations=6 shard="all"                       (one line)
//   index,scheduler,processors.count,fetches,bound,time_ps,time_bound_ps,work_ps,stall_ps,
//     idle_ps,utilisation,peak_queued_rays,peak_queued_bytes,rays,segments,samples
//   0,maxwork,1,...
//
// Values are totals over the selected frames, as `raycell replay` prints them
// (runner/result_table.h); `bound` is empty where it does not hold. Rows are written in index
// order, so the file is byte-identical for any --jobs.
//
// Decode once, replay many: the shard's combinations are taken in blocks of up to
// kSweepBlock (4096) in index order; for each block the frames are the outer loop
// (ReplayFrames): each frame is decoded and its trees and work graphs built once, every
// combination of the block is replayed on it (on --jobs threads; combinations with equal
// canonical configurations once, CanonicalConfig) and added to that combination's totals.
// What the schedulers compute from earlier frames' trees (plans, unions, ...) is made once per
// frame for every combination (SweepOptions::share_plans; scheduling/plan_cache.h).
// When the block's last frame is done its rows are appended. Memory: one frame (its rays
// until its work graphs are built, the work graphs, two Cell Trees) plus, per combination,
// its totals and scheduler: a few hundred bytes.
//
// Resuming works at two grains:
//  - rows: rows are appended to OUT.partial, one flushed write per row, in order; OUT.partial
//    is renamed to OUT when every row is written. A rerun of the same sweep keeps the rows
//    of OUT.partial and runs only the rest.
//  - frames: inside a block, the block's partial totals are written to OUT.checkpoint
//    (atomically: temporary file, rename) after a frame when checkpoint_seconds have passed
//    since the last one, and always when the sweep is stopped: the sweep's comment line, the
//    block (its first combination, size, frames done) and one row per combination with its
//    totals over the frames done, as a sweep row. A rerun whose first block is that block
//    starts from those totals at the next frame; a checkpoint of another block (stale) is
//    ignored and replaced. Totals add exactly (see MergeSweepShards), so a resumed sweep
//    writes the same bytes as an uninterrupted one.
// A .partial or .checkpoint whose comment line or header differs (another trace, config,
// vary list, frames or shard) is an InputError, never reused.
//
// Frames can be sharded as well as combinations: runs with --frames A..B over disjoint
// ranges are frame shards of one sweep, and MergeSweepShards adds their totals.
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
// Applies every value alone to `base`, so that a bad --vary fails before the trace is opened:
// InputError naming the option, key and value. Also rejects a key varied twice. What the
// combinations need of the trace (CheckReplay, the levels' cells) RunSweep checks.
void ValidateVaries(const ReplayConfig& base, const std::vector<Vary>& varies);

struct SweepSpec {
  std::string trace;   // path as given (named in the comment line)
  std::string cells;   // --cells SPEC of a regroupable capture as given; empty: its own grid
  std::string config;  // path as given; empty: the defaults
  ReplayConfig base;   // the loaded configuration
  std::vector<Vary> varies;
  std::string frames;                      // --frames as given; empty: all
  std::vector<std::size_t> frame_indices;  // into reader.frames(), increasing
  Shard shard;
};

// Combinations replayed together, frame by frame (see the top of this file).
inline constexpr std::size_t kSweepBlock = 4096;

struct SweepOptions {
  unsigned jobs = 1;  // worker threads, >= 1
  // Told the fraction of this shard's work done, after each frame and row.
  std::function<void(double)> progress;
  // Asked after each row written; returning true stops the sweep as an interruption would
  // (rows written so far stay in OUT.partial). For tests.
  std::function<bool(std::size_t rows_written)> stop;
  // Asked after each frame of a block (frames done in the block, this run and resumed);
  // returning true stops the sweep there, with a checkpoint. For tests.
  std::function<bool(std::size_t frames_done)> stop_after_frame;
  // The least wall time between two checkpoints; 0: after every frame.
  double checkpoint_seconds = 1.0;
  // Combinations per block; tests use small blocks to see several.
  std::size_t block = kSweepBlock;
  // ReplayFramesOptions::share_plans: each frame's plans made once for every combination
  // (false: per combination, for the test that they give the same rows).
  bool share_plans = true;
};

struct SweepOutcome {
  std::size_t resumed = 0;         // rows kept from an existing OUT.partial
  std::size_t ran = 0;             // rows computed by this run
  std::size_t frames_resumed = 0;  // frames taken from an OUT.checkpoint
  // Canonical configurations replayed (CanonicalConfig), summed over the blocks run: fewer
  // than the combinations when some can only differ in what no frame's result depends on.
  std::size_t distinct = 0;
  // Values the schedulers computed from earlier frames' trees (plans, unions, ...: PlanCache),
  // summed over the frames and blocks run: once per frame with plan sharing, per combination
  // without.
  std::size_t plans = 0;
  bool complete = false;  // OUT written (false: stopped, OUT.partial left)
};

// The comment line (with '\n') and the CSV header line (with '\n') of `spec`.
std::string SweepComment(const SweepSpec& spec);
std::string SweepHeader(const std::vector<Vary>& varies);
// One row (with '\n'): index, the combination's values (one per Vary), the totals' columns
// (runner/result_table.h, kSweepColumns).
std::string SweepRow(std::size_t index, const std::vector<Vary>& varies,
                     const std::vector<std::string>& values, const ReplayResult& total);
// The combination indices `shard` owns, increasing.
std::vector<std::size_t> ShardIndices(std::size_t combinations, const Shard& shard);

// Runs the sweep into `out` (via out + ".partial" and out + ".checkpoint", resumed when
// present). Validates the varies, then checks every combination against the trace once
// (CheckReplay, LevelUnitsOf), before any frame is read; the replays do not check again.
// InputError on bad input or a .partial or .checkpoint from another sweep.
SweepOutcome RunSweep(const TraceReader& reader, const SweepSpec& spec, const std::string& out,
                      const SweepOptions& options = {});

// Joins the files of one sweep's shards into `out` (tmp + rename): shards of combinations
// (--shard I/N), of frames (--frames over disjoint ranges), or both. Every combination must
// be in the files whose frames ranges tile one range A..B exactly (no frame twice, none
// missing between A and B). Rows of one combination over different frames add up as a
// frame's results add into a total: counts, bytes and times summed, peaks as maxima, the
// bound summed where it holds, utilisation recomputed from the summed times (work /
// (time x processors), processors = (work + stall + idle) / time). The result is
// byte-identical to the unsharded run: with one frames range, to the run with that range;
// with several, to the run with --frames A..B (the comment says frames="A..B").
// InputError when the files come from different sweeps, overlap in combinations or frames,
// miss some, or are incomplete; `out` is then not written.
void MergeSweepShards(const std::string& out, const std::vector<std::string>& shards);

}  // namespace raycell
