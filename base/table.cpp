#include "base/table.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "base/check.h"
#include "base/format.h"

namespace raycell {
namespace {

bool IsNonFinite(const StatValue& value) {
  if (const double* d = std::get_if<double>(&value)) return !std::isfinite(*d);
  if (const FixedReal* f = std::get_if<FixedReal>(&value)) return !std::isfinite(f->value);
  return false;
}

void PrintJsonValue(const StatValue& value, std::ostream& os);

void PrintJsonObjectLine(const StatsTable& table, std::ostream& os) {
  os << "{";
  const char* sep = "";
  for (const StatEntry& e : table.entries()) {
    os << sep << JsonQuote(e.key) << ":";
    PrintJsonValue(e.value, os);
    sep = ",";
  }
  os << "}";
}

void PrintJsonValue(const StatValue& value, std::ostream& os) {
  if (std::holds_alternative<NoValue>(value) || IsNonFinite(value)) {
    os << "null";
  } else if (const auto* s = std::get_if<std::string>(&value)) {
    os << JsonQuote(*s);
  } else if (const auto* tables = std::get_if<StatTables>(&value)) {
    os << "[";
    for (std::size_t i = 0; i < tables->size(); ++i) {
      if (i) os << ",";
      PrintJsonObjectLine((*tables)[i], os);
    }
    os << "]";
  } else {
    os << FormatValue(value);
  }
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
StatsTable& StatsTable::AddInt(std::string key, std::int64_t value) {
  return Add(std::move(key), value);
}
StatsTable& StatsTable::AddReal(std::string key, double value) {
  return Add(std::move(key), value);
}
StatsTable& StatsTable::AddFixed(std::string key, double value, int decimals) {
  RAYCELL_CHECK(decimals >= 0 && decimals <= 17);
  return Add(std::move(key), FixedReal{value, decimals});
}
StatsTable& StatsTable::AddBool(std::string key, bool value) { return Add(std::move(key), value); }
StatsTable& StatsTable::AddText(std::string key, std::string value) {
  return Add(std::move(key), std::move(value));
}
StatsTable& StatsTable::AddNone(std::string key) { return Add(std::move(key), NoValue{}); }
StatsTable& StatsTable::AddTables(std::string key, StatTables tables) {
  for (const StatsTable& t : tables) {  // each names its columns by its first entry
    RAYCELL_CHECK(t.size() > 0 && std::holds_alternative<std::string>(t.entries()[0].value));
  }
  return Add(std::move(key), std::move(tables));
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

std::uint64_t StatsTable::Count(const std::string& key) const {
  const StatValue* v = Find(key);
  RAYCELL_CHECK(v != nullptr && std::holds_alternative<std::uint64_t>(*v));
  return std::get<std::uint64_t>(*v);
}

double StatsTable::Real(const std::string& key) const {
  const StatValue* v = Find(key);
  RAYCELL_CHECK(v != nullptr);
  if (const FixedReal* f = std::get_if<FixedReal>(v)) return f->value;
  RAYCELL_CHECK(std::holds_alternative<double>(*v));
  return std::get<double>(*v);
}

StatsTable StatsTable::Flattened() const {
  StatsTable flat;
  for (const StatEntry& e : entries_) {
    const auto* tables = std::get_if<StatTables>(&e.value);
    if (!tables) {
      flat.Add(e.key, e.value);
      continue;
    }
    for (const StatsTable& t : *tables) {
      const std::string& name = std::get<std::string>(t.entries()[0].value);
      for (std::size_t i = 1; i < t.size(); ++i) {
        flat.Add(name + "_" + t.entries()[i].key, t.entries()[i].value);
      }
    }
  }
  return flat;
}

std::string FormatValue(const StatValue& value) {
  if (std::holds_alternative<NoValue>(value)) return "";
  if (const auto* u = std::get_if<std::uint64_t>(&value)) return std::to_string(*u);
  if (const auto* i = std::get_if<std::int64_t>(&value)) return std::to_string(*i);
  if (const auto* d = std::get_if<double>(&value)) return FormatReal(*d);
  if (const auto* f = std::get_if<FixedReal>(&value)) {
    return std::isfinite(f->value) ? FormatFixed(f->value, f->decimals) : FormatReal(f->value);
  }
  if (const auto* b = std::get_if<bool>(&value)) return *b ? "true" : "false";
  RAYCELL_CHECK(std::holds_alternative<std::string>(value));  // lists print flattened
  return std::get<std::string>(value);
}

void PrintText(const StatsTable& table, std::ostream& os) {
  const StatsTable flat = table.Flattened();
  std::size_t width = 0;
  for (const StatEntry& e : flat.entries()) width = std::max(width, e.key.size());
  for (const StatEntry& e : flat.entries()) {
    const bool none = std::holds_alternative<NoValue>(e.value);
    os << e.key << std::string(width - e.key.size() + 2, ' ') << (none ? "-" : FormatValue(e.value))
       << "\n";
  }
}

void PrintJson(const StatsTable& table, std::ostream& os) {
  os << "{";
  const char* sep = "\n";
  for (const StatEntry& e : table.entries()) {
    os << sep << "  " << JsonQuote(e.key) << ": ";
    PrintJsonValue(e.value, os);
    sep = ",\n";
  }
  os << (table.size() == 0 ? "}\n" : "\n}\n");
}

void PrintJsonLine(const StatsTable& table, std::ostream& os) { PrintJsonObjectLine(table, os); }

void PrintCsvHeader(const StatsTable& table, std::ostream& os) {
  const char* sep = "";
  const StatsTable flat = table.Flattened();
  for (const StatEntry& e : flat.entries()) {
    os << sep << CsvField(e.key);
    sep = ",";
  }
  os << "\n";
}

void PrintCsvRow(const StatsTable& table, std::ostream& os) {
  const char* sep = "";
  const StatsTable flat = table.Flattened();
  for (const StatEntry& e : flat.entries()) {
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
std::string ToJsonLine(const StatsTable& table) { return PrintToString(table, PrintJsonLine); }
std::string ToCsv(const StatsTable& table) { return PrintToString(table, PrintCsv); }
std::string ToCsvHeader(const StatsTable& table) { return PrintToString(table, PrintCsvHeader); }
std::string ToCsvRow(const StatsTable& table) { return PrintToString(table, PrintCsvRow); }

}  // namespace raycell
