#include "replay/config.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "base/check.h"
#include "base/file.h"
#include "base/parse.h"
#include "base/toml_read.h"
#include "replay/replacement.h"
#include "scheduling/scheduler.h"
#include "traces/subdivision.h"

namespace raycell {
namespace {

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

ReplayConfig::Granularity ParseGranularity(std::string_view text, const std::string& what) {
  if (text == "ray") return ReplayConfig::Granularity::kRay;
  if (text == "node") return ReplayConfig::Granularity::kNode;
  if (text == "auto") return ReplayConfig::Granularity::kAuto;
  Fail(what, "unknown granularity '" + std::string(text) + "' (expected ray, node or auto)");
}

MemoryConfig::AcrossFrames ParseAcrossFrames(std::string_view text, const std::string& what) {
  if (text == "warm") return MemoryConfig::AcrossFrames::kWarm;
  if (text == "cold") return MemoryConfig::AcrossFrames::kCold;
  Fail(what, "unknown memory.across_frames '" + std::string(text) + "' (expected warm or cold)");
}

const ReplacementEntry* ParseReplacement(std::string_view text, const std::string& what) {
  std::vector<std::string> names;
  for (const ReplacementEntry& e : ReplacementRegistry()) {
    if (text == e.name) return &e;
    names.push_back(e.name);
  }
  Fail(what, "unknown replacement '" + std::string(text) + "' (expected " + JoinOr(names) + ")");
}

// "lru | fifo | min (Belady's MIN, a bound)": the registry's names and notes.
std::string ReplacementMeaning() {
  std::vector<std::string> names;
  std::string notes;
  for (const ReplacementEntry& e : ReplacementRegistry()) {
    names.push_back(e.name);
    if (e.note != nullptr) notes += std::string(" (") + e.note + ")";
  }
  return Join(names, " | ") + notes;
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

// ---------------------------------------------------------------------------------------------
// The keys: one descriptor each. Everything the TOML reader and writer, the --set/--vary
// overrides, OverrideKeys and DefaultsHelp know of a key is here; a new key is one entry.

// The TOML value a key takes. Strings go to the key's parser as they are; integers (range
// checked) and booleans go to the same parser as text, so a file and an override parse alike.
enum class TomlKind { kString, kInteger, kBoolean, kIntegerOrString };

template <typename T>
struct Key {
  std::string name;      // the override key; the TOML key is its part after the last '.'
  std::string meaning;   // one line, for the TOML comments
  TomlKind kind;         //
  const char* expected;  // for a value of the wrong TOML type
  std::uint64_t lo, hi;  // integers: the valid range
  void (*parse)(std::string_view text, const std::string& what, T& target);
  std::string (*text)(const T& target);  // as overrides take it and --help prints it
  // The default, as text for `parse`, and where it comes from; "" for level keys, whose
  // defaults are per level (kDefaultLevels).
  const char* default_value;
  const char* source;
};

constexpr std::uint64_t kMax64 = std::numeric_limits<std::uint64_t>::max();

// Keys of the top-level table and of [processors] ("processors." keys), in file order.
const std::vector<Key<ReplayConfig>>& ConfigKeys() {
  static const std::vector<Key<ReplayConfig>> keys = {
      {"scheduler", "cell scheduler: " + SchedulerNameList(" | "), TomlKind::kString, "a string", 0,
       0,
       [](std::string_view t, const std::string& what, ReplayConfig& c) {
         c.scheduler = &SchedulerByName(Trim(t), what);
       },
       [](const ReplayConfig& c) { return std::string(c.scheduler_name()); }, "celltree",
       "the paper's Cell Tree scheduler"},
      {"seed",
       "seed of the schedulers whose choices depend on it (" + SeededSchedulerList(", ") + ")",
       TomlKind::kIntegerOrString, "an integer", 0, kMax64,
       [](std::string_view t, const std::string& what, ReplayConfig& c) {
         c.seed = ParseCount(t, what, 0, kMax64);
       },
       [](const ReplayConfig& c) { return std::to_string(c.seed); }, "1",
       "any fixed value keeps a replay deterministic"},
      {"granularity",
       "ray: per ray segment (exact) | node: per Cell Tree node (aggregated, fast) | auto: node "
       "with one processor (where it is exact), ray otherwise",
       TomlKind::kString, "a string", 0, 0,
       [](std::string_view t, const std::string& what, ReplayConfig& c) {
         c.granularity = ParseGranularity(Trim(t), what);
       },
       [](const ReplayConfig& c) { return std::string(ToString(c.granularity)); }, "auto",
       "exact and as fast as possible"},
      {"processors.count", "number of block processors, 1.." + std::to_string(kMaxProcessors),
       TomlKind::kInteger, "an integer", 1, kMaxProcessors,
       [](std::string_view t, const std::string& what, ReplayConfig& c) {
         c.processors.count = std::uint32_t(ParseCount(t, what, 1, kMaxProcessors));
       },
       [](const ReplayConfig& c) { return std::to_string(c.processors.count); }, "1",
       "one block processor, the paper's case"},
      {"processors.time_per_sample", "time a block processor takes per sample", TomlKind::kString,
       "a duration string such as \"10ns\"", 0, 0,
       [](std::string_view t, const std::string& what, ReplayConfig& c) {
         c.processors.time_per_sample = ParsePositiveDuration(t, what);
       },
       [](const ReplayConfig& c) { return FormatDuration(c.processors.time_per_sample); }, "10ns",
       "one sample per cycle of a 100 MHz pipeline, the Cube-5/GI-Cube design point"},
      {"processors.queue_record_bytes", "bytes per queued ray (an integer or a size, \"32B\")",
       TomlKind::kIntegerOrString, "an integer", 0, kMax64,
       [](std::string_view t, const std::string& what, ReplayConfig& c) {
         const std::string_view v = Trim(t);
         const bool digits = !v.empty() && std::all_of(v.begin(), v.end(), [](char ch) {
           return ch >= '0' && ch <= '9';
         });
         c.processors.queue_record_bytes =
             digits ? ParseCount(v, what, 0, kMax64) : ParseBytes(t, what).count();
       },
       [](const ReplayConfig& c) { return std::to_string(c.processors.queue_record_bytes); }, "32",
       "position, direction, colour/opacity, cell-tree node"},
      {"processors.prefetch",
       "fetch the next scheduled cell while the current one is worked (double buffering)",
       TomlKind::kBoolean, "true or false", 0, 0,
       [](std::string_view t, const std::string& what, ReplayConfig& c) {
         c.processors.prefetch = ParseBool(t, what);
       },
       [](const ReplayConfig& c) { return std::string(c.processors.prefetch ? "true" : "false"); },
       "false", "no double buffering, the paper's model"},
      {"memory.across_frames",
       "warm: every level keeps its cells from one frame to the next (a static volume stays on "
       "the board; a sequence of volumes keeps nothing) | cold: every frame starts with empty "
       "levels",
       TomlKind::kString, "a string", 0, 0,
       [](std::string_view t, const std::string& what, ReplayConfig& c) {
         c.memory.across_frames = ParseAcrossFrames(Trim(t), what);
       },
       [](const ReplayConfig& c) { return std::string(ToString(c.memory.across_frames)); }, "warm",
       "the board's memory is not cleared between frames; cold is the paper's comparison"},
  };
  return keys;
}

// Keys of a [[level]] table besides its name; override keys are level.NAME.KEY.
const std::vector<Key<LevelConfig>>& LevelKeys() {
  static const std::vector<Key<LevelConfig>> keys = {
      {"capacity", "\"N cell\" / \"N cells\", or a size such as \"256MiB\"", TomlKind::kString,
       "a string such as \"1 cell\" or \"256MiB\"", 0, 0,
       [](std::string_view t, const std::string& what, LevelConfig& l) {
         ParseCapacity(t, what, &l);
       },
       [](const LevelConfig& l) { return FormatCapacity(l); }, "", ""},
      {"bandwidth", "to the level below (below the last: host memory); \"unlimited\" ok",
       TomlKind::kString, "a bandwidth string such as \"1.6GB/s\"", 0, 0,
       [](std::string_view t, const std::string& what, LevelConfig& l) {
         l.bandwidth_below = ParseBandwidth(t, what);
       },
       [](const LevelConfig& l) { return l.bandwidth_below.ToString(); }, "", ""},
      {"latency", "to the level below", TomlKind::kString, "a duration string such as \"40ns\"", 0,
       0,
       [](std::string_view t, const std::string& what, LevelConfig& l) {
         l.latency_below = ParseDuration(t, what);
       },
       [](const LevelConfig& l) { return FormatDuration(l.latency_below); }, "", ""},
      {"replacement", ReplacementMeaning(), TomlKind::kString, "a string", 0, 0,
       [](std::string_view t, const std::string& what, LevelConfig& l) {
         l.replacement = ParseReplacement(Trim(t), what);
       },
       [](const LevelConfig& l) { return std::string(l.replacement->name); }, "", ""},
      {"cells",
       "what the level stores and moves: same (the replay's cells), or a SPEC of a regroupable "
       "capture's fine grid (3x3x3, kd:27:footprint, octree:BYTES...) whose cells are unions of "
       "the replay's (shared levels only)",
       TomlKind::kString, "a string", 0, 0,
       [](std::string_view t, const std::string& what, LevelConfig& l) {
         l.cells = std::string(Trim(t));
         if (l.cells == "same") l.cells.clear();
         if (l.cells.empty()) return;
         const SubdivisionSpec spec = ParseSubdivisionSpec(l.cells, what);
         if (spec.per_frame()) {
           Fail(what, "'" + l.cells +
                          "': a memory level's cells stay the same over the frames; "
                          "dynamic subdivisions are for --cells");
         }
         l.cells = spec.ToString();
       },
       [](const LevelConfig& l) { return l.cells.empty() ? std::string("same") : l.cells; }, "",
       ""},
  };
  return keys;
}

// The default levels: each value, as text for its key's parser, and where it comes from.
struct DefaultLevel {
  struct Value {
    const char* key;  // a LevelKeys() name
    const char* value;
    const char* source;
  };
  const char* name;
  const char* about;
  Value values[5];  // one per LevelKeys() entry, in any order

  // The value of `key`; every key has one (a CHECK).
  const Value& Of(const std::string& key) const {
    for (const Value& v : values) {
      if (key == v.key) return v;
    }
    RAYCELL_CHECK(false);  // every default level gives a value of every key
    return values[0];
  }
};
constexpr DefaultLevel kDefaultLevels[] = {
    {"cache",
     "the block processor's on-chip cell cache",
     {{"capacity", "1 cell", "\"cell size set to memory size\", the paper's case"},
      {"bandwidth", "1.6GB/s", "one Direct RDRAM PC800 channel, 2 bytes x 800 MT/s"},
      {"latency", "40ns", "RDRAM row access"},
      {"replacement", "lru", "with one cell every policy behaves alike"},
      {"cells", "same", "the replay's cells"}}},
    {"board",
     "board memory (RDRAM) of the PCI board",
     {{"capacity", "256MiB", "RDRAM board memory of a PCI board of the period"},
      {"bandwidth", "133MB/s", "32-bit 33 MHz PCI to host memory"},
      {"latency", "1us", "a PCI transaction"},
      {"replacement", "lru", "LRU, the usual hardware policy"},
      {"cells", "same", "the replay's cells, as on the slides"}}},
};

const DefaultLevel* DefaultLevelOf(const std::string& name) {
  for (const DefaultLevel& d : kDefaultLevels) {
    if (name == d.name) return &d;
  }
  return nullptr;
}

// The defaults of the key tables, parsed once: DefaultConfig() is a copy.
const ReplayConfig& Defaults() {
  static const ReplayConfig defaults = [] {
    ReplayConfig c;
    for (const Key<ReplayConfig>& k : ConfigKeys()) {
      k.parse(k.default_value, "default " + k.name, c);
    }
    for (const DefaultLevel& d : kDefaultLevels) {
      LevelConfig level;
      level.name = d.name;
      for (const Key<LevelConfig>& k : LevelKeys()) {
        k.parse(d.Of(k.name).value, "default level." + level.name + "." + k.name, level);
      }
      c.levels.push_back(level);
    }
    return c;
  }();
  return defaults;
}

// The part of a dotted key after its last '.': the key inside its TOML table.
std::string TableKey(const std::string& name) { return name.substr(name.rfind('.') + 1); }
// The table a key lives in: "" (the top level), "processors" or "memory".
std::string SectionOf(const std::string& name) {
  const std::size_t dot = name.find('.');
  return dot == std::string::npos ? std::string() : name.substr(0, dot);
}

// A value as TOML writes it: booleans and integers that fit a TOML integer bare, the rest as
// strings.
std::string TomlLiteral(TomlKind kind, const std::string& text) {
  if (kind == TomlKind::kBoolean) return text;
  if (kind != TomlKind::kString) {
    std::uint64_t v = 0;
    if (TryParseUint(text, &v) && v <= std::uint64_t(std::numeric_limits<std::int64_t>::max())) {
      return text;
    }
  }
  return Quote(text);
}

// ---------------------------------------------------------------------------------------------
// TOML reading with pbrt-style ReportUnused.

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
    return TomlWhere(file_, n.source()) + ": " + label_ + key;
  }

  [[noreturn]] void TypeError(const toml::node& n, const char* key, const char* expected) const {
    Fail(What(n, key), std::string("expected ") + expected + ", got " + TomlTypeName(n));
  }

  std::string String(const toml::node& n, const char* key, const char* expected) const {
    if (!n.is_string()) TypeError(n, key, expected);
    return n.as_string()->get();
  }

  // Reads `key` (its part after the last '.') into `target` if the table has it; true if so.
  template <typename T>
  bool Read(const Key<T>& key, T& target) {
    const std::string k = TableKey(key.name);
    const toml::node* n = Get(k.c_str());
    if (n == nullptr) return false;
    const std::string what = What(*n, k.c_str());
    std::string text;
    if (n->is_string() && key.kind != TomlKind::kInteger && key.kind != TomlKind::kBoolean) {
      text = n->as_string()->get();
    } else if (n->is_integer() &&
               (key.kind == TomlKind::kInteger || key.kind == TomlKind::kIntegerOrString)) {
      const std::int64_t v = n->as_integer()->get();
      if (v < 0 || std::uint64_t(v) < key.lo || std::uint64_t(v) > key.hi) {
        Fail(what, "must be in " + std::to_string(key.lo) + ".." + std::to_string(key.hi) +
                       ", got " + std::to_string(v));
      }
      text = std::to_string(v);
    } else if (n->is_boolean() && key.kind == TomlKind::kBoolean) {
      text = n->as_boolean()->get() ? "true" : "false";
    } else {
      TypeError(*n, k.c_str(), key.expected);
    }
    key.parse(text, what, target);
    return true;
  }

  [[noreturn]] void Missing(const char* key) const {
    Fail(TomlWhere(file_, table_.source()), label_ + "missing required key '" + key + "'");
  }

  void ReportUnused() const {
    const toml::key* first = FirstUnusedKey(table_, used_);
    if (first == nullptr) return;
    Fail(TomlWhere(file_, first->source()), "unknown key '" + std::string(first->str()) + "' in " +
                                                name_ + " (valid keys: " + JoinKeys(used_) + ")");
  }

 private:
  const toml::table& table_;
  std::string name_;   // "[processors]"
  std::string label_;  // "processors." or "level 'board' "
  const std::string& file_;
  std::set<std::string> used_;
};

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
  for (const LevelConfig& d : Defaults().levels) {
    if (d.name == level.name) {
      level = d;
      is_default = true;
    }
  }
  Section s(table, "[[level]] '" + level.name + "'", "level '" + level.name + "' ", file);
  s.Get("name");
  for (const Key<LevelConfig>& key : LevelKeys()) {
    // A level not named like a default one needs every value but its replacement and cells.
    if (!s.Read(key, level) && !is_default && key.name != "replacement" && key.name != "cells") {
      s.Missing(key.name.c_str());
    }
  }
  s.ReportUnused();
  return level;
}

std::vector<LevelConfig> ReadLevels(const toml::node& node, const std::string& file) {
  const std::string what = TomlWhere(file, node.source()) + ": level";
  const toml::array* array = node.as_array();
  if (array == nullptr)
    Fail(what, std::string("expected [[level]] tables, got ") + TomlTypeName(node));
  if (array->empty()) Fail(what, "at least one level is required");
  std::vector<LevelConfig> levels;
  std::map<std::string, std::string> seen;  // name → where
  for (std::size_t i = 0; i < array->size(); ++i) {
    const toml::node& element = *array->get(i);
    const toml::table* table = element.as_table();
    if (table == nullptr) {
      Fail(TomlWhere(file, element.source()) + ": level",
           std::string("expected [[level]] tables, got ") + TomlTypeName(element));
    }
    levels.push_back(ReadLevel(*table, i, file));
    const std::string where = TomlWhere(file, table->source());
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
  std::vector<std::string> sections;  // in the key table's order
  for (const Key<ReplayConfig>& key : ConfigKeys()) {
    const std::string section = SectionOf(key.name);
    if (section.empty()) {
      s.Read(key, config);
    } else if (std::find(sections.begin(), sections.end(), section) == sections.end()) {
      sections.push_back(section);
    }
  }
  for (const std::string& section : sections) {
    const toml::node* n = s.Get(section.c_str());
    if (n == nullptr) continue;
    if (!n->is_table()) s.TypeError(*n, section.c_str(), ("a [" + section + "] table").c_str());
    Section p(*n->as_table(), "[" + section + "]", section + ".", file);
    for (const Key<ReplayConfig>& key : ConfigKeys()) {
      if (SectionOf(key.name) == section) p.Read(key, config);
    }
    p.ReportUnused();
  }
  if (const toml::node* n = s.Get("level")) config.levels = ReadLevels(*n, file);
  s.ReportUnused();
  ValidateConfig(config, file);
  return config;
}

// ---------------------------------------------------------------------------------------------
// TOML writing.

// "# Meaning.\n# Default VALUE: source.\nkey = value\n" (no Default line without a source).
void WriteKey(std::ostringstream& out, std::string meaning, const std::string& source,
              const std::string& default_value, const std::string& toml_key,
              const std::string& value) {
  if (!meaning.empty()) meaning[0] = char(std::toupper(static_cast<unsigned char>(meaning[0])));
  out << "# " << meaning << ".\n";
  if (!source.empty()) out << "# Default " << default_value << ": " << source << ".\n";
  out << toml_key << " = " << value << "\n";
}

const LevelConfig* DefaultLevelConfig(const std::string& name) {
  for (const LevelConfig& l : Defaults().levels) {
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
         a.replacement == b.replacement && a.cells == b.cells;
}
bool operator!=(const LevelConfig& a, const LevelConfig& b) { return !(a == b); }

bool operator==(const ProcessorConfig& a, const ProcessorConfig& b) {
  return a.count == b.count && a.time_per_sample == b.time_per_sample &&
         a.queue_record_bytes == b.queue_record_bytes && a.prefetch == b.prefetch;
}
bool operator!=(const ProcessorConfig& a, const ProcessorConfig& b) { return !(a == b); }

bool operator==(const ReplayConfig& a, const ReplayConfig& b) {
  return a.levels == b.levels && a.processors == b.processors && a.memory == b.memory &&
         a.scheduler == b.scheduler && a.seed == b.seed && a.granularity == b.granularity;
}
bool operator!=(const ReplayConfig& a, const ReplayConfig& b) { return !(a == b); }

std::string_view ToString(ReplayConfig::Granularity g) {
  return g == ReplayConfig::Granularity::kRay    ? "ray"
         : g == ReplayConfig::Granularity::kNode ? "node"
                                                 : "auto";
}

std::string_view ToString(MemoryConfig::AcrossFrames a) {
  return a == MemoryConfig::AcrossFrames::kWarm ? "warm" : "cold";
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

ReplayConfig DefaultConfig() { return Defaults(); }
void ValidateConfig(const ReplayConfig& config, const std::string& where) {
  if (config.levels.empty()) Fail(where, "at least one level is required");
  std::set<std::string> names;
  for (const LevelConfig& l : config.levels) {
    if (!ValidLevelName(l.name)) Fail(where, "invalid level name '" + l.name + "'");
    if (!names.insert(l.name).second) Fail(where, "duplicate level name '" + l.name + "'");
    if (l.capacity == 0) Fail(where, "level '" + l.name + "' capacity must be greater than zero");
  }
  if (!config.levels[0].cells.empty()) {
    Fail(where, "level '" + config.levels[0].name + "' cells = '" + config.levels[0].cells +
                    "': the first level holds the cells the processors work; only a shared "
                    "level may hold coarser ones");
  }
  if (config.processors.count < 1 || config.processors.count > kMaxProcessors) {
    Fail(where, "processors.count must be in 1.." + std::to_string(kMaxProcessors) + ", got " +
                    std::to_string(config.processors.count));
  }
  if (config.processors.time_per_sample == SimTime::Zero()) {
    Fail(where, "processors.time_per_sample must be greater than zero");
  }
  if (config.scheduler == nullptr) Fail(where, "no scheduler");
}

ReplayConfig LoadConfigFromString(std::string_view text, const std::string& source) {
  toml::table root;
  try {
    root = toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    Fail(TomlWhere(source, e.source()), std::string(e.description()));
  }
  return ReadConfig(root, source);
}

ReplayConfig LoadConfig(const std::string& path) {
  std::string text;  // through base/file.h: the model does no file I/O of its own
  if (!ReadFile(path, &text)) throw InputError(path + ": cannot open the replay configuration");
  return LoadConfigFromString(text, path);
}

std::vector<std::string> OverrideKeys(const ReplayConfig& config) {
  std::vector<std::string> keys;
  for (const Key<ReplayConfig>& k : ConfigKeys()) keys.push_back(k.name);
  for (const LevelConfig& l : config.levels) {
    for (const Key<LevelConfig>& k : LevelKeys()) keys.push_back("level." + l.name + "." + k.name);
  }
  return keys;
}

void ApplyOverride(ReplayConfig& config, const std::string& key, const std::string& value,
                   const std::string& what_given) {
  const std::string what = what_given.empty() ? "override '" + key + "'" : what_given;
  ReplayConfig c = config;
  const auto top = std::find_if(ConfigKeys().begin(), ConfigKeys().end(),
                                [&](const Key<ReplayConfig>& k) { return k.name == key; });
  if (top != ConfigKeys().end()) {
    top->parse(value, what, c);
  } else if (key.rfind("level.", 0) == 0 && key.find('.', 6) != std::string::npos) {
    const std::size_t dot = key.find('.', 6);
    const std::string field = key.substr(dot + 1);
    const auto lk = std::find_if(LevelKeys().begin(), LevelKeys().end(),
                                 [&](const Key<LevelConfig>& k) { return k.name == field; });
    if (lk == LevelKeys().end()) {
      std::vector<std::string> fields;
      for (const Key<LevelConfig>& k : LevelKeys()) fields.push_back(k.name);
      Fail(what, "unknown level key '" + field + "' (expected " + JoinOr(fields) + ")");
    }
    lk->parse(value, what, *FindLevel(c, key.substr(6, dot - 6), what));
  } else {
    std::string keys;
    for (const std::string& k : OverrideKeys(config)) keys += (keys.empty() ? "" : ", ") + k;
    Fail(what, "unknown key (valid keys: " + keys + ")");
  }
  ValidateConfig(c, what);
  config = std::move(c);
}

std::string ToToml(const ReplayConfig& config) {
  const ReplayConfig& d = Defaults();
  std::ostringstream out;
  out << "# raycell replay configuration (docs/design.md §2).\n"
         "# Defaults model the GI-Cube board on the slides: a PCI board whose block processors\n"
         "# are backed by Direct RDRAM, with host memory reached over PCI.\n\n";
  std::string section;  // the table being written
  for (const Key<ReplayConfig>& k : ConfigKeys()) {
    if (SectionOf(k.name) != section) {
      section = SectionOf(k.name);
      out << "\n[" << section << "]\n";
    }
    WriteKey(out, k.meaning, k.source, TomlLiteral(k.kind, k.text(d)), TableKey(k.name),
             TomlLiteral(k.kind, k.text(config)));
  }
  out << "\n# Memory levels, nearest (on-chip cache) first; the level below the last is host\n"
         "# memory, unlimited. [[level]] tables in a file replace the default levels entirely.\n";
  for (const LevelConfig& l : config.levels) {
    const LevelConfig* dl = DefaultLevelConfig(l.name);
    const DefaultLevel* doc = DefaultLevelOf(l.name);
    out << "\n[[level]]\n";
    if (doc != nullptr) out << "# Default level: " << doc->about << ".\n";
    out << "name = " << Quote(l.name) << "\n";
    const LevelConfig& ref = dl != nullptr ? *dl : l;
    for (const Key<LevelConfig>& k : LevelKeys()) {
      WriteKey(out, k.meaning, doc != nullptr ? doc->Of(k.name).source : "",
               TomlLiteral(k.kind, k.text(ref)), k.name, TomlLiteral(k.kind, k.text(l)));
    }
  }
  return out.str();
}

std::string DefaultsHelp() {
  const ReplayConfig& d = Defaults();
  std::vector<std::array<std::string, 3>> rows;  // key, value, source
  for (const Key<ReplayConfig>& k : ConfigKeys()) rows.push_back({k.name, k.text(d), k.source});
  for (const LevelConfig& l : d.levels) {
    const DefaultLevel* doc = DefaultLevelOf(l.name);
    RAYCELL_CHECK(doc != nullptr);
    for (const Key<LevelConfig>& k : LevelKeys()) {
      rows.push_back({"level." + l.name + "." + k.name, k.text(l), doc->Of(k.name).source});
    }
  }
  std::size_t width = 0;
  for (const auto& [k, v, source] : rows) width = std::max(width, k.size() + 3 + v.size());
  std::string out;
  for (const auto& [k, v, source] : rows) {
    std::string line = "  " + k + " = " + v;
    line.resize(2 + width, ' ');
    out += line + "  (" + source + ")\n";
  }
  return out;
}

}  // namespace raycell

namespace raycell {

const char* ReplayConfig::scheduler_name() const { return scheduler ? scheduler->name : "none"; }

ReplayConfig::Granularity EffectiveGranularity(const ReplayConfig& config) {
  if (config.granularity != ReplayConfig::Granularity::kAuto) return config.granularity;
  return config.processors.count == 1 ? ReplayConfig::Granularity::kNode
                                      : ReplayConfig::Granularity::kRay;
}

}  // namespace raycell
