// docs/schemas.md against real outputs: every documented key is in the output, with the
// documented type, and every key of the output is documented.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "tests/test_util.h"
#include "tests/tools/cli_util.h"
#include "tests/tools/json_value.h"

namespace raycell::testing {
namespace {

// One row of a schema table.
struct Row {
  std::string key;  // empty for a placeholder row (a key in italics)
  std::string type, unit, present, meaning;
};

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(' '), e = s.find_last_not_of(' ');
  return b == std::string::npos ? "" : s.substr(b, e - b + 1);
}

// The table after "<!-- schema: NAME -->" in docs/schemas.md.
std::vector<Row> SchemaTable(const std::string& name) {
  std::istringstream in(ReadBytes(RAYCELL_SOURCE_DIR "/docs/schemas.md"));
  std::string line;
  while (std::getline(in, line) && line != "<!-- schema: " + name + " -->") {
  }
  EXPECT_TRUE(in) << "no table " << name << " in docs/schemas.md";
  std::vector<Row> rows;
  for (int n = 0; std::getline(in, line) && line.rfind("|", 0) == 0; ++n) {
    std::vector<std::string> cells;
    std::stringstream s(line.substr(1));
    for (std::string c; std::getline(s, c, '|');) cells.push_back(Trim(c));
    EXPECT_EQ(cells.size(), 5u) << line;
    if (n == 0) {
      EXPECT_EQ(line, "| key | type | unit | present | meaning |");
      continue;
    }
    if (n == 1 || cells.size() != 5) continue;  // the separator
    const std::string& k = cells[0];
    const bool code = k.size() > 2 && k.front() == '`' && k.back() == '`';
    EXPECT_TRUE(code || (k.size() > 2 && k.front() == '*' && k.back() == '*')) << line;
    rows.push_back({code ? k.substr(1, k.size() - 2) : "", cells[1], cells[2], cells[3], cells[4]});
  }
  EXPECT_FALSE(rows.empty()) << name;
  return rows;
}

// The documented keys present with `options` (the options given to the command).
std::vector<std::string> Keys(const std::vector<Row>& rows, const std::string& options) {
  std::vector<std::string> keys;
  for (const Row& r : rows) {
    const bool present =
        r.present == "always" ||
        (r.present.front() == '`' &&
         options.find(r.present.substr(1, r.present.size() - 2)) != std::string::npos);
    if (!r.key.empty() && present) keys.push_back(r.key);
  }
  return keys;
}

// Does `v` have the documented type ("integer", "string or null", ...)?
bool HasType(const Json& v, const std::string& type) {
  const bool nullable = type.size() > 8 && type.substr(type.size() - 8) == " or null";
  const std::string base = nullable ? type.substr(0, type.size() - 8) : type;
  if (v.type == Json::Type::kNull) return nullable;
  const std::map<std::string, Json::Type> types = {
      {"integer", Json::Type::kInteger}, {"number", Json::Type::kNumber},
      {"string", Json::Type::kString},   {"boolean", Json::Type::kBoolean},
      {"array", Json::Type::kArray},     {"object", Json::Type::kObject}};
  const auto it = types.find(base);
  return it != types.end() && it->second == v.type;
}

// Every key path of `v` ("a", "a[].b", "a.b") with each value found there.
void Flatten(const Json& v, const std::string& prefix,
             std::map<std::string, std::vector<const Json*>>& out) {
  for (const auto& [k, member] : v.members) {
    const std::string path = prefix + k;
    out[path].push_back(&member);
    if (member.type == Json::Type::kObject) Flatten(member, path + ".", out);
    for (const Json& item : member.items) {
      if (item.type == Json::Type::kObject) Flatten(item, path + "[].", out);
    }
  }
}

// The documented table `name` against JSON `objects` made with `options`: the same keys, in
// the documented order when `ordered`, of the documented types.
void CheckJson(const std::string& name, const std::vector<Json>& objects,
               const std::string& options, bool ordered) {
  const std::vector<Row> rows = SchemaTable(name);
  const std::vector<std::string> documented = Keys(rows, options);
  ASSERT_FALSE(objects.empty());
  for (const Json& object : objects) {
    std::map<std::string, std::vector<const Json*>> found;
    Flatten(object, "", found);
    std::set<std::string> keys;
    for (const auto& [k, values] : found) keys.insert(k);
    EXPECT_EQ(keys, std::set<std::string>(documented.begin(), documented.end()))
        << name << " with '" << options << "'";
    for (const Row& r : rows) {
      for (const Json* v : found[r.key]) {
        EXPECT_TRUE(HasType(*v, r.type)) << name << ": " << r.key << " is not " << r.type;
      }
    }
    if (ordered) {
      std::vector<std::string> order;
      for (const auto& [k, v] : object.members) order.push_back(k);
      EXPECT_EQ(order, documented) << name << ": keys out of the documented order";
    }
  }
}

std::vector<Json> JsonLines(const std::string& text) {
  std::vector<Json> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(Json::Parse(line));
  return out;
}

class SchemaTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::filesystem::path(CliDir("schema"));
    trace_ = (*dir_ / "s.rct").string();
    const Result r = Raycell(
        "record --res 24x24 --cells 2x2x2 --orbit 2:30 --no-images --quiet "
        "--out " +
        trace_);
    ASSERT_EQ(r.code, 0) << r.out;
  }
  static void TearDownTestSuite() {
    std::filesystem::remove_all(*dir_);
    delete dir_;
  }
  static std::filesystem::path* dir_;
  static std::string trace_;
};
std::filesystem::path* SchemaTest::dir_ = nullptr;
std::string SchemaTest::trace_;

TEST_F(SchemaTest, AnalyzeJsonHasTheDocumentedKeysTypesAndOrder) {
  for (const std::string options :
       {"--exact", "--exact --timing", "", "--bracket --effort quick"}) {
    const Result r = Raycell("analyze " + trace_ + " --format json --quiet " + options, false);
    ASSERT_EQ(r.code, 0) << r.out;
    const std::vector<Json> objects = JsonLines(r.out);
    EXPECT_EQ(objects.size(), 2u);
    CheckJson("analyze-json", objects, options, true);
    for (const Json& o : objects) EXPECT_EQ(o["schema"].text, "raycell-analyze/1");
  }
}

TEST_F(SchemaTest, ReplayJsonHasTheDocumentedKeysAndTypes) {
  // One processor (the bound holds) and two (it does not: null).
  for (const std::string options : {"", "--set processors.count=2"}) {
    const Result r = Raycell("replay " + trace_ + " --format json --quiet " + options, false);
    ASSERT_EQ(r.code, 0) << r.out;
    CheckJson("replay-json", {Json::Parse(r.out)}, options, false);
  }
}

// The timeline: with the default scheduler (celltree: its reasons), with one that gives none,
// and with prefetch and two processors (prefetch transfers, misses false, idle slices).
TEST_F(SchemaTest, ReplayTimelineHasTheDocumentedKeysAndTypes) {
  const std::string file = (*dir_ / "timeline.json").string();
  for (const std::string options :
       {"--scheduler celltree", "--scheduler maxwork",
        "--scheduler celltree --set processors.count=2 --set "
        "processors.prefetch=true --set 'level.cache.capacity=2 cells'"}) {
    const Result r =
        Raycell("replay " + trace_ + " --quiet --timeline " + file + " " + options, false);
    ASSERT_EQ(r.code, 0) << r.out;
    const Json doc = Json::Parse(ReadBytes(file));
    CheckJson("replay-timeline", {doc}, options, false);
    EXPECT_EQ(doc["otherData"]["schema"].text, "raycell-timeline/1");
  }
}

// "# raycell sweep NAME=VALUE NAME=VALUE ...", values JSON strings or bare words.
std::map<std::string, std::vector<std::string>> CommentParts(const std::string& comment) {
  const std::string start = "# raycell sweep ";
  EXPECT_EQ(comment.rfind(start, 0), 0u) << comment;
  std::map<std::string, std::vector<std::string>> parts;
  std::size_t pos = start.size();
  while (pos < comment.size()) {
    const std::size_t eq = comment.find('=', pos);
    EXPECT_NE(eq, std::string::npos) << comment;
    if (eq == std::string::npos) break;
    const std::string name = comment.substr(pos, eq - pos);
    std::size_t end = eq + 1;
    if (comment[end] == '"') {  // a JSON string: up to the unescaped closing quote
      for (++end; end < comment.size() && comment[end] != '"'; ++end) end += comment[end] == '\\';
      ++end;
    } else {
      end = std::min(comment.find(' ', end), comment.size());
    }
    parts[name].push_back(comment.substr(eq + 1, end - eq - 1));
    pos = end + 1;
  }
  return parts;
}

bool CsvHasType(const std::string& v, const std::string& type) {
  const bool emptyable = type.size() > 9 && type.substr(type.size() - 9) == " or empty";
  const std::string base = emptyable ? type.substr(0, type.size() - 9) : type;
  if (v.empty()) return emptyable;
  const bool digits = v.find_first_not_of("0123456789") == std::string::npos;
  if (base == "integer") return digits;
  if (base == "number") {
    const auto dot = v.find('.');
    return dot != std::string::npos && dot > 0 && dot + 1 < v.size() &&
           v.find_first_not_of("0123456789.") == std::string::npos;
  }
  return base == "string";
}

TEST_F(SchemaTest, SweepCsvHasTheDocumentedCommentColumnsAndTypes) {
  const std::string out = (*dir_ / "sweep.csv").string();
  const Result r = Raycell("sweep " + trace_ +
                               " --vary scheduler=maxwork,peel --vary processors.count=1,2 "
                               "--quiet --out " +
                               out,
                           false);
  ASSERT_EQ(r.code, 0) << r.out;
  std::istringstream in(ReadBytes(out));
  std::string comment, header;
  std::getline(in, comment);
  std::getline(in, header);

  const std::map<std::string, std::vector<std::string>> parts = CommentParts(comment);
  const std::vector<Row> comment_rows = SchemaTable("sweep-csv-comment");
  std::set<std::string> names;
  for (const auto& [name, values] : parts) names.insert(name);
  const std::vector<std::string> documented = Keys(comment_rows, "");
  EXPECT_EQ(names, std::set<std::string>(documented.begin(), documented.end())) << comment;
  for (const Row& row : comment_rows) {
    for (const std::string& v :
         parts.count(row.key) ? parts.at(row.key) : std::vector<std::string>{}) {
      const bool quoted = v.size() >= 2 && v.front() == '"' && v.back() == '"';
      if (row.key == "config_hash") {
        EXPECT_EQ(v.size(), 16u) << v;
      } else if (row.type == "string") {
        EXPECT_TRUE(quoted) << row.key << "=" << v;
      } else {
        EXPECT_TRUE(CsvHasType(v, row.type)) << row.key << "=" << v;
      }
    }
  }
  EXPECT_EQ(parts.at("vary").size(), 2u);

  std::vector<std::string> columns;
  std::stringstream hs(header);
  for (std::string c; std::getline(hs, c, ',');) columns.push_back(c);
  const std::vector<Row> rows = SchemaTable("sweep-csv");
  std::vector<std::string> expected;  // documented columns, the --vary keys at the placeholder
  for (const Row& row : rows) {
    if (!row.key.empty()) expected.push_back(row.key);
    if (row.key.empty()) expected.insert(expected.end(), {"scheduler", "processors.count"});
  }
  EXPECT_EQ(columns, expected) << header;
  int lines = 0;
  for (std::string line; std::getline(in, line); ++lines) {
    std::vector<std::string> values;
    std::stringstream ls(line);
    for (std::string v; std::getline(ls, v, ',');) values.push_back(v);
    if (line.back() == ',') values.push_back("");
    ASSERT_EQ(values.size(), columns.size()) << line;
    std::size_t c = 0;
    for (const Row& row : rows) {
      if (row.key.empty()) {
        c += 2;
        continue;
      }
      EXPECT_TRUE(CsvHasType(values[c], row.type)) << row.key << " = '" << values[c] << "'";
      ++c;
    }
  }
  EXPECT_EQ(lines, 4);
}

}  // namespace
}  // namespace raycell::testing
