// The printer side of statistics (CONTRIBUTING.md, ChampSim): components own plain stats
// structs; a caller turns them into a StatsTable (an ordered list of named values) and
// prints it as text, JSON or CSV. Formatting is deterministic: integers in decimal, reals
// in the shortest form that reads back to the same double, or with fixed decimals where the
// table says so.
#pragma once

#include <cstdint>
#include <ostream>
#include <string>
#include <variant>
#include <vector>

#include "base/format.h"  // JsonQuote, CsvField: the printers' quoting

namespace raycell {

class StatsTable;

// A real printed with a fixed number of decimals ("0.0404"), a number in JSON.
struct FixedReal {
  double value = 0;
  int decimals = 0;
};

// No value: null in JSON, an empty CSV field, "-" in text.
using NoValue = std::monostate;

// A list of tables (one per memory level, say): an array of objects in JSON. In text and CSV
// it is flattened, each table giving one column per entry after its first, named
// FIRST_KEY, where FIRST is the first entry's value (the table's name): a list
// [{name: cache, bytes: 7}] under any key gives the column cache_bytes = 7.
using StatTables = std::vector<StatsTable>;

using StatValue = std::variant<NoValue, std::uint64_t, std::int64_t, double, FixedReal, bool,
                               std::string, StatTables>;

struct StatEntry {
  std::string key;
  StatValue value;
};

class StatsTable {
 public:
  // Each key at most once (CHECK); entries keep the order they were added in.
  StatsTable& AddCount(std::string key, std::uint64_t value);
  StatsTable& AddInt(std::string key, std::int64_t value);
  StatsTable& AddReal(std::string key, double value);
  StatsTable& AddFixed(std::string key, double value, int decimals);
  StatsTable& AddBool(std::string key, bool value);
  StatsTable& AddText(std::string key, std::string value);
  StatsTable& AddNone(std::string key);
  StatsTable& AddTables(std::string key, StatTables tables);

  const std::vector<StatEntry>& entries() const { return entries_; }
  std::size_t size() const { return entries_.size(); }
  // The entry named `key`, or nullptr.
  const StatValue* Find(const std::string& key) const;
  // The value of `key`, which must exist and hold that type (CHECK).
  std::uint64_t Count(const std::string& key) const;
  double Real(const std::string& key) const;  // a real or a fixed real

  // The table with lists of tables flattened into columns, as text and CSV print it.
  StatsTable Flattened() const;

 private:
  StatsTable& Add(std::string key, StatValue value);
  std::vector<StatEntry> entries_;
};

// One value as the printers write it, unquoted: "42", "-3", "0.1", "0.0404", "1e+300", "nan",
// "inf", "true", text; "" for no value. CHECK-fails on a list of tables.
std::string FormatValue(const StatValue& value);

// "key    value" lines, keys padded to the longest key; no value prints as "-".
void PrintText(const StatsTable& table, std::ostream& os);
// A JSON object, one key per line in table order; non-finite reals and no value print as
// null.
void PrintJson(const StatsTable& table, std::ostream& os);
// The same object on one line without spaces or a final newline: {"a":1,"b":[{"c":2}]}.
void PrintJsonLine(const StatsTable& table, std::ostream& os);
// Two lines: the keys, then the values (RFC 4180 quoting). PrintCsvHeader and PrintCsvRow
// print one each, for sweeps that print many tables with the same keys.
void PrintCsv(const StatsTable& table, std::ostream& os);
void PrintCsvHeader(const StatsTable& table, std::ostream& os);
void PrintCsvRow(const StatsTable& table, std::ostream& os);

// The same printers into a string.
std::string ToText(const StatsTable& table);
std::string ToJson(const StatsTable& table);
std::string ToJsonLine(const StatsTable& table);
std::string ToCsv(const StatsTable& table);
std::string ToCsvHeader(const StatsTable& table);
std::string ToCsvRow(const StatsTable& table);

}  // namespace raycell
