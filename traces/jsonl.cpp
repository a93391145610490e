#include "traces/jsonl.h"

#include <algorithm>
#include <charconv>
#include <functional>
#include <limits>
#include <map>
#include <queue>
#include <string_view>
#include <utility>
#include <vector>

#include "base/check.h"
#include "traces/trace_writer.h"

namespace raycell {

// ============================================================================== Writing

namespace {
constexpr std::size_t kFlushAt = std::size_t{1} << 20;
}  // namespace

JsonlWriter::JsonlWriter(std::ostream& out) : out_(out) { buf_.reserve(kFlushAt + 4096); }

JsonlWriter::~JsonlWriter() { Flush(); }

void JsonlWriter::Write(const RayView& r, std::optional<std::int32_t> frame) {
  Put('{');
  if (frame) Text("\"frame\":").Int(*frame).Put(',');
  Text("\"id\":").Int(r.id);
  if (r.is_primary()) {
    Text(",\"parent\":null,\"spawn\":null");
  } else {
    Text(",\"parent\":").Int(r.parent).Text(",\"spawn\":").Int(r.spawn);
  }
  Text(",\"kind\":\"").Text(ToString(r.kind)).Text("\",\"pixel\":[").Int(r.pixel_x).Put(',');
  Int(r.pixel_y).Text("],\"cells\":");
  List(r.cells, r.visit_count).Text(",\"samples\":").List(r.samples, r.visit_count);
  Text("}\n");
  if (buf_.size() >= kFlushAt) Flush();
}

void JsonlWriter::Flush() {
  out_.write(buf_.data(), static_cast<std::streamsize>(buf_.size()));
  buf_.clear();
}

JsonlWriter& JsonlWriter::Put(char c) {
  buf_.push_back(c);
  return *this;
}

JsonlWriter& JsonlWriter::Text(const char* s) {
  buf_.append(s);
  return *this;
}

template <typename T>
JsonlWriter& JsonlWriter::Int(T v) {
  char tmp[24];
  const auto end = std::to_chars(tmp, tmp + sizeof tmp, v).ptr;
  buf_.append(tmp, end);
  return *this;
}

JsonlWriter& JsonlWriter::List(const std::uint32_t* v, std::size_t n) {
  Put('[');
  for (std::size_t i = 0; i < n; ++i) {
    if (i) Put(',');
    Int(v[i]);
  }
  return Put(']');
}

JsonlWriter& JsonlWriter::List(const CellId* v, std::size_t n) {
  Put('[');
  for (std::size_t i = 0; i < n; ++i) {
    if (i) Put(',');
    Int(v[i].value());
  }
  return Put(']');
}

namespace {

void WriteFrame(const TraceReader& reader, std::size_t index, bool with_frame, JsonlWriter& out) {
  std::optional<std::int32_t> frame;
  if (with_frame) frame = reader.frames()[index].frame;
  reader.ForEachBatch(index, [&](const RayBatch& b) {
    for (std::size_t i = 0; i < b.size(); ++i) out.Write(b.ray(i), frame);
  });
}

}  // namespace

void WriteJsonl(const TraceReader& reader, std::optional<std::size_t> frame_index,
                std::ostream& out) {
  JsonlWriter writer(out);
  if (frame_index) {
    WriteFrame(reader, *frame_index, false, writer);
    return;
  }
  const bool with_frame = reader.frames().size() > 1;
  for (std::size_t i = 0; i < reader.frames().size(); ++i) {
    WriteFrame(reader, i, with_frame, writer);
  }
}

// ============================================================================== Reading

namespace {

enum Key : unsigned { kFrame, kId, kParent, kSpawn, kKind, kPixel, kCells, kSamples, kKeyCount };
const char* const kKeyNames[kKeyCount] = {"frame", "id",    "parent", "spawn",
                                          "kind",  "pixel", "cells",  "samples"};

std::string Quoted(Key k) { return std::string("\"") + kKeyNames[k] + "\""; }

// One line as parsed, before it is checked against the others of its frame.
struct ParsedLine {
  unsigned seen = 0;  // bit k: key k was present
  std::int64_t frame = 0;
  RayId id = 0;
  bool parent_null = true, spawn_null = true;
  RayId parent = 0;
  std::uint64_t spawn = 0;
  std::string kind;
  std::vector<std::uint64_t> pixel, cells, samples;
  bool has(Key k) const { return seen & (1u << k); }
};

// A strict parser for one line: a flat JSON object whose values are integers, null, strings
// without escapes, or arrays of integers. Errors are InputError "column N: what" or name the
// key.
class LineParser {
 public:
  explicit LineParser(std::string_view line) : s_(line) {}

  void Parse(ParsedLine& out) {
    out.seen = 0;
    Expect('{');
    if (!Consume('}')) {
      do ParseMember(out);
      while (Consume(','));
      Expect('}');
    }
    SkipSpace();
    if (pos_ != s_.size()) Fail("unexpected text after the object");
  }

 private:
  [[noreturn]] void Fail(const std::string& what) const {
    throw InputError("column " + std::to_string(pos_ + 1) + ": " + what);
  }
  void SkipSpace() {
    while (pos_ < s_.size() && (s_[pos_] == ' ' || s_[pos_] == '\t' || s_[pos_] == '\r')) ++pos_;
  }
  bool Consume(char c) {
    SkipSpace();
    if (pos_ < s_.size() && s_[pos_] == c) return ++pos_, true;
    return false;
  }
  void Expect(char c) {
    if (!Consume(c)) Fail(std::string("expected '") + c + "'");
  }
  bool ConsumeNull() {
    SkipSpace();
    if (s_.compare(pos_, 4, "null") != 0) return false;
    pos_ += 4;
    return true;
  }
  bool AtString() {
    SkipSpace();
    return pos_ < s_.size() && s_[pos_] == '"';
  }
  bool AtArray() {
    SkipSpace();
    return pos_ < s_.size() && s_[pos_] == '[';
  }
  std::string_view ParseString() {
    Expect('"');
    const std::size_t end = s_.find_first_of("\"\\", pos_);
    if (end == std::string_view::npos || s_[end] != '"') Fail("unterminated or escaped string");
    const std::string_view out = s_.substr(pos_, end - pos_);
    pos_ = end + 1;
    return out;
  }
  // A JSON integer (no fraction, no exponent); negative only where `negative` is given.
  std::uint64_t ParseInt(bool* negative = nullptr) {
    SkipSpace();
    if (negative) *negative = pos_ < s_.size() && s_[pos_] == '-';
    if (negative && *negative) ++pos_;
    const std::size_t start = pos_;
    std::uint64_t v = 0;
    while (pos_ < s_.size() && s_[pos_] >= '0' && s_[pos_] <= '9') {
      const std::uint64_t d = static_cast<std::uint64_t>(s_[pos_] - '0');
      if (v > (std::numeric_limits<std::uint64_t>::max() - d) / 10) Fail("integer too large");
      v = v * 10 + d;
      ++pos_;
    }
    if (pos_ == start) Fail(negative ? "expected an integer" : "expected a non-negative integer");
    if (pos_ - start > 1 && s_[start] == '0') {
      pos_ = start;
      Fail("leading zero");
    }
    if (pos_ < s_.size() && (s_[pos_] == '.' || s_[pos_] == 'e' || s_[pos_] == 'E')) {
      Fail("expected an integer");
    }
    return v;
  }
  void ParseArray(std::vector<std::uint64_t>& out) {
    out.clear();
    Expect('[');
    if (Consume(']')) return;
    do out.push_back(ParseInt());
    while (Consume(','));
    Expect(']');
  }
  [[noreturn]] void WrongType(Key k, const char* expected) const {
    throw InputError(Quoted(k) + ": expected " + expected);
  }
  Key ParseKey() {
    const std::string_view key = ParseString();
    for (unsigned k = 0; k < kKeyCount; ++k) {
      if (key == kKeyNames[k]) return static_cast<Key>(k);
    }
    throw InputError("unknown key \"" + std::string(key) + "\" (expected " +
                     "frame, id, parent, spawn, kind, pixel, cells or samples)");
  }
  std::int64_t ParseFrame() {
    if (AtString() || AtArray() || ConsumeNull()) WrongType(kFrame, "an integer");
    bool negative = false;
    const std::uint64_t v = ParseInt(&negative);
    const std::uint64_t limit = negative ? std::uint64_t{1} << 31 : (std::uint64_t{1} << 31) - 1;
    if (v > limit)
      throw InputError("\"frame\" " + std::string(negative ? "-" : "") + std::to_string(v) +
                       " does not fit in 32 bits");
    return negative ? -static_cast<std::int64_t>(v) : static_cast<std::int64_t>(v);
  }
  // An integer or null (parent, spawn); true when null.
  bool ParseOptionalInt(Key k, std::uint64_t* v) {
    if (ConsumeNull()) return true;
    if (AtString() || AtArray()) WrongType(k, "a non-negative integer or null");
    *v = ParseInt();
    return false;
  }
  void ParseMember(ParsedLine& out) {
    const Key k = ParseKey();
    if (out.has(k)) throw InputError("duplicate key " + Quoted(k));
    out.seen |= 1u << k;
    Expect(':');
    switch (k) {
      case kFrame:
        out.frame = ParseFrame();
        break;
      case kId:
        if (AtString() || AtArray() || ConsumeNull()) WrongType(k, "a non-negative integer");
        out.id = ParseInt();
        break;
      case kParent:
        out.parent_null = ParseOptionalInt(k, &out.parent);
        break;
      case kSpawn:
        out.spawn_null = ParseOptionalInt(k, &out.spawn);
        break;
      case kKind:
        if (!AtString()) WrongType(k, "a string");
        out.kind.assign(ParseString());
        break;
      default:
        if (!AtArray()) WrongType(k, "an array of non-negative integers");
        ParseArray(k == kPixel ? out.pixel : k == kCells ? out.cells : out.samples);
    }
  }

  std::string_view s_;
  std::size_t pos_ = 0;
};

constexpr std::uint8_t kHasParent = 1, kHasPixel = 2;

// The rays of one frame in file order, as given.
struct PendingFrame {
  std::vector<RayId> id, parent;  // parent: where kHasParent
  std::vector<std::uint8_t> flags;
  std::vector<std::uint32_t> spawn, px, py;
  std::vector<RayKind> kind;
  std::vector<std::size_t> line;        // line number in the file
  std::vector<std::uint64_t> begin{0};  // ray i's visits: [begin[i], begin[i + 1])
  std::vector<CellId> cells;
  std::vector<std::uint32_t> samples;

  std::size_t size() const { return id.size(); }
  std::size_t visits(std::size_t i) const { return begin[i + 1] - begin[i]; }
  void Clear() { *this = PendingFrame(); }
};

std::uint32_t To32(std::uint64_t v, const std::string& what) {
  if (v > std::numeric_limits<std::uint32_t>::max()) {
    throw InputError(what + " " + std::to_string(v) + " does not fit in 32 bits");
  }
  return static_cast<std::uint32_t>(v);
}

std::string RayName(RayId id) { return "ray " + std::to_string(id) + ": "; }

// Appends a parsed line's ray to the frame, after the checks that need only the line.
class LineChecker {
 public:
  explicit LineChecker(const JsonlReadOptions& o) : options_(o) {}

  void Add(const ParsedLine& p, std::size_t line, PendingFrame& f) const {
    for (Key k : {kId, kParent, kSpawn, kCells}) {
      if (!p.has(k)) throw InputError("missing " + Quoted(k));
    }
    const std::string ray = RayName(p.id);
    if (p.parent_null != p.spawn_null) {
      throw InputError(ray + "\"parent\" and \"spawn\" must both be null or both be set");
    }
    std::uint8_t flags = p.parent_null ? 0 : kHasParent;
    const RayKind kind = Kind(p, ray);
    f.id.push_back(p.id);
    f.parent.push_back(p.parent_null ? kNoParent : p.parent);
    f.spawn.push_back(p.spawn_null ? 0 : To32(p.spawn, ray + "\"spawn\""));
    f.kind.push_back(kind);
    std::uint32_t px = 0, py = 0;
    if (p.has(kPixel)) {
      if (p.pixel.size() != 2) throw InputError(ray + "\"pixel\" must have 2 elements");
      px = To32(p.pixel[0], ray + "\"pixel\" x");
      py = To32(p.pixel[1], ray + "\"pixel\" y");
      flags |= kHasPixel;
    }
    f.px.push_back(px);
    f.py.push_back(py);
    f.flags.push_back(flags);
    f.line.push_back(line);
    AddVisits(p, ray, f);
  }

 private:
  RayKind Kind(const ParsedLine& p, const std::string& ray) const {
    if (!p.has(kKind)) return p.parent_null ? RayKind::kPrimary : RayKind::kReflection;
    const std::optional<RayKind> kind = ParseRayKind(p.kind);
    if (!kind) {
      throw InputError(ray + "unknown kind \"" + std::string(p.kind) +
                       "\" (expected primary, reflection, refraction or shadow)");
    }
    if (*kind == RayKind::kPrimary && !p.parent_null) {
      throw InputError(ray + "kind \"primary\" with a parent (" + std::to_string(p.parent) + ")");
    }
    if (*kind != RayKind::kPrimary && p.parent_null) {
      throw InputError(ray + "kind \"" + std::string(p.kind) +
                       "\" without a parent (only primary rays have none)");
    }
    return *kind;
  }

  void AddVisits(const ParsedLine& p, const std::string& ray, PendingFrame& f) const {
    if (p.has(kSamples) && p.samples.size() != p.cells.size()) {
      throw InputError(ray + "\"cells\" and \"samples\" differ in length (" +
                       std::to_string(p.cells.size()) + " and " + std::to_string(p.samples.size()) +
                       ")");
    }
    if (p.cells.size() > kTraceMaxRayVisits) {
      throw InputError(ray + std::to_string(p.cells.size()) + " visits (at most " +
                       std::to_string(kTraceMaxRayVisits) + ")");
    }
    for (std::size_t v = 0; v < p.cells.size(); ++v) {
      const std::uint64_t c = p.cells[v];
      if (v > 0 && c == p.cells[v - 1]) {
        throw InputError(ray + "cell " + std::to_string(c) + " repeated at visit " +
                         std::to_string(v));
      }
      CheckCell(c, ray);
      f.cells.push_back(static_cast<CellId>(c));
      f.samples.push_back(p.has(kSamples) ? To32(p.samples[v], ray + "\"samples\"") : 1);
    }
    f.begin.push_back(f.cells.size());
  }

  void CheckCell(std::uint64_t c, const std::string& ray) const {
    if (options_.cell_count == 0 && c >= kJsonlMaxCells) {
      throw InputError(ray + "cell " + std::to_string(c) + " out of range (at most " +
                       std::to_string(kJsonlMaxCells) + " cells)");
    }
    if (options_.cell_count != 0 && c >= options_.cell_count) {
      throw InputError(ray + "cell " + std::to_string(c) + " out of range: " +
                       (options_.cells_what.empty() ? "the grid" : options_.cells_what) + " has " +
                       std::to_string(options_.cell_count) + " cells");
    }
  }

  const JsonlReadOptions& options_;
};

// Puts one frame's rays in the reader's order (see JsonlFrame::rays) after checking what needs
// the whole frame: duplicate ids, unknown parents, spawn visits, cycles.
class FrameOrderer {
 public:
  FrameOrderer(const PendingFrame& f, const std::string& name) : f_(f), name_(name) {}

  void Run(JsonlFrame& out) {
    SortById();
    CheckDuplicates();
    FindParents();
    Order();
    Emit(out);
  }

 private:
  [[noreturn]] void Fail(std::size_t i, const std::string& what) const {
    throw InputError(name_ + ":" + std::to_string(f_.line[i]) + ": " + RayName(f_.id[i]) + what);
  }
  bool HasParent(std::size_t i) const { return f_.flags[i] & kHasParent; }

  // by_id_: ray indices by id, file order among equal ids; rank_: the inverse.
  void SortById() {
    by_id_.resize(f_.size());
    for (std::size_t i = 0; i < by_id_.size(); ++i) by_id_[i] = i;
    std::stable_sort(by_id_.begin(), by_id_.end(),
                     [&](std::size_t a, std::size_t b) { return f_.id[a] < f_.id[b]; });
    rank_.resize(f_.size());
    for (std::size_t k = 0; k < by_id_.size(); ++k) rank_[by_id_[k]] = k;
  }

  // The first line (in file order) that repeats an earlier line's id.
  void CheckDuplicates() const {
    std::size_t worst = f_.size(), first = 0;
    for (std::size_t k = 1; k < by_id_.size(); ++k) {
      const std::size_t a = by_id_[k - 1], b = by_id_[k];
      if (f_.id[a] != f_.id[b]) continue;
      std::size_t start = k - 1;
      while (start > 0 && f_.id[by_id_[start - 1]] == f_.id[b]) --start;
      if (worst == f_.size() || b < worst) worst = b, first = by_id_[start];
    }
    if (worst != f_.size()) {
      Fail(worst, "duplicate id (also the id of line " + std::to_string(f_.line[first]) + ")");
    }
  }

  std::size_t Find(RayId id) const {
    const auto it = std::lower_bound(by_id_.begin(), by_id_.end(), id,
                                     [&](std::size_t a, RayId v) { return f_.id[a] < v; });
    return it != by_id_.end() && f_.id[*it] == id ? *it : f_.size();
  }

  // parent_[i]: the parent's index; checks, in file order, that it exists and that the ray
  // starts where its parent spawned it.
  void FindParents() {
    parent_.assign(f_.size(), f_.size());
    for (std::size_t i = 0; i < f_.size(); ++i) {
      if (!HasParent(i)) continue;
      const RayId pid = f_.parent[i];
      const std::size_t p = Find(pid);
      if (p == f_.size()) Fail(i, "unknown parent " + std::to_string(pid));
      parent_[i] = p;
      const std::string of_parent =
          "parent " + std::to_string(pid) + " (line " + std::to_string(f_.line[p]) + ")";
      if (f_.spawn[i] >= f_.visits(p)) {
        Fail(i, "spawn " + std::to_string(f_.spawn[i]) + " out of range: " + of_parent + " has " +
                    std::to_string(f_.visits(p)) + " visits");
      }
      const CellId spawn_cell = f_.cells[f_.begin[p] + f_.spawn[i]];
      if (f_.visits(i) > 0 && f_.cells[f_.begin[i]] != spawn_cell) {
        Fail(i, "first cell " + std::to_string(f_.cells[f_.begin[i]].value()) +
                    " is not the cell " + std::to_string(spawn_cell.value()) + " of " + of_parent +
                    "'s spawn visit " + std::to_string(f_.spawn[i]));
      }
    }
  }

  // Ray trees by their primary ray's id; in each, the smallest id whose parent is placed.
  void Order() {
    const std::size_t n = f_.size();
    std::vector<std::size_t> child_begin(n + 1, 0), children(n);
    for (std::size_t i = 0; i < n; ++i) {
      if (HasParent(i)) ++child_begin[parent_[i] + 1];
    }
    for (std::size_t i = 0; i < n; ++i) child_begin[i + 1] += child_begin[i];
    std::vector<std::size_t> fill(child_begin.begin(), child_begin.end() - 1);
    for (std::size_t i : by_id_) {  // children in id order
      if (HasParent(i)) children[fill[parent_[i]]++] = i;
    }
    order_.clear();
    order_.reserve(n);
    std::priority_queue<std::size_t, std::vector<std::size_t>, std::greater<>> ready;  // ranks
    for (std::size_t root : by_id_) {
      if (HasParent(root)) continue;
      ready.push(rank_[root]);
      while (!ready.empty()) {
        const std::size_t i = by_id_[ready.top()];
        ready.pop();
        order_.push_back(i);
        for (std::size_t c = child_begin[i]; c < child_begin[i + 1]; ++c) {
          ready.push(rank_[children[c]]);
        }
      }
    }
    if (order_.size() != n) FailCycle();
  }

  // Some rays were never placed: their chains of parents loop without a primary ray.
  [[noreturn]] void FailCycle() const {
    std::vector<bool> placed(f_.size(), false);
    for (std::size_t i : order_) placed[i] = true;
    std::size_t i = 0;
    while (placed[i]) ++i;  // the first unplaced line
    std::vector<bool> on_chain(f_.size(), false);
    std::string chain;
    std::size_t shown = 0;
    for (std::size_t j = i;; j = parent_[j]) {
      if (shown < 12) chain += (shown ? " -> " : "") + std::to_string(f_.id[j]);
      ++shown;
      if (on_chain[j]) break;
      on_chain[j] = true;
    }
    if (shown > 12) chain += " -> ...";
    Fail(i, "its chain of parents loops without reaching a primary ray: " + chain);
  }

  void Emit(JsonlFrame& out) const {
    const std::size_t n = f_.size();
    std::vector<RayId> new_id(n);
    for (std::size_t k = 0; k < n; ++k) new_id[order_[k]] = k;
    std::vector<std::uint32_t> px(f_.px), py(f_.py);  // pixels after inheritance
    out.rays = RayBatch(false);
    out.rays.Reserve(n, f_.cells.size());
    out.renumbered = false;
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t i = order_[k];
      if (f_.id[i] != k) out.renumbered = true;
      const bool spawned = HasParent(i);
      if (spawned && !(f_.flags[i] & kHasPixel)) px[i] = px[parent_[i]], py[i] = py[parent_[i]];
      out.rays.BeginRay(f_.kind[i], spawned ? new_id[parent_[i]] : kNoParent,
                        spawned ? f_.spawn[i] : 0, px[i], py[i]);
      for (std::uint64_t v = f_.begin[i]; v < f_.begin[i + 1]; ++v) {
        out.rays.AddVisit(f_.cells[v], f_.samples[v], 0.f, 0.f);
      }
    }
  }

  const PendingFrame& f_;
  const std::string& name_;
  std::vector<std::size_t> by_id_, rank_, parent_, order_;
};

bool IsBlank(std::string_view line) {
  return line.find_first_not_of(" \t\r") == std::string_view::npos;
}

}  // namespace

struct JsonlReader::Impl {
  std::istream& in;
  std::string name;
  JsonlReadOptions options;
  std::size_t line_number = 0;
  std::string text;
  ParsedLine parsed;
  // The first line of the next frame, read while finishing the current one.
  bool has_lookahead = false;
  ParsedLine lookahead;
  std::size_t lookahead_line = 0;
  // Whether lines carry "frame", as the first line decided.
  std::optional<bool> with_frame;
  std::size_t first_line = 0;
  std::map<std::int64_t, std::pair<std::size_t, std::size_t>> done;  // frame -> its lines
  PendingFrame pending;

  Impl(std::istream& i, std::string n, JsonlReadOptions o)
      : in(i), name(std::move(n)), options(std::move(o)) {}

  [[noreturn]] void Fail(std::size_t line, const std::string& what) const {
    throw InputError(name + ":" + std::to_string(line) + ": " + what);
  }

  // Parses the next non-blank line into `parsed`; false at the end.
  bool ReadLine() {
    while (std::getline(in, text)) {
      ++line_number;
      if (IsBlank(text)) continue;
      try {
        LineParser(text).Parse(parsed);
      } catch (const InputError& e) {
        Fail(line_number, e.what());
      }
      CheckFrameKey();
      return true;
    }
    if (in.bad()) throw InputError(name + ": read error after line " + std::to_string(line_number));
    return false;
  }

  void CheckFrameKey() {
    const bool has = parsed.has(kFrame);
    if (!with_frame) {
      with_frame = has;
      first_line = line_number;
    } else if (*with_frame != has) {
      Fail(line_number, std::string(has ? "a" : "no") + " \"frame\" key, but line " +
                            std::to_string(first_line) + " has " + (has ? "none" : "one") +
                            " (either every line has one or none does)");
    }
  }

  void Add(const ParsedLine& p, std::size_t line) {
    try {
      LineChecker(options).Add(p, line, pending);
    } catch (const InputError& e) {
      Fail(line, e.what());
    }
  }

  bool Next(JsonlFrame& out) {
    pending.Clear();
    std::size_t first = 0;
    if (has_lookahead) {
      has_lookahead = false;
      std::swap(parsed, lookahead);
      first = lookahead_line;
    } else {
      if (!ReadLine()) return false;
      first = line_number;
    }
    const std::int64_t frame = parsed.frame;
    Add(parsed, first);
    std::size_t last = first;
    while (ReadLine()) {
      if (parsed.frame != frame) {
        CheckNewFrame(parsed.frame, frame);
        std::swap(parsed, lookahead);
        lookahead_line = line_number;
        has_lookahead = true;
        break;
      }
      Add(parsed, line_number);
      last = line_number;
    }
    done[frame] = {first, last};
    out.frame = static_cast<std::int32_t>(frame);
    out.first_line = first;
    out.last_line = last;
    FrameOrderer(pending, name).Run(out);
    return true;
  }

  void CheckNewFrame(std::int64_t next, std::int64_t current) const {
    const auto it = done.find(next);
    if (it == done.end()) return;
    Fail(line_number, "frame " + std::to_string(next) + " again, after frame " +
                          std::to_string(current) + ": the lines of a frame must be together (" +
                          "frame " + std::to_string(next) + " was at lines " +
                          std::to_string(it->second.first) + "-" +
                          std::to_string(it->second.second) + ")");
  }
};

JsonlReader::JsonlReader(std::istream& in, std::string name, JsonlReadOptions options)
    : impl_(std::make_unique<Impl>(in, std::move(name), std::move(options))) {}
JsonlReader::JsonlReader(JsonlReader&&) noexcept = default;
JsonlReader& JsonlReader::operator=(JsonlReader&&) noexcept = default;
JsonlReader::~JsonlReader() = default;

bool JsonlReader::Next(JsonlFrame& frame) { return impl_->Next(frame); }

}  // namespace raycell
