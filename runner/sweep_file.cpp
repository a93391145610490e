#include "runner/sweep_file.h"

#include "base/check.h"
#include "base/checked.h"
#include "base/format.h"
#include "base/hash.h"
#include "base/parse.h"
#include "base/table.h"
#include "replay/config.h"
#include "runner/driver.h"
#include "runner/result_table.h"
#include "runner/sweep.h"

namespace raycell {
namespace {

StatsTable SweepRowTable(std::size_t index, const std::vector<Vary>& varies,
                         const std::vector<std::string>& values, const ReplayResult& total) {
  RAYCELL_CHECK_EQ(values.size(), varies.size());
  StatsTable t;
  t.AddCount("index", index);
  for (std::size_t k = 0; k < varies.size(); ++k) t.AddText(varies[k].key, values[k]);
  AddResult(total, kSweepColumns, &t);
  return t;
}

std::uint64_t Field(const std::string& text, const std::string& where) {
  std::uint64_t v = 0;
  if (!TryParseUint(text, &v))
    throw InputError(where + ": expected a whole number, got '" + text + "'");
  return v;
}

}  // namespace

namespace sweep_file {

// Whole decimal number, or false.
bool ParseSize(const std::string& s, std::size_t* out) {
  std::uint64_t v = 0;
  if (!TryParseUint(s, &v) || s.size() > 18) return false;
  *out = std::size_t(v);
  return true;
}

std::string ConfigHash(const ReplayConfig& config) {
  // The configuration, not its documentation: the printed TOML without its comment lines, so
  // that a better help text changes no sweep file (nor stops a sweep from resuming).
  const std::string toml = ToToml(config);
  std::string values;
  for (std::size_t start = 0; start < toml.size();) {
    std::size_t end = toml.find('\n', start);
    end = end == std::string::npos ? toml.size() : end + 1;
    const std::size_t first = toml.find_first_not_of(" \t", start);
    if (first >= end || toml[first] != '#') values.append(toml, start, end - start);
    start = end;
  }
  Hash64 h;
  h.AddBytes(values.data(), values.size());
  return FormatHex64(h.Finish());
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

}  // namespace sweep_file

using sweep_file::ConfigHash;
using sweep_file::kCombinationsPart;
using sweep_file::kCommentStart;
using sweep_file::kFramesPart;
using sweep_file::kShardPart;

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

}  // namespace raycell
