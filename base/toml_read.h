// What the two readers of TOML files (the replay configuration, replay/config.cpp, and scene
// files, record/scene_file.cpp) share: positions and type names for messages, and the unknown
// key pbrt-style ReportUnused names. Header-only: its users link toml++ themselves, base/ does
// not.
#pragma once

#include <toml++/toml.h>

#include <set>
#include <string>

namespace raycell {

// "FILE:LINE:COL" of a TOML node or key.
inline std::string TomlWhere(const std::string& file, const toml::source_region& r) {
  return file + ":" + std::to_string(r.begin.line) + ":" + std::to_string(r.begin.column);
}

// "a table", "an integer", ... for "expected X, got Y" messages.
inline const char* TomlTypeName(const toml::node& n) {
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

// The first key of `table` in the file (by position) that is not in `used`, or null.
inline const toml::key* FirstUnusedKey(const toml::table& table,
                                       const std::set<std::string>& used) {
  const toml::key* first = nullptr;
  for (auto&& [k, v] : table) {
    if (used.count(std::string(k.str())) != 0) continue;
    if (first == nullptr || k.source().begin < first->source().begin) first = &k;
  }
  return first;
}

// The keys read, "a, b, c", for the message naming an unknown key.
inline std::string JoinKeys(const std::set<std::string>& used) {
  std::string valid;
  for (const std::string& k : used) valid += (valid.empty() ? "" : ", ") + k;
  return valid;
}

}  // namespace raycell
