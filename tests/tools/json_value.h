// A small, strict JSON reader for the tests of raycell's outputs (RFC 8259 minus \u escapes
// beyond ASCII): values keep their kind, integers apart from decimal fractions, and objects
// keep their key order.
#pragma once

#include <cctype>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace raycell::testing {

struct Json {
  enum class Type { kNull, kBoolean, kInteger, kNumber, kString, kArray, kObject };
  Type type = Type::kNull;
  bool boolean = false;
  std::string text;  // the number as written, or the string's value
  std::vector<Json> items;
  std::vector<std::pair<std::string, Json>> members;

  // The member `key`; throws when absent.
  const Json& operator[](const std::string& key) const {
    for (const auto& [k, v] : members) {
      if (k == key) return v;
    }
    throw std::runtime_error("no key " + key);
  }

  static Json Parse(const std::string& s) {
    std::size_t pos = 0;
    Json v = ParseValue(s, pos);
    SkipSpace(s, pos);
    if (pos != s.size()) Fail(s, pos, "trailing text");
    return v;
  }

 private:
  [[noreturn]] static void Fail(const std::string& s, std::size_t pos, const std::string& what) {
    throw std::runtime_error("JSON: " + what + " at " + std::to_string(pos) +
                             " in: " + s.substr(0, 200));
  }
  static void SkipSpace(const std::string& s, std::size_t& pos) {
    while (pos < s.size() && (s[pos] == ' ' || s[pos] == '\n' || s[pos] == '\t' || s[pos] == '\r'))
      ++pos;
  }
  static void Expect(const std::string& s, std::size_t& pos, char c) {
    SkipSpace(s, pos);
    if (pos >= s.size() || s[pos] != c) Fail(s, pos, std::string("expected ") + c);
    ++pos;
  }
  static std::string ParseString(const std::string& s, std::size_t& pos) {
    Expect(s, pos, '"');
    std::string out;
    while (pos < s.size() && s[pos] != '"') {
      if (s[pos] != '\\') {
        out += s[pos++];
        continue;
      }
      if (++pos >= s.size()) Fail(s, pos, "bad escape");
      const char e = s[pos++];
      const std::string plain = "\"\\/bfnrt", meant = "\"\\/\b\f\n\r\t";
      if (plain.find(e) != std::string::npos) {
        out += meant[plain.find(e)];
      } else if (e == 'u' && pos + 4 <= s.size()) {
        out += char(std::stoi(s.substr(pos, 4), nullptr, 16));
        pos += 4;
      } else {
        Fail(s, pos, "bad escape");
      }
    }
    Expect(s, pos, '"');
    return out;
  }
  static Json ParseNumber(const std::string& s, std::size_t& pos) {
    Json v;
    v.type = Type::kInteger;
    const std::size_t start = pos;
    if (s[pos] == '-') ++pos;
    const std::size_t digits = pos;
    while (pos < s.size() && std::isdigit(static_cast<unsigned char>(s[pos]))) ++pos;
    if (pos == digits || (pos - digits > 1 && s[digits] == '0')) Fail(s, start, "bad number");
    if (pos < s.size() && s[pos] == '.') {
      v.type = Type::kNumber;
      const std::size_t frac = ++pos;
      while (pos < s.size() && std::isdigit(static_cast<unsigned char>(s[pos]))) ++pos;
      if (pos == frac) Fail(s, start, "bad number");
    }
    if (pos < s.size() && (s[pos] == 'e' || s[pos] == 'E')) {
      v.type = Type::kNumber;
      ++pos;
      if (pos < s.size() && (s[pos] == '+' || s[pos] == '-')) ++pos;
      const std::size_t exp = pos;
      while (pos < s.size() && std::isdigit(static_cast<unsigned char>(s[pos]))) ++pos;
      if (pos == exp) Fail(s, start, "bad number");
    }
    v.text = s.substr(start, pos - start);
    return v;
  }
  static Json ParseValue(const std::string& s, std::size_t& pos) {
    SkipSpace(s, pos);
    if (pos >= s.size()) Fail(s, pos, "expected a value");
    Json v;
    for (const auto& [word, type, b] :
         {std::tuple<const char*, Type, bool>{"null", Type::kNull, false},
          {"true", Type::kBoolean, true},
          {"false", Type::kBoolean, false}}) {
      if (s.compare(pos, std::string(word).size(), word) == 0) {
        pos += std::string(word).size();
        v.type = type;
        v.boolean = b;
        return v;
      }
    }
    if (s[pos] == '"') {
      v.type = Type::kString;
      v.text = ParseString(s, pos);
    } else if (s[pos] == '[') {
      v.type = Type::kArray;
      ++pos;
      SkipSpace(s, pos);
      if (pos < s.size() && s[pos] == ']') return ++pos, v;
      do v.items.push_back(ParseValue(s, pos));
      while (SkipSpace(s, pos), pos < s.size() && s[pos] == ',' && ++pos);
      Expect(s, pos, ']');
    } else if (s[pos] == '{') {
      v.type = Type::kObject;
      ++pos;
      SkipSpace(s, pos);
      if (pos < s.size() && s[pos] == '}') return ++pos, v;
      do {
        std::string key = ParseString(s, pos);
        Expect(s, pos, ':');
        v.members.emplace_back(std::move(key), ParseValue(s, pos));
      } while (SkipSpace(s, pos), pos < s.size() && s[pos] == ',' && ++pos);
      Expect(s, pos, '}');
    } else {
      v = ParseNumber(s, pos);
    }
    return v;
  }
};

}  // namespace raycell::testing
