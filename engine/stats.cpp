#include "engine/stats.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "base/check.h"
#include "base/format.h"

namespace raycell {
namespace {

bool IsNonFinite(const StatValue& value) {
  const double* d = std::get_if<double>(&value);
  return d != nullptr && !std::isfinite(*d);
}

std::string JsonValue(const StatValue& value) {
  if (IsNonFinite(value)) return "null";
  if (const auto* s = std::get_if<std::string>(&value)) return JsonQuote(*s);
  return FormatValue(value);
}

template <typename F>
std::string PrintToString(const StatsTable& table, F print) {
  std::ostringstream os;
  print(table, os);
  return os.str();
}

}  // namespace

StatsTable& StatsTable::AddCount(std::string key, std::uint64_t value) {
  return Add(std::move(key), value);
}
StatsTable& StatsTable::AddReal(std::string key, double value) {
  return Add(std::move(key), value);
}
StatsTable& StatsTable::AddText(std::string key, std::string value) {
  return Add(std::move(key), std::move(value));
}

StatsTable& StatsTable::Add(std::string key, StatValue value) {
  RAYCELL_CHECK_OP(Find(key), ==, static_cast<const StatValue*>(nullptr));  // unique keys
  entries_.push_back({std::move(key), std::move(value)});
  return *this;
}

const StatValue* StatsTable::Find(const std::string& key) const {
  for (const StatEntry& e : entries_) {
    if (e.key == key) return &e.value;
  }
  return nullptr;
}

std::string FormatValue(const StatValue& value) {
  if (const auto* u = std::get_if<std::uint64_t>(&value)) return std::to_string(*u);
  if (const auto* d = std::get_if<double>(&value)) return FormatReal(*d);
  return std::get<std::string>(value);
}

void PrintText(const StatsTable& table, std::ostream& os) {
  std::size_t width = 0;
  for (const StatEntry& e : table.entries()) width = std::max(width, e.key.size());
  for (const StatEntry& e : table.entries()) {
    os << e.key << std::string(width - e.key.size() + 2, ' ') << FormatValue(e.value) << "\n";
  }
}

void PrintJson(const StatsTable& table, std::ostream& os) {
  os << "{";
  const char* sep = "\n";
  for (const StatEntry& e : table.entries()) {
    os << sep << "  " << JsonQuote(e.key) << ": " << JsonValue(e.value);
    sep = ",\n";
  }
  os << (table.size() == 0 ? "}\n" : "\n}\n");
}

void PrintCsvHeader(const StatsTable& table, std::ostream& os) {
  const char* sep = "";
  for (const StatEntry& e : table.entries()) {
    os << sep << CsvField(e.key);
    sep = ",";
  }
  os << "\n";
}

void PrintCsvRow(const StatsTable& table, std::ostream& os) {
  const char* sep = "";
  for (const StatEntry& e : table.entries()) {
    os << sep << CsvField(FormatValue(e.value));
    sep = ",";
  }
  os << "\n";
}

void PrintCsv(const StatsTable& table, std::ostream& os) {
  PrintCsvHeader(table, os);
  PrintCsvRow(table, os);
}

std::string ToText(const StatsTable& table) { return PrintToString(table, PrintText); }
std::string ToJson(const StatsTable& table) { return PrintToString(table, PrintJson); }
std::string ToCsv(const StatsTable& table) { return PrintToString(table, PrintCsv); }

}  // namespace raycell
