// The printer side of statistics (CONVENTIONS.md, ChampSim): components own plain stats
// structs; a caller turns them into a StatsTable (an ordered list of named values) and
// prints it as text, JSON or CSV. Formatting is deterministic: integers in decimal, reals
// in the shortest form that reads back to the same double.
#pragma once

#include <cstdint>
#include <ostream>
#include <string>
#include <variant>
#include <vector>

#include "base/format.h"  // JsonQuote, CsvField: the printers' quoting

namespace raycell {

using StatValue = std::variant<std::uint64_t, double, std::string>;

struct StatEntry {
  std::string key;
  StatValue value;
};

class StatsTable {
 public:
  // Each key at most once (CHECK); entries keep the order they were added in.
  StatsTable& AddCount(std::string key, std::uint64_t value);
  StatsTable& AddReal(std::string key, double value);
  StatsTable& AddText(std::string key, std::string value);

  const std::vector<StatEntry>& entries() const { return entries_; }
  std::size_t size() const { return entries_.size(); }
  // The entry named `key`, or nullptr.
  const StatValue* Find(const std::string& key) const;

 private:
  StatsTable& Add(std::string key, StatValue value);
  std::vector<StatEntry> entries_;
};

// One value as the printers write it, unquoted: "42", "0.1", "1e+300", "nan", "inf", text.
std::string FormatValue(const StatValue& value);

// "key    value" lines, keys padded to the longest key.
void PrintText(const StatsTable& table, std::ostream& os);
// A JSON object, one key per line in table order; non-finite reals print as null.
void PrintJson(const StatsTable& table, std::ostream& os);
// Two lines: the keys, then the values (RFC 4180 quoting). PrintCsvHeader and PrintCsvRow
// print one each, for sweeps that print many tables with the same keys.
void PrintCsv(const StatsTable& table, std::ostream& os);
void PrintCsvHeader(const StatsTable& table, std::ostream& os);
void PrintCsvRow(const StatsTable& table, std::ostream& os);

// The same printers into a string.
std::string ToText(const StatsTable& table);
std::string ToJson(const StatsTable& table);
std::string ToCsv(const StatsTable& table);

}  // namespace raycell
