// `raycell sweep merge`: the files of one sweep's shards joined into the file of the whole
// (runner/sweep.h MergeSweepShards).
#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include "base/check.h"
#include "base/checked.h"
#include "base/file.h"
#include "base/format.h"
#include "base/parse.h"
#include "base/table.h"
#include "runner/driver.h"
#include "runner/result_table.h"
#include "runner/sweep.h"
#include "runner/sweep_file.h"

namespace raycell {
namespace {

using sweep_file::FinishReadTotals;
using sweep_file::kCombinationsPart;
using sweep_file::kCommentStart;
using sweep_file::kFramesPart;
using sweep_file::kShardPart;
using sweep_file::Lines;
using sweep_file::ParsedRow;
using sweep_file::ParseRow;
using sweep_file::ParseSize;
using sweep_file::RowContext;
using sweep_file::RowIndex;
using sweep_file::RowWithTotals;

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
