#include "runner/sweep.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>

#include "base/check.h"
#include "base/file.h"
#include "base/format.h"
#include "base/hash.h"
#include "base/parse.h"
#include "base/table.h"
#include "runner/driver.h"
#include "runner/result_table.h"
#include "runner/sweep_file.h"

namespace raycell {
namespace {

using sweep_file::kCheckpointStart;
using sweep_file::Lines;
using sweep_file::ParsedRow;
using sweep_file::ParseRow;
using sweep_file::ParseSize;
using sweep_file::RowContext;
using sweep_file::RowIndex;

constexpr std::size_t kMaxCombinations = 10'000'000;

// ---- Resuming rows -----------------------------------------------------------------------

// Checks that `rows` are the first rows of `indices`.
void CheckPrefix(const std::string& path, const std::vector<std::string>& rows,
                 const std::vector<std::size_t>& indices) {
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const std::size_t index = RowIndex(rows[k]);
    if (k < indices.size() && index == indices[k]) continue;
    throw InputError(RowContext(path, k) + ": expected the row of combination " +
                     (k < indices.size() ? std::to_string(indices[k]) : "(none: too many rows)") +
                     " of this sweep; the file does not hold this sweep's first rows. Delete it "
                     "to start again");
  }
}

// Opens OUT.partial for appending: created with `prelude` when absent (or cut short inside
// it), else checked against `prelude` and `indices`, with a row cut short dropped. Returns
// the number of rows kept.
std::size_t ResumePartial(const std::string& path, const std::string& prelude,
                          const std::vector<std::size_t>& indices) {
  std::string text;
  if (!ReadFile(path, &text) ||
      (text.size() < prelude.size() && prelude.compare(0, text.size(), text) == 0)) {
    WriteFileAtomically(path, prelude);
    return 0;
  }
  if (text.compare(0, prelude.size(), prelude) != 0) {
    throw InputError(path +
                     ": left by a different sweep (its comment line or header is not this "
                     "sweep's); rerun the command that wrote it to resume, or delete it");
  }
  const std::size_t keep = text.rfind('\n') + 1;  // drops a row cut short
  const std::vector<std::string> rows = Lines(text.substr(prelude.size(), keep - prelude.size()));
  CheckPrefix(path, rows, indices);
  if (keep < text.size()) std::filesystem::resize_file(path, keep);
  return rows.size();
}

// ---- Checkpoints -------------------------------------------------------------------------
// OUT.checkpoint: "# raycell sweep checkpoint block=FIRST+COUNT frames_done=K/N", the
// sweep's comment line and header, then one row per combination of the block with its
// totals over the first K of the N frames.

std::string CheckpointLine(std::size_t first, std::size_t count, std::size_t done,
                           std::size_t frames) {
  return kCheckpointStart + std::string("block=") + std::to_string(first) + "+" +
         std::to_string(count) + " frames_done=" + std::to_string(done) + "/" +
         std::to_string(frames) + "\n";
}

// The block being run: its combinations, configurations and totals so far.
struct Block {
  std::vector<std::size_t> indices;
  std::vector<ReplayConfig> configs;
  std::vector<ReplayResult> totals;
  std::size_t frames_done = 0;
};

void WriteCheckpoint(const std::string& path, const std::string& prelude, const SweepSpec& spec,
                     const Block& b) {
  std::string text = CheckpointLine(b.indices.front(), b.indices.size(), b.frames_done,
                                    spec.frame_indices.size()) +
                     prelude;
  for (std::size_t k = 0; k < b.indices.size(); ++k) {
    ReplayResult t = b.totals[k];
    FinishTotal(b.configs[k].processors.count, &t);
    text += SweepRow(b.indices[k], spec.varies, CombinationValues(spec.varies, b.indices[k]), t);
  }
  WriteFileAtomically(path, text);
}

// Loads the totals of OUT.checkpoint into `b` when it holds this block; returns the frames
// it had done (0 when there is no checkpoint or it is another block's).
std::size_t ReadCheckpoint(const std::string& path, const std::string& prelude,
                           const SweepSpec& spec, Block* b) {
  std::string text;
  if (!ReadFile(path, &text)) return 0;
  const std::vector<std::string> lines = Lines(text);
  if (lines.size() < 3 || text.compare(lines[0].size() + 1, prelude.size(), prelude) != 0) {
    throw InputError(path +
                     ": left by a different sweep (its comment line or header is not "
                     "this sweep's); rerun the command that wrote it to resume, or "
                     "delete it");
  }
  const std::size_t frames = spec.frame_indices.size();
  std::size_t done = 0;
  for (; done <= frames; ++done) {
    if (lines[0] + "\n" == CheckpointLine(b->indices.front(), b->indices.size(), done, frames)) {
      break;
    }
  }
  if (done > frames) return 0;  // another block's: stale
  if (lines.size() != 3 + b->indices.size()) {
    throw InputError(path + ": expected " + std::to_string(b->indices.size()) +
                     " rows after the header; the checkpoint is damaged, delete it");
  }
  for (std::size_t k = 0; k < b->indices.size(); ++k) {
    const std::string where = path + ": line " + std::to_string(k + 4);
    ParsedRow row = ParseRow(lines[3 + k], where);
    if (row.index != b->indices[k]) {
      throw InputError(where + ": expected the row of combination " +
                       std::to_string(b->indices[k]) + "; the checkpoint is damaged, delete it");
    }
    b->totals[k] = row.totals;
  }
  return done;
}

// ---- Running -----------------------------------------------------------------------------

class Run {
 public:
  Run(const TraceReader& reader, const SweepSpec& spec, const std::string& out,
      const SweepOptions& options)
      : reader_(reader),
        spec_(spec),
        options_(options),
        partial_(out + ".partial"),
        checkpoint_(out + ".checkpoint"),
        prelude_(SweepComment(spec) + SweepHeader(spec.varies)) {}

  SweepOutcome Go(const std::string& out) {
    const std::vector<std::size_t> indices =
        ShardIndices(CombinationCount(spec_.varies), spec_.shard);
    outcome_.resumed = ResumePartial(partial_, prelude_, indices);
    const std::vector<std::size_t> todo(indices.begin() + outcome_.resumed, indices.end());
    total_rows_ = indices.size();
    rows_done_ = outcome_.resumed;
    file_.open(partial_, std::ios::binary | std::ios::app);
    if (!file_) throw InputError(partial_ + ": cannot open for appending");
    const std::size_t size = std::max<std::size_t>(options_.block, 1);
    for (std::size_t first = 0; first < todo.size() && !stopped_; first += size) {
      Block b;
      b.indices.assign(todo.begin() + first, todo.begin() + std::min(todo.size(), first + size));
      RunBlock(b);
    }
    file_.close();
    outcome_.complete = !stopped_;
    if (outcome_.complete) {
      RenameFile(partial_, out);
      std::filesystem::remove(checkpoint_);
    }
    return outcome_;
  }

 private:
  void RunBlock(Block& b) {
    for (std::size_t index : b.indices) {
      b.configs.push_back(CombinationConfig(spec_.base, spec_.varies, index));
    }
    b.totals.assign(b.indices.size(), ReplayResult{});
    b.frames_done = ReadCheckpoint(checkpoint_, prelude_, spec_, &b);
    outcome_.frames_resumed += b.frames_done;
    const std::vector<std::size_t> frames(spec_.frame_indices.begin() + b.frames_done,
                                          spec_.frame_indices.end());
    ReplayFramesOptions o;
    o.jobs = options_.jobs;
    o.checked = true;  // RunSweep checked every combination
    o.share_plans = options_.share_plans;
    o.caller_reads_trees = false;
    last_checkpoint_ = std::chrono::steady_clock::now();
    const ReplayFramesStats stats = ReplayFrames(
        reader_, frames, b.configs, o,
        [&](const LoadedFrame&, const std::vector<ReplayResult>& results) {
          for (std::size_t k = 0; k < results.size(); ++k) Accumulate(results[k], &b.totals[k]);
          ++b.frames_done;
          Progress(b);
          stopped_ = options_.stop_after_frame && options_.stop_after_frame(b.frames_done);
          if (stopped_ || CheckpointDue()) {
            WriteCheckpoint(checkpoint_, prelude_, spec_, b);
            last_checkpoint_ = std::chrono::steady_clock::now();
          }
          return !stopped_;
        });
    outcome_.distinct += stats.distinct;
    outcome_.plans += stats.plans;
    if (stopped_) return;
    for (std::size_t k = 0; k < b.indices.size() && !stopped_; ++k) {
      FinishTotal(b.configs[k].processors.count, &b.totals[k]);
      WriteRow(SweepRow(b.indices[k], spec_.varies, CombinationValues(spec_.varies, b.indices[k]),
                        b.totals[k]));
    }
  }

  bool CheckpointDue() const {
    const double since =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - last_checkpoint_).count();
    return since >= options_.checkpoint_seconds;
  }

  void WriteRow(const std::string& row) {
    if (!(file_ << row) || !file_.flush()) throw InputError(partial_ + ": cannot write");
    ++outcome_.ran;
    ++rows_done_;
    if (options_.progress) options_.progress(double(rows_done_) / double(total_rows_));
    stopped_ = options_.stop && options_.stop(outcome_.ran);
  }

  void Progress(const Block& b) const {
    if (!options_.progress || spec_.frame_indices.empty()) return;
    const double block =
        double(b.indices.size()) * double(b.frames_done) / double(spec_.frame_indices.size());
    options_.progress((double(rows_done_) + block) / double(total_rows_));
  }

  const TraceReader& reader_;
  const SweepSpec& spec_;
  const SweepOptions& options_;
  std::string partial_, checkpoint_, prelude_;
  std::ofstream file_;
  SweepOutcome outcome_;
  std::size_t total_rows_ = 0, rows_done_ = 0;
  bool stopped_ = false;
  std::chrono::steady_clock::time_point last_checkpoint_;
};

}  // namespace

// ---- Vary and Shard ----------------------------------------------------------------------

Vary Vary::Parse(const std::string& text, const std::string& option) {
  const std::string what = option + " '" + text + "'";
  const auto eq = text.find('=');
  if (eq == std::string::npos) throw InputError(what + ": expected KEY=V1,V2,...");
  Vary v{std::string(Trim(std::string_view(text).substr(0, eq))), {}};
  if (v.key.empty()) throw InputError(what + ": the key before '=' is empty");
  if (text.find_first_of("\r\n") != std::string::npos) {
    throw InputError(what + ": holds a line break");
  }
  for (const std::string& value : Split(text.substr(eq + 1), ',')) {
    v.values.emplace_back(Trim(value));
    if (v.values.back().empty()) {
      throw InputError(what + ": empty value for " + v.key + " (expected KEY=V1,V2,...)");
    }
  }
  return v;
}

std::string Vary::ToString() const {
  std::string s = key + "=";
  for (std::size_t i = 0; i < values.size(); ++i) s += (i ? "," : "") + values[i];
  return s;
}

Shard Shard::Parse(const std::string& text, const std::string& option) {
  const auto slash = text.find('/');
  Shard s;
  if (slash == std::string::npos || !ParseSize(text.substr(0, slash), &s.index) ||
      !ParseSize(text.substr(slash + 1), &s.count) || s.count == 0 || s.index >= s.count) {
    throw InputError(option + " '" + text + "': expected I/N with 0 <= I < N, e.g. 0/3");
  }
  return s;
}

std::string Shard::ToString() const {
  return count == 1 ? "all" : std::to_string(index) + "/" + std::to_string(count);
}

// ---- Combinations ------------------------------------------------------------------------

std::size_t CombinationCount(const std::vector<Vary>& varies) {
  std::size_t n = 1;
  for (const Vary& v : varies) {
    if (v.values.empty()) throw InputError("--vary " + v.key + ": no values");
    if (n > kMaxCombinations / v.values.size()) {
      throw InputError("--vary: more than " + std::to_string(kMaxCombinations) + " combinations");
    }
    n *= v.values.size();
  }
  return n;
}

std::vector<std::string> CombinationValues(const std::vector<Vary>& varies, std::size_t index) {
  std::vector<std::string> values(varies.size());
  for (std::size_t k = varies.size(); k-- > 0;) {
    const std::size_t n = varies[k].values.size();
    values[k] = varies[k].values[index % n];
    index /= n;
  }
  RAYCELL_CHECK_EQ(index, 0u);
  return values;
}

ReplayConfig CombinationConfig(const ReplayConfig& base, const std::vector<Vary>& varies,
                               std::size_t index) {
  ReplayConfig config = base;
  const std::vector<std::string> values = CombinationValues(varies, index);
  for (std::size_t k = 0; k < varies.size(); ++k) ApplyOverride(config, varies[k].key, values[k]);
  return config;
}

void ValidateVaries(const ReplayConfig& base, const std::vector<Vary>& varies) {
  std::set<std::string> keys;
  for (const Vary& v : varies) {
    if (!keys.insert(v.key).second) throw InputError("--vary " + v.key + ": key varied twice");
    for (const std::string& value : v.values) {
      try {
        ReplayConfig c = base;
        ApplyOverride(c, v.key, value);
      } catch (const InputError& e) {
        throw InputError("--vary " + v.key + "=" + value + ": " + e.what());
      }
    }
  }
}

std::vector<std::size_t> ShardIndices(std::size_t combinations, const Shard& shard) {
  std::vector<std::size_t> out;
  for (std::size_t i = shard.index; i < combinations; i += shard.count) out.push_back(i);
  return out;
}

// ---- Running -----------------------------------------------------------------

SweepOutcome RunSweep(const TraceReader& reader, const SweepSpec& spec, const std::string& out,
                      const SweepOptions& options) {
  ValidateVaries(spec.base, spec.varies);
  const std::uint64_t cells = reader.header().cell_count();
  std::set<std::vector<std::string>> level_cells;  // the levels' cells, each set checked once
  for (std::size_t i = 0, n = CombinationCount(spec.varies); i < n; ++i) {
    try {
      const ReplayConfig c = CombinationConfig(spec.base, spec.varies, i);
      CheckReplay(c, cells);
      std::vector<std::string> levels;
      for (const LevelConfig& l : c.levels) levels.push_back(l.cells);
      if (level_cells.insert(levels).second) LevelUnitsOf(c, reader);
    } catch (const InputError& e) {
      throw InputError((spec.varies.empty() ? "--config " + spec.config
                                            : "--vary: combination " + std::to_string(i)) +
                       ": " + e.what());
    }
  }
  return Run(reader, spec, out, options).Go(out);
}

}  // namespace raycell
