#include "replay/sweep.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <optional>
#include <set>

#include "base/check.h"
#include "base/file.h"
#include "base/format.h"
#include "base/hash.h"
#include "base/parse.h"
#include "engine/stats.h"
#include "replay/driver.h"
#include "replay/result_table.h"

namespace raycell {
namespace {

constexpr std::size_t kMaxCombinations = 10'000'000;
constexpr char kCommentStart[] = "# raycell sweep ";
constexpr char kFramesPart[] = " frames=";
constexpr char kCombinationsPart[] = " combinations=";
constexpr char kShardPart[] = " shard=";
constexpr char kCheckpointStart[] = "# raycell sweep checkpoint ";
// The totals' columns at the end of every row (replay/result_table.h, kSweepColumns).
constexpr std::size_t kResultColumns = 13;

// Whole decimal number, or false.
bool ParseSize(const std::string& s, std::size_t* out) {
  std::uint64_t v = 0;
  if (!TryParseUint(s, &v) || s.size() > 18) return false;
  *out = std::size_t(v);
  return true;
}

std::string ConfigHash(const ReplayConfig& config) {
  const std::string toml = ToToml(config);
  Hash64 h;
  h.AddBytes(toml.data(), toml.size());
  return FormatHex64(h.Finish());
}

bool ReadFile(const std::string& path, std::string* text) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  text->assign(std::istreambuf_iterator<char>(in), {});
  return true;
}

void WriteFile(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!(f << text) || !f.flush()) throw InputError(path + ": cannot write");
}

// The lines of `text` (which ends with '\n' or is empty), without their '\n'.
std::vector<std::string> Lines(const std::string& text) {
  if (text.empty()) return {};
  std::vector<std::string> lines = Split(text, '\n');
  lines.pop_back();  // after the last '\n'
  return lines;
}

// The combination index a row starts with, or SIZE_MAX.
std::size_t RowIndex(const std::string& row) {
  std::size_t index = 0;
  return ParseSize(row.substr(0, row.find(',')), &index) ? index : SIZE_MAX;
}

std::string RowContext(const std::string& path, std::size_t row) {
  return path + ": line " + std::to_string(row + 3);
}

StatsTable SweepRowTable(std::size_t index, const std::vector<Vary>& varies,
                         const std::vector<std::string>& values, const ReplayResult& total) {
  RAYCELL_CHECK_EQ(values.size(), varies.size());
  StatsTable t;
  t.AddCount("index", index);
  for (std::size_t k = 0; k < varies.size(); ++k) t.AddText(varies[k].key, values[k]);
  AddResult(total, kSweepColumns, &t);
  return t;
}

// ---- Rows as totals ----------------------------------------------------------------------
// A row splits into its head (index and values, as written) and the totals it prints. The
// totals' columns hold no comma or quote, so they are the last kResultColumns fields.

struct ParsedRow {
  std::size_t index = SIZE_MAX;
  std::string head;     // "index,values..." as written
  ReplayResult totals;  // the counted columns; utilisation as printed (not used to add)
};

std::uint64_t Field(const std::string& text, const std::string& where) {
  std::uint64_t v = 0;
  if (!TryParseUint(text, &v))
    throw InputError(where + ": expected a whole number, got '" + text + "'");
  return v;
}

ParsedRow ParseRow(const std::string& row, const std::string& where) {
  std::vector<std::string> fields;
  std::size_t end = row.size();
  for (std::size_t k = 0; k < kResultColumns; ++k) {
    const std::size_t comma = row.rfind(',', end - 1);
    if (end == 0 || comma == std::string::npos) {
      throw InputError(where + ": expected a sweep row (index, values, " +
                       std::to_string(kResultColumns) + " totals)");
    }
    fields.insert(fields.begin(), row.substr(comma + 1, end - comma - 1));
    end = comma;
  }
  ParsedRow r;
  r.head = row.substr(0, end);
  r.index = RowIndex(r.head);
  if (r.index == SIZE_MAX) throw InputError(where + ": the row does not start with an index");
  ReplayResult& t = r.totals;
  t.fetches = Field(fields[0], where);
  if (!fields[1].empty()) t.bound = Field(fields[1], where);
  t.time = SimTime::Picoseconds(Field(fields[2], where));
  t.time_bound = SimTime::Picoseconds(Field(fields[3], where));
  t.work = SimTime::Picoseconds(Field(fields[4], where));
  t.stall = SimTime::Picoseconds(Field(fields[5], where));
  t.idle = SimTime::Picoseconds(Field(fields[6], where));
  // fields[7], utilisation, is recomputed from the times
  t.peak_queued_rays = Field(fields[8], where);
  t.peak_queued_bytes = Field(fields[9], where);
  t.rays = Field(fields[10], where);
  t.segments = Field(fields[11], where);
  t.samples = Field(fields[12], where);
  return r;
}

// Sets the utilisation of totals read back from rows. The processors are not in the row,
// but every frame's idle time is (processors x time - work - stall), so they are
// (work + stall + idle) / time.
void FinishReadTotals(ReplayResult* t, const std::string& where) {
  const std::uint64_t time = t->time.picoseconds();
  if (time == 0) {
    t->utilisation = 0;
    return;
  }
  const std::uint64_t busy =
      CheckedAdd(CheckedAdd(t->work.picoseconds(), t->stall.picoseconds()), t->idle.picoseconds());
  if (busy % time != 0 || busy / time == 0 || busy / time > kMaxProcessors) {
    throw InputError(where + ": work + stall + idle (" + std::to_string(busy) +
                     " ps) is not a whole number of processors times the time (" +
                     std::to_string(time) + " ps)");
  }
  FinishTotal(std::uint32_t(busy / time), t);
}

// The row of `head` with `totals`, without its '\n': the bytes SweepRow writes for the same
// totals.
std::string RowWithTotals(const std::string& head, const ReplayResult& totals) {
  std::string row = head + "," + ToCsvRow(ToStatsTable(totals, kSweepColumns));
  row.pop_back();
  return row;
}

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
    WriteFile(path, prelude);
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

// ---- Merging -----------------------------------------------------------------------------

// One file of a sharded sweep.
struct ShardFile {
  std::string path;
  std::string head;    // the comment line before its frames part
  std::string frames;  // the frames part's value: "all" or a range as given
  std::string header;
  Shard shard;
  std::size_t combinations = 0;
  int first = 0, last = 0;  // the frames range, when not "all"
  std::vector<std::string> rows;
};

// The JSON string value that starts `text` at `at` (a quote), without its quotes; the
// sweep's values (paths aside, which are before the parts read here) have no escapes.
std::string QuotedValue(const ShardFile& f, const std::string& comment, std::size_t at,
                        const char* part) {
  const std::size_t close = comment.find('"', at + 1);
  if (at >= comment.size() || comment[at] != '"' || close == std::string::npos) {
    throw InputError(f.path + ": line 1: bad" + std::string(part) + " in the sweep comment");
  }
  return comment.substr(at + 1, close - at - 1);
}

void ParseComment(const std::string& comment, ShardFile* f) {
  if (comment.rfind(kCommentStart, 0) != 0) {
    throw InputError(f->path + ": line 1: expected '" + kCommentStart + "...' (a sweep file)");
  }
  const std::size_t shard_at = comment.rfind(kShardPart);
  const std::size_t count_at = comment.rfind(kCombinationsPart, shard_at);
  const std::size_t frames_at = comment.rfind(kFramesPart, count_at);
  if (shard_at == std::string::npos || count_at == std::string::npos ||
      frames_at == std::string::npos) {
    throw InputError(f->path + ": line 1: the sweep comment lacks frames, combinations or shard");
  }
  const std::string shard =
      QuotedValue(*f, comment, shard_at + std::strlen(kShardPart), kShardPart);
  f->shard = shard == "all" ? Shard{} : Shard::Parse(shard, f->path + ": line 1: shard");
  const std::size_t count_begin = count_at + std::strlen(kCombinationsPart);
  if (!ParseSize(comment.substr(count_begin, shard_at - count_begin), &f->combinations)) {
    throw InputError(f->path + ": line 1: bad combinations count");
  }
  f->frames = QuotedValue(*f, comment, frames_at + std::strlen(kFramesPart), kFramesPart);
  f->head = comment.substr(0, frames_at);
  if (f->frames != "all") {
    const std::vector<int> range = ParseFrameRange(f->frames, f->path + ": line 1: frames");
    f->first = range.front(), f->last = range.back();
  }
}

// ",fetches,bound,time_ps,...,samples": the totals' columns this version writes at the end of
// every header.
std::string TotalsHeader() {
  std::string totals = "," + ToCsvHeader(ToStatsTable(ReplayResult{}, kSweepColumns));
  totals.pop_back();  // the '\n'
  return totals;
}

ShardFile ReadShard(const std::string& path) {
  ShardFile f;
  f.path = path;
  std::string text;
  if (!ReadFile(path, &text)) throw InputError(path + ": cannot open");
  if (text.empty() || text.back() != '\n') {
    throw InputError(path + ": incomplete (does not end with a newline)");
  }
  f.rows = Lines(text);
  if (f.rows.size() < 2) throw InputError(path + ": no comment line and header");
  ParseComment(f.rows[0], &f);
  f.header = f.rows[1];
  const std::string totals = TotalsHeader();
  if (f.header.size() < totals.size() ||
      f.header.compare(f.header.size() - totals.size(), totals.size(), totals) != 0) {
    throw InputError(path + ": line 2: the header does not end with the totals' columns (" +
                     totals.substr(1) +
                     "): written by another version of raycell? Rerun that shard to merge it");
  }
  f.rows.erase(f.rows.begin(), f.rows.begin() + 2);
  return f;
}

void CheckSameSweep(const ShardFile& a, const ShardFile& b) {
  if (a.head != b.head || a.combinations != b.combinations || a.header != b.header) {
    throw InputError(b.path + ": not a shard of the same sweep as " + a.path +
                     " (their comment lines or headers differ apart from the shard and frames)");
  }
}

// A row of one file: which file, and the frames it covers.
struct Piece {
  const ShardFile* file;
  std::size_t row;
};

// Rows per combination, from every file, checked against the files' shards.
std::vector<std::vector<Piece>> Gather(const std::vector<ShardFile>& files, std::size_t n) {
  std::vector<std::vector<Piece>> pieces(n);
  for (const ShardFile& f : files) {
    for (std::size_t k = 0; k < f.rows.size(); ++k) {
      const std::size_t index = RowIndex(f.rows[k]);
      if (index >= n || !f.shard.Owns(index)) {
        throw InputError(RowContext(f.path, k) + ": no combination of shard " + f.shard.ToString() +
                         " starts this row");
      }
      pieces[index].push_back({&f, k});
    }
  }
  return pieces;
}

// Checks that the pieces of combination `index` cover frames first..last once each.
void CheckTiling(std::size_t index, std::vector<Piece>& p, bool ranges, int first, int last) {
  const std::string what = "combination " + std::to_string(index);
  if (p.empty()) {
    throw InputError(what + " is in none of the shards (a shard missing or not finished?)");
  }
  if (!ranges) {  // one frames selection: every combination in exactly one file
    if (p.size() > 1) {
      throw InputError(what + " is in both " + p[0].file->path + " and " + p[1].file->path +
                       " (overlapping shards)");
    }
    return;
  }
  std::sort(p.begin(), p.end(),
            [](const Piece& a, const Piece& b) { return a.file->first < b.file->first; });
  long long next = first;
  for (const Piece& piece : p) {
    const ShardFile& f = *piece.file;
    if (f.first < next) {
      throw InputError(what + ": frames " +
                       FormatFrameRange(f.first, int(std::min<long long>(f.last, next - 1))) +
                       " are in " + f.path + " and another shard (overlapping frames)");
    }
    if (f.first > next) {
      throw InputError(what + ": frames " + FormatFrameRange(int(next), f.first - 1) +
                       " are in none of the shards (missing frames)");
    }
    next = (long long)f.last + 1;
  }
  if (next <= last) {
    throw InputError(what + ": frames " + FormatFrameRange(int(next), last) +
                     " are in none of the shards (missing frames)");
  }
}

// The merged row of one combination: the one row, or the rows of its frame ranges added.
std::string MergedRow(const std::vector<Piece>& p) {
  if (p.size() == 1) return p[0].file->rows[p[0].row];
  ReplayResult total;
  std::string head;
  for (const Piece& piece : p) {
    const std::string where = RowContext(piece.file->path, piece.row);
    const ParsedRow row = ParseRow(piece.file->rows[piece.row], where);
    if (!head.empty() && row.head != head) {
      throw InputError(where + ": the combination's values differ from " + p[0].file->path +
                       "'s (not the same sweep)");
    }
    if (!head.empty() && row.totals.bound.has_value() != total.bound.has_value()) {
      throw InputError(where + ": a bound in some frames' rows but not in others'");
    }
    head = row.head;
    Accumulate(row.totals, &total);
  }
  FinishReadTotals(&total, RowContext(p[0].file->path, p[0].row));
  return RowWithTotals(head, total);
}

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
  for (std::size_t i = 0, n = CombinationCount(varies); i < n; ++i) {
    try {
      CheckReplayable(CombinationConfig(base, varies, i));
    } catch (const InputError& e) {
      throw InputError("--vary: combination " + std::to_string(i) + ": " + e.what());
    }
  }
}

std::vector<std::size_t> ShardIndices(std::size_t combinations, const Shard& shard) {
  std::vector<std::size_t> out;
  for (std::size_t i = shard.index; i < combinations; i += shard.count) out.push_back(i);
  return out;
}

// ---- The file ----------------------------------------------------------------------------

// ---- The file ----------------------------------------------------------------------------

std::string SweepComment(const SweepSpec& spec) {
  std::string s = kCommentStart;
  s += "schema=" + JsonQuote("raycell-sweep/1") + " ";
  s += "trace=" + JsonQuote(spec.trace);
  if (!spec.cells.empty()) s += " cells=" + JsonQuote(spec.cells);
  s += " config=" + JsonQuote(spec.config.empty() ? "defaults" : spec.config);
  s += " config_hash=" + ConfigHash(spec.base);
  for (const Vary& v : spec.varies) s += " vary=" + JsonQuote(v.ToString());
  s += kFramesPart + JsonQuote(spec.frames.empty() ? "all" : spec.frames);
  s += kCombinationsPart + std::to_string(CombinationCount(spec.varies));
  return s + kShardPart + JsonQuote(spec.shard.ToString()) + "\n";
}

std::string SweepHeader(const std::vector<Vary>& varies) {
  return ToCsvHeader(
      SweepRowTable(0, varies, std::vector<std::string>(varies.size()), ReplayResult{}));
}

std::string SweepRow(std::size_t index, const std::vector<Vary>& varies,
                     const std::vector<std::string>& values, const ReplayResult& total) {
  return ToCsvRow(SweepRowTable(index, varies, values, total));
}

// ---- Running and merging -----------------------------------------------------------------

SweepOutcome RunSweep(const TraceReader& reader, const SweepSpec& spec, const std::string& out,
                      const SweepOptions& options) {
  ValidateVaries(spec.base, spec.varies);
  const std::uint64_t cells = reader.header().cell_count();
  std::set<std::vector<std::string>> level_cells;  // the levels' cells, each set checked once
  for (std::size_t i = 0, n = CombinationCount(spec.varies); i < n; ++i) {
    try {
      const ReplayConfig c = CombinationConfig(spec.base, spec.varies, i);
      CheckModelSize(c, cells);
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

void MergeSweepShards(const std::string& out, const std::vector<std::string>& shard_paths) {
  if (shard_paths.empty()) throw InputError("sweep merge: give the shard files to merge");
  std::vector<ShardFile> files;
  for (const std::string& path : shard_paths) files.push_back(ReadShard(path));
  for (const ShardFile& f : files) CheckSameSweep(files.front(), f);
  // One frames selection in every file: shards of combinations only. Else frame ranges.
  bool ranges = false;
  int first = files.front().first, last = files.front().last;
  for (const ShardFile& f : files) {
    if (f.frames == files.front().frames) continue;
    ranges = true;
  }
  if (ranges) {
    for (const ShardFile& f : files) {
      if (f.frames == "all") {
        throw InputError(f.path +
                         ": frames \"all\" cannot be merged with shards of frame "
                         "ranges (run every shard with --frames A..B)");
      }
      first = std::min(first, f.first), last = std::max(last, f.last);
    }
  }
  const std::size_t n = files.front().combinations;
  std::vector<std::vector<Piece>> pieces = Gather(files, n);
  for (std::size_t i = 0; i < n; ++i) CheckTiling(i, pieces[i], ranges, first, last);
  std::string text = files.front().head + kFramesPart +
                     JsonQuote(ranges ? FormatFrameRange(first, last) : files.front().frames) +
                     kCombinationsPart + std::to_string(n) + kShardPart + JsonQuote("all") + "\n" +
                     files.front().header + "\n";
  for (std::size_t i = 0; i < n; ++i) text += MergedRow(pieces[i]) + "\n";
  WriteFileAtomically(out, text);
}

}  // namespace raycell
