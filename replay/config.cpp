#include "replay/config.h"

#include <toml++/toml.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "base/check.h"
#include "base/parse.h"

namespace raycell {
namespace {

// ---------------------------------------------------------------------------------------------
// Default values and where they come from: one table used by DefaultConfig's documentation,
// ToToml's comments and DefaultsHelp.

struct KeyDoc {
  const char* key;      // dotted override key; "level.*.x" for any level
  const char* meaning;  // what the key is
};

constexpr KeyDoc kKeyDocs[] = {
    {"scheduler", "cell scheduler: maxwork | roundrobin | random | peel | celltree"},
    {"seed", "seed of the random scheduler"},
    {"granularity",
     "ray: per ray segment (exact) | node: per Cell Tree node (aggregated, fast) | auto: node "
     "with one processor (where it is exact), ray otherwise"},
    {"processors.count", "number of block processors, 1..1024"},
    {"processors.time_per_sample", "time a block processor takes per sample"},
    {"processors.queue_record_bytes", "bytes per queued ray (an integer or a size, \"32B\")"},
    {"processors.prefetch",
     "fetch the next scheduled cell while the current one is worked (double buffering)"},
    {"level.*.name", "unique name, [A-Za-z0-9_-]+; override keys are level.NAME.KEY"},
    {"level.*.capacity", "\"N cell\" / \"N cells\", or a size such as \"256MiB\""},
    {"level.*.bandwidth", "to the level below (below the last: host memory); \"unlimited\" ok"},
    {"level.*.latency", "to the level below"},
    {"level.*.replacement", "lru | fifo | min (Belady's MIN, a bound)"},
};

// Source of each default value, keyed like kKeyDocs but with default level names.
const std::map<std::string, std::string>& DefaultSources() {
  static const std::map<std::string, std::string> sources = {
      {"scheduler", "the paper's Cell Tree scheduler"},
      {"seed", "any fixed value keeps a replay deterministic"},
      {"granularity", "exact and as fast as possible"},
      {"processors.count", "one block processor, the paper's case"},
      {"processors.time_per_sample",
       "one sample per cycle of a 100 MHz pipeline, the Cube-5/GI-Cube design point"},
      {"processors.queue_record_bytes", "position, direction, colour/opacity, cell-tree node"},
      {"processors.prefetch", "no double buffering, the paper's model"},
      {"level.cache", "the block processor's on-chip cell cache"},
      {"level.cache.capacity", "\"cell size set to memory size\", the paper's case"},
      {"level.cache.bandwidth", "one Direct RDRAM PC800 channel, 2 bytes x 800 MT/s"},
      {"level.cache.latency", "RDRAM row access"},
      {"level.cache.replacement", "with one cell every policy behaves alike"},
      {"level.board", "board memory (RDRAM) of the PCI board"},
      {"level.board.capacity", "RDRAM board memory of a PCI board of the period"},
      {"level.board.bandwidth", "32-bit 33 MHz PCI to host memory"},
      {"level.board.latency", "a PCI transaction"},
      {"level.board.replacement", "LRU, the usual hardware policy"},
  };
  return sources;
}

std::string SourceOf(const std::string& key) {
  const auto it = DefaultSources().find(key);
  return it == DefaultSources().end() ? std::string() : it->second;
}

// ---------------------------------------------------------------------------------------------
// Value parsing shared by files and overrides. `what` prefixes every message.

[[noreturn]] void Fail(const std::string& what, const std::string& message) {
  throw InputError(what + ": " + message);
}

// A decimal unsigned integer in [lo, hi], digits only.
std::uint64_t ParseCount(std::string_view text, const std::string& what, std::uint64_t lo,
                         std::uint64_t hi) {
  std::uint64_t v = 0;
  const bool ok = TryParseUint(Trim(text), &v);
  if (!ok) Fail(what, "expected a whole number, got '" + std::string(text) + "'");
  if (v < lo || v > hi) {
    Fail(what, "must be in " + std::to_string(lo) + ".." + std::to_string(hi) + ", got " +
                   std::to_string(v));
  }
  return v;
}

bool ParseBool(std::string_view text, const std::string& what) {
  const std::string_view t = Trim(text);
  if (t == "true") return true;
  if (t == "false") return false;
  Fail(what, "expected true or false, got '" + std::string(text) + "'");
}

std::string ParseScheduler(std::string_view text, const std::string& what) {
  for (const std::string_view s : kSchedulers) {
    if (text == s) return std::string(s);
  }
  Fail(what, "unknown scheduler '" + std::string(text) +
                 "' (expected maxwork, roundrobin, random, peel or celltree)");
}

ReplayConfig::Granularity ParseGranularity(std::string_view text, const std::string& what) {
  if (text == "ray") return ReplayConfig::Granularity::kRay;
  if (text == "node") return ReplayConfig::Granularity::kNode;
  if (text == "auto") return ReplayConfig::Granularity::kAuto;
  Fail(what, "unknown granularity '" + std::string(text) + "' (expected ray, node or auto)");
}

LevelConfig::Replacement ParseReplacement(std::string_view text, const std::string& what) {
  if (text == "lru") return LevelConfig::Replacement::kLru;
  if (text == "fifo") return LevelConfig::Replacement::kFifo;
  if (text == "min") return LevelConfig::Replacement::kMin;
  Fail(what, "unknown replacement '" + std::string(text) + "' (expected lru, fifo or min)");
}

// "1 cell", "4 cells" or a size ("256MiB"); > 0.
void ParseCapacity(std::string_view text, const std::string& what, LevelConfig* level) {
  std::string_view t = Trim(text);
  for (const std::string_view suffix : {"cells", "cell"}) {
    if (t.size() > suffix.size() && t.substr(t.size() - suffix.size()) == suffix) {
      level->capacity_unit = LevelConfig::CapacityUnit::kCells;
      level->capacity = ParseCount(t.substr(0, t.size() - suffix.size()), what + " (cells)", 1,
                                   std::numeric_limits<std::uint64_t>::max());
      return;
    }
  }
  const Bytes b = ParseBytes(text, what);
  if (b.count() == 0) Fail(what, "capacity must be greater than zero: '" + std::string(text) + "'");
  level->capacity_unit = LevelConfig::CapacityUnit::kBytes;
  level->capacity = b.count();
}

SimTime ParsePositiveDuration(std::string_view text, const std::string& what) {
  const SimTime t = ParseDuration(text, what);
  if (t == SimTime::Zero()) Fail(what, "must be greater than zero: '" + std::string(text) + "'");
  return t;
}

bool ValidLevelName(std::string_view name) {
  return !name.empty() && std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
  });
}

// ---------------------------------------------------------------------------------------------
// TOML reading with pbrt-style ReportUnused.

std::string Where(const std::string& file, const toml::source_region& r) {
  return file + ":" + std::to_string(r.begin.line) + ":" + std::to_string(r.begin.column);
}

const char* TypeName(const toml::node& n) {
  switch (n.type()) {
    case toml::node_type::table:
      return "a table";
    case toml::node_type::array:
      return "an array";
    case toml::node_type::string:
      return "a string";
    case toml::node_type::integer:
      return "an integer";
    case toml::node_type::floating_point:
      return "a floating-point number";
    case toml::node_type::boolean:
      return "a boolean";
    case toml::node_type::date:
    case toml::node_type::time:
    case toml::node_type::date_time:
      return "a date/time";
    default:
      return "nothing";
  }
}

// One TOML table being read: Get() marks a key used; ReportUnused() rejects the rest.
class Section {
 public:
  Section(const toml::table& table, std::string name, std::string label, const std::string& file)
      : table_(table), name_(std::move(name)), label_(std::move(label)), file_(file) {}

  // The node for `key`, or nullptr; marks the key as read.
  const toml::node* Get(const char* key) {
    used_.insert(key);
    return table_.get(key);
  }

  // "FILE:LINE:COL: LABEL KEY" for values of this table.
  std::string What(const toml::node& n, const char* key) const {
    return Where(file_, n.source()) + ": " + label_ + key;
  }

  [[noreturn]] void TypeError(const toml::node& n, const char* key, const char* expected) const {
    Fail(What(n, key), std::string("expected ") + expected + ", got " + TypeName(n));
  }

  std::string String(const toml::node& n, const char* key, const char* expected) const {
    if (!n.is_string()) TypeError(n, key, expected);
    return n.as_string()->get();
  }

  std::uint64_t Integer(const toml::node& n, const char* key, std::uint64_t lo,
                        std::uint64_t hi) const {
    if (!n.is_integer()) TypeError(n, key, "an integer");
    const std::int64_t v = n.as_integer()->get();
    if (v < 0 || std::uint64_t(v) < lo || std::uint64_t(v) > hi) {
      Fail(What(n, key), "must be in " + std::to_string(lo) + ".." + std::to_string(hi) + ", got " +
                             std::to_string(v));
    }
    return std::uint64_t(v);
  }

  // An integer, or a decimal string for values above 2^63 - 1.
  std::uint64_t BigInteger(const toml::node& n, const char* key) const {
    if (n.is_string()) {
      return ParseCount(n.as_string()->get(), What(n, key), 0,
                        std::numeric_limits<std::uint64_t>::max());
    }
    return Integer(n, key, 0, std::numeric_limits<std::uint64_t>::max());
  }

  bool Boolean(const toml::node& n, const char* key) const {
    if (!n.is_boolean()) TypeError(n, key, "true or false");
    return n.as_boolean()->get();
  }

  [[noreturn]] void Missing(const char* key) const {
    Fail(Where(file_, table_.source()), label_ + "missing required key '" + key + "'");
  }

  void ReportUnused() const {
    const toml::key* first = nullptr;
    for (auto&& [k, v] : table_) {
      if (used_.count(std::string(k.str())) != 0) continue;
      if (first == nullptr || k.source().begin < first->source().begin) first = &k;
    }
    if (first == nullptr) return;
    std::string valid;
    for (const std::string& k : used_) valid += (valid.empty() ? "" : ", ") + k;
    Fail(Where(file_, first->source()), "unknown key '" + std::string(first->str()) + "' in " +
                                            name_ + " (valid keys: " + valid + ")");
  }

 private:
  const toml::table& table_;
  std::string name_;   // "[processors]"
  std::string label_;  // "processors." or "level 'board' "
  const std::string& file_;
  std::set<std::string> used_;
};

void ReadProcessors(const toml::table& table, const std::string& file, ProcessorConfig* p) {
  Section s(table, "[processors]", "processors.", file);
  if (const toml::node* n = s.Get("count"))
    p->count = std::uint32_t(s.Integer(*n, "count", 1, 1024));
  if (const toml::node* n = s.Get("time_per_sample")) {
    p->time_per_sample =
        ParsePositiveDuration(s.String(*n, "time_per_sample", "a duration string such as \"10ns\""),
                              s.What(*n, "time_per_sample"));
  }
  if (const toml::node* n = s.Get("queue_record_bytes")) {
    if (n->is_string()) {
      p->queue_record_bytes =
          ParseBytes(n->as_string()->get(), s.What(*n, "queue_record_bytes")).count();
    } else {
      p->queue_record_bytes =
          s.Integer(*n, "queue_record_bytes", 0, std::numeric_limits<std::uint64_t>::max());
    }
  }
  if (const toml::node* n = s.Get("prefetch")) p->prefetch = s.Boolean(*n, "prefetch");
  s.ReportUnused();
}

LevelConfig ReadLevel(const toml::table& table, std::size_t index, const std::string& file) {
  const std::string number = "#" + std::to_string(index + 1);
  LevelConfig level;
  {
    Section unnamed(table, "[[level]] " + number, "level " + number + " ", file);
    const toml::node* name_node = unnamed.Get("name");
    if (name_node == nullptr) unnamed.Missing("name");
    level.name = unnamed.String(*name_node, "name", "a string");
    if (!ValidLevelName(level.name)) {
      Fail(unnamed.What(*name_node, "name"),
           "'" + level.name + "' is not a valid level name (use [A-Za-z0-9_-]+)");
    }
  }
  // A level named like a default level starts from it; any other needs every value.
  bool is_default = false;
  for (const LevelConfig& d : DefaultConfig().levels) {
    if (d.name == level.name) {
      level = d;
      is_default = true;
    }
  }
  Section s(table, "[[level]] '" + level.name + "'", "level '" + level.name + "' ", file);
  s.Get("name");
  const auto get = [&](const char* key) {
    const toml::node* n = s.Get(key);
    if (n == nullptr && !is_default && std::string_view(key) != "replacement") s.Missing(key);
    return n;
  };
  if (const toml::node* n = get("capacity")) {
    ParseCapacity(s.String(*n, "capacity", "a string such as \"1 cell\" or \"256MiB\""),
                  s.What(*n, "capacity"), &level);
  }
  if (const toml::node* n = get("bandwidth")) {
    level.bandwidth_below =
        ParseBandwidth(s.String(*n, "bandwidth", "a bandwidth string such as \"1.6GB/s\""),
                       s.What(*n, "bandwidth"));
  }
  if (const toml::node* n = get("latency")) {
    level.latency_below = ParseDuration(
        s.String(*n, "latency", "a duration string such as \"40ns\""), s.What(*n, "latency"));
  }
  if (const toml::node* n = get("replacement")) {
    level.replacement =
        ParseReplacement(s.String(*n, "replacement", "a string"), s.What(*n, "replacement"));
  }
  s.ReportUnused();
  return level;
}

std::vector<LevelConfig> ReadLevels(const toml::node& node, const std::string& file) {
  const std::string what = Where(file, node.source()) + ": level";
  const toml::array* array = node.as_array();
  if (array == nullptr) Fail(what, std::string("expected [[level]] tables, got ") + TypeName(node));
  if (array->empty()) Fail(what, "at least one level is required");
  std::vector<LevelConfig> levels;
  std::map<std::string, std::string> seen;  // name → where
  for (std::size_t i = 0; i < array->size(); ++i) {
    const toml::node& element = *array->get(i);
    const toml::table* table = element.as_table();
    if (table == nullptr) {
      Fail(Where(file, element.source()) + ": level",
           std::string("expected [[level]] tables, got ") + TypeName(element));
    }
    levels.push_back(ReadLevel(*table, i, file));
    const std::string where = Where(file, table->source());
    const auto [it, inserted] = seen.emplace(levels.back().name, where);
    if (!inserted) {
      Fail(where + ": level",
           "duplicate level name '" + levels.back().name + "' (first at " + it->second + ")");
    }
  }
  return levels;
}

ReplayConfig ReadConfig(const toml::table& root, const std::string& file) {
  ReplayConfig config = DefaultConfig();
  Section s(root, "the top-level table", "", file);
  if (const toml::node* n = s.Get("scheduler")) {
    config.scheduler =
        ParseScheduler(s.String(*n, "scheduler", "a string"), s.What(*n, "scheduler"));
  }
  if (const toml::node* n = s.Get("seed")) config.seed = s.BigInteger(*n, "seed");
  if (const toml::node* n = s.Get("granularity")) {
    config.granularity =
        ParseGranularity(s.String(*n, "granularity", "a string"), s.What(*n, "granularity"));
  }
  if (const toml::node* n = s.Get("processors")) {
    if (!n->is_table()) s.TypeError(*n, "processors", "a [processors] table");
    ReadProcessors(*n->as_table(), file, &config.processors);
  }
  if (const toml::node* n = s.Get("level")) config.levels = ReadLevels(*n, file);
  s.ReportUnused();
  ValidateConfig(config, file);
  return config;
}

// ---------------------------------------------------------------------------------------------
// TOML writing.

std::string Quote(std::string_view s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", unsigned(static_cast<unsigned char>(c)));
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

const char* Meaning(const std::string& key) {
  for (const KeyDoc& d : kKeyDocs) {
    if (key == d.key) return d.meaning;
  }
  return "";
}

// "# meaning\n# Default VALUE: source.\nkey = value\n".
void WriteKey(std::ostringstream& out, const std::string& doc_key, const std::string& source_key,
              const std::string& default_value, const char* toml_key, const std::string& value) {
  std::string meaning = Meaning(doc_key);
  if (!meaning.empty()) meaning[0] = char(std::toupper(static_cast<unsigned char>(meaning[0])));
  out << "# " << meaning << ".\n";
  const std::string source = SourceOf(source_key);
  if (!source.empty()) out << "# Default " << default_value << ": " << source << ".\n";
  out << toml_key << " = " << value << "\n";
}

std::string UintToml(std::uint64_t v) {
  if (v <= std::uint64_t(std::numeric_limits<std::int64_t>::max())) return std::to_string(v);
  return Quote(std::to_string(v));
}

const LevelConfig* DefaultLevel(const std::string& name) {
  static const ReplayConfig defaults = DefaultConfig();
  for (const LevelConfig& l : defaults.levels) {
    if (l.name == name) return &l;
  }
  return nullptr;
}

// ---------------------------------------------------------------------------------------------
// Overrides.

LevelConfig* FindLevel(ReplayConfig& config, const std::string& name, const std::string& what) {
  for (LevelConfig& l : config.levels) {
    if (l.name == name) return &l;
  }
  std::string names;
  for (const LevelConfig& l : config.levels) names += (names.empty() ? "" : ", ") + l.name;
  Fail(what, "no level named '" + name + "' (levels: " + names + ")");
}

}  // namespace

// -----------------------------------------------------------------------------------------------

bool operator==(const LevelConfig& a, const LevelConfig& b) {
  return a.name == b.name && a.capacity_unit == b.capacity_unit && a.capacity == b.capacity &&
         a.bandwidth_below == b.bandwidth_below && a.latency_below == b.latency_below &&
         a.replacement == b.replacement;
}
bool operator!=(const LevelConfig& a, const LevelConfig& b) { return !(a == b); }

bool operator==(const ProcessorConfig& a, const ProcessorConfig& b) {
  return a.count == b.count && a.time_per_sample == b.time_per_sample &&
         a.queue_record_bytes == b.queue_record_bytes && a.prefetch == b.prefetch;
}
bool operator!=(const ProcessorConfig& a, const ProcessorConfig& b) { return !(a == b); }

bool operator==(const ReplayConfig& a, const ReplayConfig& b) {
  return a.levels == b.levels && a.processors == b.processors && a.scheduler == b.scheduler &&
         a.seed == b.seed && a.granularity == b.granularity;
}
bool operator!=(const ReplayConfig& a, const ReplayConfig& b) { return !(a == b); }

std::string_view ToString(LevelConfig::Replacement r) {
  switch (r) {
    case LevelConfig::Replacement::kLru:
      return "lru";
    case LevelConfig::Replacement::kFifo:
      return "fifo";
    case LevelConfig::Replacement::kMin:
      return "min";
  }
  return "?";
}

std::string_view ToString(ReplayConfig::Granularity g) {
  return g == ReplayConfig::Granularity::kRay    ? "ray"
         : g == ReplayConfig::Granularity::kNode ? "node"
                                                 : "auto";
}

std::string_view ToString(LevelConfig::CapacityUnit u) {
  return u == LevelConfig::CapacityUnit::kBytes ? "bytes" : "cells";
}

std::string FormatCapacity(const LevelConfig& level) {
  if (level.capacity_unit == LevelConfig::CapacityUnit::kBytes) {
    return Bytes(level.capacity).ToString();
  }
  return std::to_string(level.capacity) + (level.capacity == 1 ? " cell" : " cells");
}

ReplayConfig DefaultConfig() {
  ReplayConfig c;
  LevelConfig cache;
  cache.name = "cache";                                             // on-chip cell cache
  cache.capacity_unit = LevelConfig::CapacityUnit::kCells;          // "cell size set to
  cache.capacity = 1;                                               //  memory size"
  cache.bandwidth_below = Bandwidth::BytesPerSecond(1600'000'000);  // Direct RDRAM PC800
  cache.latency_below = SimTime::Nanoseconds(40);                   // RDRAM row access
  cache.replacement = LevelConfig::Replacement::kLru;               // one cell: any policy
  LevelConfig board;
  board.name = "board";  // board RDRAM
  board.capacity_unit = LevelConfig::CapacityUnit::kBytes;
  board.capacity = std::uint64_t(256) << 20;                       // 256MiB
  board.bandwidth_below = Bandwidth::BytesPerSecond(133'000'000);  // 32-bit 33 MHz PCI
  board.latency_below = SimTime::Microseconds(1);                  // a PCI transaction
  board.replacement = LevelConfig::Replacement::kLru;
  c.levels = {cache, board};
  return c;  // processors, scheduler, seed, granularity: the member defaults in config.h
}

void ValidateConfig(const ReplayConfig& config, const std::string& where) {
  if (config.levels.empty()) Fail(where, "at least one level is required");
  std::set<std::string> names;
  for (const LevelConfig& l : config.levels) {
    if (!ValidLevelName(l.name)) Fail(where, "invalid level name '" + l.name + "'");
    if (!names.insert(l.name).second) Fail(where, "duplicate level name '" + l.name + "'");
    if (l.capacity == 0) Fail(where, "level '" + l.name + "' capacity must be greater than zero");
  }
  if (config.processors.count < 1 || config.processors.count > 1024) {
    Fail(where,
         "processors.count must be in 1..1024, got " + std::to_string(config.processors.count));
  }
  if (config.processors.time_per_sample == SimTime::Zero()) {
    Fail(where, "processors.time_per_sample must be greater than zero");
  }
  ParseScheduler(config.scheduler, where + ": scheduler");
}

ReplayConfig LoadConfigFromString(std::string_view text, const std::string& source) {
  toml::table root;
  try {
    root = toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    Fail(Where(source, e.source()), std::string(e.description()));
  }
  return ReadConfig(root, source);
}

ReplayConfig LoadConfig(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open the replay configuration");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw InputError(path + ": cannot read the replay configuration");
  return LoadConfigFromString(text.str(), path);
}

std::vector<std::string> OverrideKeys(const ReplayConfig& config) {
  std::vector<std::string> keys = {"scheduler",
                                   "seed",
                                   "granularity",
                                   "processors.count",
                                   "processors.time_per_sample",
                                   "processors.queue_record_bytes",
                                   "processors.prefetch"};
  for (const LevelConfig& l : config.levels) {
    for (const char* k : {"capacity", "bandwidth", "latency", "replacement"}) {
      keys.push_back("level." + l.name + "." + k);
    }
  }
  return keys;
}

void ApplyOverride(ReplayConfig& config, const std::string& key, const std::string& value) {
  const std::string what = "override '" + key + "'";
  ReplayConfig c = config;
  ProcessorConfig& p = c.processors;
  if (key == "scheduler") {
    c.scheduler = ParseScheduler(Trim(value), what);
  } else if (key == "seed") {
    c.seed = ParseCount(value, what, 0, std::numeric_limits<std::uint64_t>::max());
  } else if (key == "granularity") {
    c.granularity = ParseGranularity(Trim(value), what);
  } else if (key == "processors.count") {
    p.count = std::uint32_t(ParseCount(value, what, 1, 1024));
  } else if (key == "processors.time_per_sample") {
    p.time_per_sample = ParsePositiveDuration(value, what);
  } else if (key == "processors.queue_record_bytes") {
    const std::string_view t = Trim(value);
    const bool digits = !t.empty() && std::all_of(t.begin(), t.end(),
                                                  [](char ch) { return ch >= '0' && ch <= '9'; });
    p.queue_record_bytes = digits
                               ? ParseCount(t, what, 0, std::numeric_limits<std::uint64_t>::max())
                               : ParseBytes(value, what).count();
  } else if (key == "processors.prefetch") {
    p.prefetch = ParseBool(value, what);
  } else if (key.rfind("level.", 0) == 0 && key.find('.', 6) != std::string::npos) {
    const std::size_t dot = key.find('.', 6);
    const std::string field = key.substr(dot + 1);
    if (field == "capacity" || field == "bandwidth" || field == "latency" ||
        field == "replacement") {
      LevelConfig* l = FindLevel(c, key.substr(6, dot - 6), what);
      if (field == "capacity") ParseCapacity(value, what, l);
      if (field == "bandwidth") l->bandwidth_below = ParseBandwidth(value, what);
      if (field == "latency") l->latency_below = ParseDuration(value, what);
      if (field == "replacement") l->replacement = ParseReplacement(Trim(value), what);
    } else {
      Fail(what, "unknown level key '" + field +
                     "' (expected capacity, bandwidth, latency or replacement)");
    }
  } else {
    std::string keys;
    for (const std::string& k : OverrideKeys(config)) keys += (keys.empty() ? "" : ", ") + k;
    Fail(what, "unknown key (valid keys: " + keys + ")");
  }
  ValidateConfig(c, what);
  config = std::move(c);
}

std::string ToToml(const ReplayConfig& config) {
  const ReplayConfig d = DefaultConfig();
  const ProcessorConfig& p = config.processors;
  std::ostringstream out;
  out << "# raycell replay configuration (DESIGN.md §2).\n"
         "# Defaults model the GI-Cube board on the slides: a PCI board whose block processors\n"
         "# are backed by Direct RDRAM, with host memory reached over PCI.\n\n";
  WriteKey(out, "scheduler", "scheduler", Quote(d.scheduler), "scheduler", Quote(config.scheduler));
  WriteKey(out, "seed", "seed", UintToml(d.seed), "seed", UintToml(config.seed));
  WriteKey(out, "granularity", "granularity", Quote(ToString(d.granularity)), "granularity",
           Quote(ToString(config.granularity)));
  out << "\n[processors]\n";
  const auto pkey = [&](const char* k, const std::string& def, const std::string& value) {
    const std::string full = std::string("processors.") + k;
    WriteKey(out, full, full, def, k, value);
  };
  pkey("count", std::to_string(d.processors.count), std::to_string(p.count));
  pkey("time_per_sample", Quote(FormatDuration(d.processors.time_per_sample)),
       Quote(FormatDuration(p.time_per_sample)));
  // Above 2^63 - 1 a TOML integer cannot hold it: written as a size string instead.
  const auto record_bytes = [](std::uint64_t v) {
    return v <= std::uint64_t(std::numeric_limits<std::int64_t>::max())
               ? std::to_string(v)
               : Quote(Bytes(v).ToString());
  };
  pkey("queue_record_bytes", record_bytes(d.processors.queue_record_bytes),
       record_bytes(p.queue_record_bytes));
  pkey("prefetch", d.processors.prefetch ? "true" : "false", p.prefetch ? "true" : "false");
  out << "\n# Memory levels, nearest (on-chip cache) first; the level below the last is host\n"
         "# memory, unlimited. [[level]] tables in a file replace the default levels entirely.\n";
  for (const LevelConfig& l : config.levels) {
    const LevelConfig* dl = DefaultLevel(l.name);
    const std::string prefix = dl != nullptr ? "level." + l.name : std::string("level.*");
    out << "\n[[level]]\n";
    const std::string about = SourceOf("level." + l.name);
    if (!about.empty()) out << "# Default level: " << about << ".\n";
    out << "name = " << Quote(l.name) << "\n";
    const auto lkey = [&](const char* k, const std::string& def, const std::string& value) {
      WriteKey(out, std::string("level.*.") + k, prefix + "." + k, def, k, value);
    };
    const LevelConfig& ref = dl != nullptr ? *dl : l;
    lkey("capacity", Quote(FormatCapacity(ref)), Quote(FormatCapacity(l)));
    lkey("bandwidth", Quote(ref.bandwidth_below.ToString()), Quote(l.bandwidth_below.ToString()));
    lkey("latency", Quote(FormatDuration(ref.latency_below)),
         Quote(FormatDuration(l.latency_below)));
    lkey("replacement", Quote(ToString(ref.replacement)), Quote(ToString(l.replacement)));
  }
  return out.str();
}

std::string DefaultsHelp() {
  const ReplayConfig d = DefaultConfig();
  std::vector<std::pair<std::string, std::string>> rows = {
      {"scheduler", d.scheduler},
      {"seed", std::to_string(d.seed)},
      {"granularity", std::string(ToString(d.granularity))},
      {"processors.count", std::to_string(d.processors.count)},
      {"processors.time_per_sample", FormatDuration(d.processors.time_per_sample)},
      {"processors.queue_record_bytes", std::to_string(d.processors.queue_record_bytes)},
      {"processors.prefetch", d.processors.prefetch ? "true" : "false"}};
  for (const LevelConfig& l : d.levels) {
    const std::string k = "level." + l.name + ".";
    rows.push_back({k + "capacity", FormatCapacity(l)});
    rows.push_back({k + "bandwidth", l.bandwidth_below.ToString()});
    rows.push_back({k + "latency", FormatDuration(l.latency_below)});
    rows.push_back({k + "replacement", std::string(ToString(l.replacement))});
  }
  std::size_t width = 0;
  for (const auto& [k, v] : rows) width = std::max(width, k.size() + 3 + v.size());
  std::string out;
  for (const auto& [k, v] : rows) {
    std::string line = "  " + k + " = " + v;
    line.resize(2 + width, ' ');
    out += line + "  (" + SourceOf(k) + ")\n";
  }
  return out;
}

}  // namespace raycell

namespace raycell {

ReplayConfig::Granularity EffectiveGranularity(const ReplayConfig& config) {
  if (config.granularity != ReplayConfig::Granularity::kAuto) return config.granularity;
  return config.processors.count == 1 ? ReplayConfig::Granularity::kNode
                                      : ReplayConfig::Granularity::kRay;
}

}  // namespace raycell
