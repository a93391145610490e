#include "replay/sweep.h"

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <mutex>
#include <set>
#include <thread>

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
constexpr char kShardPart[] = " shard=";
constexpr char kCombinationsPart[] = " combinations=";

// Whole decimal number, or false.
bool ParseSize(const std::string& s, std::size_t* out) {
  std::uint64_t v = 0;
  if (!TryParseUint(s, &v) || s.size() > 18) return false;
  *out = std::size_t(v);
  return true;
}

std::string Hex(std::uint64_t v) {
  char buf[20];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

std::string ConfigHash(const ReplayConfig& config) {
  const std::string toml = ToToml(config);
  Hash64 h;
  h.AddBytes(toml.data(), toml.size());
  return Hex(h.Finish());
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

// ---- Resuming ----------------------------------------------------------------------------

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

// ---- Running -----------------------------------------------------------------------------

// Receives rows in any order from the workers and appends them to the file in order.
class RowWriter {
 public:
  RowWriter(const std::string& path, std::size_t done, std::size_t total,
            const SweepOptions& options)
      : path_(path),
        file_(path, std::ios::binary | std::ios::app),
        done_(done),
        total_(total),
        options_(options) {
    if (!file_) throw InputError(path + ": cannot open for appending");
  }

  // Row `pos` of this run's list; writes every row that is now next in order.
  void Put(std::size_t pos, std::string row) {
    std::lock_guard<std::mutex> lock(mu_);
    waiting_.emplace(pos, std::move(row));
    while (!stopped() && !waiting_.empty() && waiting_.begin()->first == written_) {
      WriteNext();
    }
  }

  void Fail(std::exception_ptr error) {
    std::lock_guard<std::mutex> lock(mu_);
    if (!error_) error_ = error;
    stop_ = true;
  }

  bool stopped() const { return stop_; }
  std::size_t written() const { return written_; }
  void RethrowError() const {
    if (error_) std::rethrow_exception(error_);
  }

 private:
  void WriteNext() {
    auto it = waiting_.begin();
    if (!(file_ << it->second) || !file_.flush()) throw InputError(path_ + ": cannot write");
    waiting_.erase(it);
    ++written_;
    if (options_.progress) options_.progress(double(done_ + written_) / double(total_));
    if (options_.stop && options_.stop(written_)) stop_ = true;
  }

  std::string path_;
  std::ofstream file_;
  std::size_t done_, total_;
  const SweepOptions& options_;
  std::mutex mu_;
  std::map<std::size_t, std::string> waiting_;
  std::size_t written_ = 0;
  std::atomic<bool> stop_{false};
  std::exception_ptr error_;
};

std::string ComputeRow(const TraceReader& reader, const SweepSpec& spec, std::size_t index) {
  const ReplayConfig config = CombinationConfig(spec.base, spec.varies, index);
  const TraceReplay replay = ReplayTrace(reader, spec.frame_indices, config);
  return SweepRow(index, spec.varies, CombinationValues(spec.varies, index), replay.total);
}

void Work(const TraceReader& reader, const SweepSpec& spec, const std::vector<std::size_t>& todo,
          std::atomic<std::size_t>& next, RowWriter& writer) {
  for (std::size_t pos; !writer.stopped() && (pos = next++) < todo.size();) {
    try {
      writer.Put(pos, ComputeRow(reader, spec, todo[pos]));
    } catch (...) {
      writer.Fail(std::current_exception());
    }
  }
}

// Runs the combinations `todo` on `options.jobs` threads; returns the rows written.
std::size_t RunRows(const TraceReader& reader, const SweepSpec& spec,
                    const std::vector<std::size_t>& todo, const std::string& path, std::size_t done,
                    const SweepOptions& options) {
  RowWriter writer(path, done, done + todo.size(), options);
  std::atomic<std::size_t> next{0};
  const std::size_t jobs =
      std::clamp<std::size_t>(options.jobs, 1, std::max<std::size_t>(todo.size(), 1));
  std::vector<std::thread> threads;
  for (std::size_t j = 0; j < jobs; ++j) {
    threads.emplace_back([&] { Work(reader, spec, todo, next, writer); });
  }
  for (std::thread& t : threads) t.join();
  writer.RethrowError();
  return writer.written();
}

// ---- Merging -----------------------------------------------------------------------------

struct ShardFile {
  std::string path, comment_prefix, header;  // comment line without its shard part
  Shard shard;
  std::size_t combinations = 0;
  std::vector<std::string> rows;
};

// The value of the part " NAME=VALUE" of `comment` found from the end.
std::string PartValue(const std::string& path, const std::string& comment, const char* part) {
  const auto at = comment.rfind(part);
  if (at == std::string::npos) {
    throw InputError(path + ": line 1: no" + std::string(part) + " in the sweep comment");
  }
  const std::size_t begin = at + std::char_traits<char>::length(part);
  return comment.substr(begin, comment.find(' ', begin) - begin);
}

void ParseComment(const std::string& comment, ShardFile* f) {
  if (comment.rfind(kCommentStart, 0) != 0) {
    throw InputError(f->path + ": line 1: expected '" + kCommentStart + "...' (a sweep file)");
  }
  std::string shard = PartValue(f->path, comment, kShardPart);
  if (shard.size() < 2 || shard.front() != '"' || shard.back() != '"') {
    throw InputError(f->path + ": line 1: bad shard " + shard);
  }
  shard = shard.substr(1, shard.size() - 2);
  f->shard = shard == "all" ? Shard{} : Shard::Parse(shard, f->path + ": line 1: shard");
  if (!ParseSize(PartValue(f->path, comment, kCombinationsPart), &f->combinations)) {
    throw InputError(f->path + ": line 1: bad combinations count");
  }
  f->comment_prefix = comment.substr(0, comment.rfind(kShardPart));
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
  f.rows.erase(f.rows.begin(), f.rows.begin() + 2);
  return f;
}

void CheckSameSweep(const ShardFile& a, const ShardFile& b) {
  if (a.comment_prefix != b.comment_prefix || a.header != b.header) {
    throw InputError(b.path + ": not a shard of the same sweep as " + a.path +
                     " (their comment lines or headers differ apart from the shard)");
  }
}

// Places the rows of `f` at their indices; `owner` says which file holds each index.
void PlaceRows(const ShardFile& f, std::vector<std::string>& rows,
               std::vector<const ShardFile*>& owner) {
  for (std::size_t k = 0; k < f.rows.size(); ++k) {
    const std::size_t index = RowIndex(f.rows[k]);
    if (index >= rows.size() || !f.shard.Owns(index)) {
      throw InputError(RowContext(f.path, k) + ": no combination of shard " + f.shard.ToString() +
                       " starts this row");
    }
    if (owner[index]) {
      throw InputError("combination " + std::to_string(index) + " is in both " +
                       owner[index]->path + " and " + f.path + " (overlapping shards)");
    }
    rows[index] = f.rows[k];
    owner[index] = &f;
  }
}

void CheckCovered(const std::vector<const ShardFile*>& owner) {
  for (std::size_t i = 0; i < owner.size(); ++i) {
    if (owner[i]) continue;
    throw InputError("combination " + std::to_string(i) + " of " + std::to_string(owner.size()) +
                     " is in none of the shards (a shard missing or not finished?)");
  }
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
      CombinationConfig(base, varies, i);
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

std::string SweepComment(const SweepSpec& spec) {
  std::string s = kCommentStart;
  s += "schema=" + JsonQuote("raycell-sweep/1") + " ";
  s += "trace=" + JsonQuote(spec.trace);
  s += " config=" + JsonQuote(spec.config.empty() ? "defaults" : spec.config);
  s += " config_hash=" + ConfigHash(spec.base);
  for (const Vary& v : spec.varies) s += " vary=" + JsonQuote(v.ToString());
  s += " frames=" + JsonQuote(spec.frames.empty() ? "all" : spec.frames);
  s += kCombinationsPart + std::to_string(CombinationCount(spec.varies));
  return s + kShardPart + JsonQuote(spec.shard.ToString()) + "\n";
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
  const std::string partial = out + ".partial";
  const std::vector<std::size_t> indices = ShardIndices(CombinationCount(spec.varies), spec.shard);
  SweepOutcome outcome;
  outcome.resumed = ResumePartial(partial, SweepComment(spec) + SweepHeader(spec.varies), indices);
  const std::vector<std::size_t> todo(indices.begin() + outcome.resumed, indices.end());
  outcome.ran = RunRows(reader, spec, todo, partial, outcome.resumed, options);
  outcome.complete = outcome.ran == todo.size();
  if (outcome.complete) RenameFile(partial, out);
  return outcome;
}

void MergeSweepShards(const std::string& out, const std::vector<std::string>& shard_paths) {
  if (shard_paths.empty()) throw InputError("sweep merge: give the shard files to merge");
  std::vector<ShardFile> shards;
  for (const std::string& path : shard_paths) shards.push_back(ReadShard(path));
  for (const ShardFile& s : shards) CheckSameSweep(shards.front(), s);
  const std::size_t n = shards.front().combinations;
  std::vector<std::string> rows(n);
  std::vector<const ShardFile*> owner(n, nullptr);
  for (const ShardFile& s : shards) PlaceRows(s, rows, owner);
  CheckCovered(owner);
  std::string text = shards.front().comment_prefix + kShardPart + JsonQuote("all") + "\n" +
                     shards.front().header + "\n";
  for (const std::string& row : rows) text += row + "\n";
  WriteFileAtomically(out, text);
}

}  // namespace raycell
