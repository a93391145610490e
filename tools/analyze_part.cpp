#include "tools/analyze_part.h"

#include <algorithm>
#include <fstream>
#include <iterator>
#include <optional>

#include "base/check.h"
#include "base/file.h"
#include "base/format.h"
#include "base/hash.h"
#include "base/parse.h"

namespace raycell {
namespace {

constexpr char kPartStart[] = "# raycell analyze part schema=\"raycell-analyze-part/1\"";
// Where a row of the table goes on, on a line of its own (the optimum's status).
constexpr char kTableContinuation[] = "         optimum ";

struct Part {
  std::string path;
  AnalyzePartInfo info;
  std::string header;              // csv and table: the header line; json: none
  std::vector<std::string> lines;  // the rows (and the table's continuation lines)
};

// Reads the first line of a part back, left to right.
class LineReader {
 public:
  LineReader(const std::string& path, const std::string& line) : path_(path), line_(line) {}
  void Expect(const std::string& text) {
    if (line_.compare(at_, text.size(), text) != 0) {
      throw InputError(path_ + ": line 1: expected '" + text + "' at column " +
                       std::to_string(at_ + 1) + " (a part's first line is damaged?)");
    }
    at_ += text.size();
  }
  // Up to `end` or the end of the line; `end` is not read.
  std::string Until(char end) {
    const std::size_t stop = std::min(line_.find(end, at_), line_.size());
    std::string value = line_.substr(at_, stop - at_);
    at_ = stop;
    return value;
  }

 private:
  const std::string& path_;
  const std::string& line_;
  std::size_t at_ = 0;
};

AnalyzePartInfo ParsePartLine(const std::string& path, const std::string& line) {
  if (line.rfind("# raycell analyze part ", 0) != 0) {
    throw InputError(path +
                     ": line 1: expected '# raycell analyze part ...': not a part written by "
                     "`raycell analyze --part`");
  }
  if (line.rfind(kPartStart, 0) != 0) {
    throw InputError(path +
                     ": line 1: not schema \"raycell-analyze-part/1\": written by another "
                     "version of raycell? Rerun that part to merge it");
  }
  AnalyzePartInfo info;
  LineReader r(path, line);
  r.Expect(kPartStart);
  r.Expect(" format=");
  info.format = r.Until(' ');
  if (info.format != "table" && info.format != "json" && info.format != "csv") {
    throw InputError(path + ": line 1: format '" + info.format + "': expected table, json or csv");
  }
  r.Expect(" frames=");
  const std::vector<int> range = ParseFrameRange(r.Until(' '), path + ": line 1: frames");
  info.first = range.front(), info.last = range.back();
  r.Expect(" trace_hash=");
  const std::string hash = r.Until(' ');
  std::size_t used = 0;
  try {
    info.trace_hash = std::stoull(hash, &used, 16);
  } catch (const std::exception&) {
    used = 0;
  }
  if (hash.size() != 16 || used != 16) {
    throw InputError(path + ": line 1: trace_hash '" + hash + "': expected 16 hex digits");
  }
  r.Expect(" options=\"");
  info.options = r.Until('"');
  r.Expect("\" trace=");
  info.trace = r.Until('\n');
  return info;
}

// The frame number a line of a part's rows starts, or nothing for the table's continuation
// lines; InputError when it is no row of the format.
std::optional<long long> RowFrame(const Part& p, const std::string& line, std::size_t number) {
  std::string text;
  if (p.info.format == "csv") {
    text = line.substr(0, line.find(','));
  } else if (p.info.format == "json") {
    const std::string key = "{\"schema\":\"raycell-analyze/1\",\"frame\":";
    if (line.rfind(key, 0) == 0)
      text = line.substr(key.size(), line.find(',', key.size()) - key.size());
  } else {
    if (line.rfind(kTableContinuation, 0) == 0) return std::nullopt;
    const std::string_view trimmed = Trim(line);
    text = std::string(trimmed.substr(0, trimmed.find(' ')));
  }
  try {
    return ParseInt(text, "frame", -(1ll << 31), (1ll << 31) - 1);
  } catch (const InputError&) {
    throw InputError(p.path + ": line " + std::to_string(number) + ": not a row of analyze's " +
                     p.info.format + " output");
  }
}

Part ReadPart(const std::string& path) {
  Part p;
  p.path = path;
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open");
  const std::string text{std::istreambuf_iterator<char>(in), {}};
  p.info = ParsePartLine(path, text.substr(0, text.find('\n')));
  if (text.back() != '\n') {
    throw InputError(path + ": incomplete (does not end with a newline); rerun that part");
  }
  std::vector<std::string> lines = Split(text, '\n');
  lines.pop_back();  // after the last '\n'
  std::size_t body = 1;
  if (p.info.format != "json") {
    if (lines.size() < 2) throw InputError(path + ": no header line after the part's first line");
    p.header = lines[1];
    body = 2;
  }
  p.lines.assign(lines.begin() + body, lines.end());
  long long previous = (long long)p.info.first - 1;
  for (std::size_t k = 0; k < p.lines.size(); ++k) {
    const std::optional<long long> f = RowFrame(p, p.lines[k], body + k + 1);
    if (!f) continue;
    if (*f < p.info.first || *f > p.info.last) {
      throw InputError(path + ": line " + std::to_string(body + k + 1) + ": frame " +
                       std::to_string(*f) + " is outside the part's frames " +
                       FormatFrameRange(p.info.first, p.info.last));
    }
    if (*f <= previous) {
      throw InputError(path + ": line " + std::to_string(body + k + 1) + ": frame " +
                       std::to_string(*f) + " after frame " + std::to_string(previous));
    }
    previous = *f;
  }
  return p;
}

void CheckSameAnalysis(const Part& a, const Part& b) {
  const std::string what = b.path + ": not a part of the same analysis as " + a.path;
  if (a.info.trace_hash != b.info.trace_hash) {
    throw InputError(what + ": another trace (" + b.info.trace + ", trace_hash " +
                     FormatHex64(b.info.trace_hash) + ", against " + a.info.trace + ", " +
                     FormatHex64(a.info.trace_hash) + ")");
  }
  if (a.info.format != b.info.format) {
    throw InputError(what + ": format " + b.info.format + " against " + a.info.format);
  }
  if (a.info.options != b.info.options) {
    throw InputError(what + ": other options ('" + b.info.options + "' against '" + a.info.options +
                     "')");
  }
  if (a.header != b.header) {
    throw InputError(what + ": another header line (written by another version of raycell?)");
  }
}

}  // namespace

std::uint64_t TraceFingerprint(const TraceReader& reader) {
  Hash64 h;
  for (std::uint32_t n : reader.header().cells) h.Add(n);
  h.Add(reader.frames().size());
  for (const FrameSummary& f : reader.frames()) {
    h.Add(std::uint64_t(std::uint32_t(f.frame)));
    h.Add(f.rays);
    h.Add(f.visits);
    h.Add(f.samples);
    h.Add(f.checksum);
  }
  return h.Finish();
}

std::string AnalyzePartLine(const AnalyzePartInfo& info) {
  return std::string(kPartStart) + " format=" + info.format +
         " frames=" + FormatFrameRange(info.first, info.last) +
         " trace_hash=" + FormatHex64(info.trace_hash) + " options=\"" + info.options +
         "\" trace=" + JsonQuote(info.trace) + "\n";
}

void MergeAnalyzeParts(const std::vector<std::string>& paths, const std::string& out) {
  if (paths.empty()) throw InputError("analyze merge: give the part files to merge");
  if (out.empty()) throw InputError("analyze merge: give --out FILE");
  std::vector<Part> parts;
  for (const std::string& path : paths) parts.push_back(ReadPart(path));
  for (const Part& p : parts) CheckSameAnalysis(parts.front(), p);
  std::stable_sort(parts.begin(), parts.end(),
                   [](const Part& a, const Part& b) { return a.info.first < b.info.first; });
  for (std::size_t i = 1; i < parts.size(); ++i) {
    const Part &a = parts[i - 1], &b = parts[i];
    if (b.info.first <= a.info.last) {
      throw InputError("frames " +
                       FormatFrameRange(b.info.first, std::min(a.info.last, b.info.last)) +
                       " are in both " + a.path + " and " + b.path +
                       " (overlapping parts: each frame must be in one part)");
    }
    if (b.info.first > (long long)a.info.last + 1) {
      throw InputError("frames " + FormatFrameRange((long long)a.info.last + 1, b.info.first - 1) +
                       " are in none of the parts (a gap between " + a.path + " and " + b.path +
                       "): analyse them with --frames " +
                       FormatFrameRange((long long)a.info.last + 1, b.info.first - 1) +
                       " --part FILE and merge that part too");
    }
  }
  std::string bytes;
  if (!parts.front().header.empty()) bytes = parts.front().header + "\n";
  for (const Part& p : parts) {
    for (const std::string& line : p.lines) bytes += line + "\n";
  }
  WriteFileAtomically(out, bytes, "--out " + out);
}

}  // namespace raycell
