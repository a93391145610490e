#include "graph/cell_tree.h"

#include <algorithm>
#include <istream>
#include <sstream>
#include <utility>

#include "base/check.h"
#include "traces/format.h"

namespace raycell {

// ---------------------------------------------------------------------------- CellTree

CellTree::CellTree()
    : cell_{kNoCell},
      parent_{kNoNode},
      enter_{0},
      samples_{0},
      visits_{0},
      generation_{0},
      first_child_{kNoNode},
      next_sibling_{kNoNode},
      last_child_{kNoNode} {}

std::vector<NodeId> CellTree::children(NodeId n) const {
  std::vector<NodeId> out;
  for (NodeId c = first_child_[n]; c != kNoNode; c = next_sibling_[c]) out.push_back(c);
  return out;
}

NodeId CellTree::FindChild(NodeId n, CellId cell) const {
  for (NodeId c = first_child_[n]; c != kNoNode; c = next_sibling_[c]) {
    if (cell_[c] == cell) return c;
  }
  return kNoNode;
}

NodeId CellTree::AddNode(NodeId parent, CellId cell) {
  RAYCELL_CHECK_LT(cell_.size(), std::size_t{kNoNode});
  const auto id = static_cast<NodeId>(cell_.size());
  cell_.push_back(cell);
  parent_.push_back(parent);
  enter_.push_back(0);
  samples_.push_back(0);
  visits_.push_back(0);
  first_child_.push_back(kNoNode);
  next_sibling_.push_back(kNoNode);
  last_child_.push_back(kNoNode);
  if (last_child_[parent] == kNoNode) {
    first_child_[parent] = id;
  } else {
    next_sibling_[last_child_[parent]] = id;
  }
  last_child_[parent] = id;
  cell_count_ = std::max(cell_count_, cell + 1);
  return id;
}

// Depth-first with a per-cell count of the nodes of that cell on the current path: O(nodes).
void CellTree::ComputeGenerations() {
  generation_.assign(size(), 0);
  std::vector<std::uint32_t> on_path(cell_count_, 0);
  std::vector<std::pair<NodeId, bool>> stack;  // (node, leaving)
  for (NodeId c = first_child_[kRootNode]; c != kNoNode; c = next_sibling_[c]) {
    stack.push_back({c, false});
  }
  while (!stack.empty()) {
    const auto [n, leaving] = stack.back();
    stack.pop_back();
    if (leaving) {
      --on_path[cell_[n]];
      continue;
    }
    generation_[n] = ++on_path[cell_[n]];
    stack.push_back({n, true});
    for (NodeId c = first_child_[n]; c != kNoNode; c = next_sibling_[c])
      stack.push_back({c, false});
  }
}

std::string CellTree::ToString() const {
  std::ostringstream s;
  s << "CellTree(" << node_count() << " nodes)\n";
  std::vector<std::pair<NodeId, int>> stack;
  for (NodeId c : children(kRootNode)) stack.push_back({c, 1});
  std::reverse(stack.begin(), stack.end());
  while (!stack.empty()) {
    const auto [n, depth] = stack.back();
    stack.pop_back();
    s << std::string(2 * depth, ' ') << "cell " << cell_[n] << " gen " << generation_[n]
      << " enter " << enter_[n] << " samples " << samples_[n] << "\n";
    std::vector<NodeId> kids = children(n);
    for (auto it = kids.rbegin(); it != kids.rend(); ++it) stack.push_back({*it, depth + 1});
  }
  return s.str();
}

std::vector<std::uint32_t> MaxGenerations(const CellTree& tree) {
  std::vector<std::uint32_t> max_gen(tree.cell_count(), 0);
  for (NodeId n = 1; n < tree.size(); ++n) {
    max_gen[tree.cell(n)] = std::max(max_gen[tree.cell(n)], tree.generation(n));
  }
  return max_gen;
}

std::uint64_t Bound(const CellTree& tree) {
  std::uint64_t sum = 0;
  for (std::uint32_t g : MaxGenerations(tree)) sum += g;
  return sum;
}

// --------------------------------------------------------------------- CellTreeBuilder

namespace {

[[noreturn]] void RayError(RayId id, const std::string& what) {
  throw InputError("ray " + std::to_string(id) + ": " + what);
}

}  // namespace

CellTreeBuilder::CellTreeBuilder() = default;

void CellTreeBuilder::AddBatch(const RayBatch& batch) {
  for (std::size_t i = 0; i < batch.size(); ++i) AddRay(batch.ray(i));
}

// Children are found by walking the sibling list while a node has few of them (the common
// case: a handful of cells follow any cell), and through a hash index once it has many.
NodeId CellTreeBuilder::Child(NodeId parent, CellId cell) {
  const std::uint64_t key = (std::uint64_t{parent} << 32) | cell;
  if (child_counts_[parent] <= kScanChildren) {
    const NodeId found = tree_.FindChild(parent, cell);
    if (found != kNoNode) return found;
  } else {
    const auto it = child_index_.find(key);
    if (it != child_index_.end()) return it->second;
  }
  const NodeId n = tree_.AddNode(parent, cell);
  child_counts_.push_back(0);
  if (++child_counts_[parent] == kScanChildren + 1) {
    for (NodeId c = tree_.first_child(parent); c != kNoNode; c = tree_.next_sibling(c)) {
      child_index_.emplace((std::uint64_t{parent} << 32) | tree_.cell(c), c);
    }
  } else if (child_counts_[parent] > kScanChildren) {
    child_index_.emplace(key, n);
  }
  return n;
}

// The parent's node of the spawn visit; the parent must be known and the spawn in range.
NodeId CellTreeBuilder::ParentVisitNode(const RayView& ray) const {
  auto it = std::lower_bound(ray_ids_.begin(), ray_ids_.end(), ray.parent);
  if (it == ray_ids_.end() || *it != ray.parent) {
    RayError(ray.id, "unknown parent " + std::to_string(ray.parent) +
                         (ray.parent < last_id_ && !ray_ids_.empty() && ray.parent < ray_ids_[0]
                              ? " (it is not in the current ray tree: rays must come one tree "
                                "at a time, a primary ray followed by its descendants)"
                              : ""));
  }
  const std::size_t i = static_cast<std::size_t>(it - ray_ids_.begin());
  const std::uint64_t begin = ray_begin_[i];
  const std::uint64_t end = i + 1 < ray_begin_.size() ? ray_begin_[i + 1] : visit_nodes_.size();
  if (ray.spawn >= end - begin) {
    RayError(ray.id, "spawn " + std::to_string(ray.spawn) + " out of range: parent " +
                         std::to_string(ray.parent) + " has " + std::to_string(end - begin) +
                         " visits");
  }
  return visit_nodes_[begin + ray.spawn];
}

// The node of the ray's first visit. A primary ray enters child cells[0] of the root; a
// spawned ray works at its parent's node of the spawn visit without entering it.
NodeId CellTreeBuilder::StartNode(const RayView& ray) {
  if (ray.is_primary()) {
    const NodeId n = Child(kRootNode, ray.cells[0]);
    ++tree_.enter_[n];
    return n;
  }
  const NodeId n = ParentVisitNode(ray);
  if (tree_.cell(n) != ray.cells[0]) {
    RayError(ray.id, "first cell " + std::to_string(ray.cells[0]) + " is not the cell " +
                         std::to_string(tree_.cell(n)) + " of parent " +
                         std::to_string(ray.parent) + "'s spawn visit " +
                         std::to_string(ray.spawn));
  }
  return n;
}

void CellTreeBuilder::AddRay(const RayView& ray) {
  for (std::size_t v = 0; v < ray.visit_count; ++v) {
    // The tree keeps arrays indexed by cell: cells are bounded as in a trace.
    if (ray.cells[v] >= kTraceMaxCells) {
      RayError(ray.id, "cell " + std::to_string(ray.cells[v]) + " is beyond the largest cell " +
                           "grid (" + std::to_string(kTraceMaxCells) + " cells, kTraceMaxCells)");
    }
  }
  if (any_ray_ && ray.id <= last_id_) {
    RayError(ray.id, "ids must increase; previous ray was " + std::to_string(last_id_));
  }
  any_ray_ = true;
  last_id_ = ray.id;
  ++tree_.rays_;
  if (ray.is_primary()) {  // a new ray tree: no later ray can spawn from the previous ones
    ray_ids_.clear();
    ray_begin_.clear();
    visit_nodes_.clear();
  }
  if (!ray.is_primary() && ray.visit_count == 0) ParentVisitNode(ray);  // validates only
  ray_ids_.push_back(ray.id);
  ray_begin_.push_back(visit_nodes_.size());
  if (ray.visit_count == 0) return;
  NodeId n = StartNode(ray);
  for (std::size_t v = 0; v < ray.visit_count; ++v) {
    if (v > 0) {
      if (ray.cells[v] == ray.cells[v - 1]) {
        RayError(ray.id, "cell " + std::to_string(ray.cells[v]) + " repeated at visit " +
                             std::to_string(v));
      }
      n = Child(n, ray.cells[v]);
      ++tree_.enter_[n];
    }
    tree_.samples_[n] += ray.samples[v];
    ++tree_.visits_[n];
    visit_nodes_.push_back(n);
  }
}

CellTree CellTreeBuilder::Finish() {
  CellTree tree = std::move(tree_);
  tree.last_child_.clear();
  tree.last_child_.shrink_to_fit();
  tree.ComputeGenerations();
  *this = CellTreeBuilder();
  return tree;
}

// ------------------------------------------------------------------------------- JSONL

namespace {

// A strict parser for one line of the ray format: a flat object whose values are
// non-negative integers, null, strings without escapes, or arrays of integers.
class LineParser {
 public:
  explicit LineParser(const std::string& line) : s_(line) {}

  struct Value {
    enum class Type { kNull, kInt, kString, kArray } type = Type::kNull;
    std::uint64_t integer = 0;
    std::string string;
    std::vector<std::uint64_t> array;
  };
  using Object = std::vector<std::pair<std::string, Value>>;

  Object ParseObject() {
    Object out;
    Expect('{');
    if (!Consume('}')) {
      do {
        std::string key = ParseString();
        Expect(':');
        out.emplace_back(std::move(key), ParseValue());
      } while (Consume(','));
      Expect('}');
    }
    SkipSpace();
    if (pos_ != s_.size()) Fail("unexpected text after the object");
    return out;
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
  std::string ParseString() {
    Expect('"');
    const std::size_t end = s_.find_first_of("\"\\", pos_);
    if (end == std::string::npos || s_[end] != '"') Fail("unterminated or escaped string");
    std::string out = s_.substr(pos_, end - pos_);
    pos_ = end + 1;
    return out;
  }
  std::uint64_t ParseInt() {
    SkipSpace();
    const std::size_t start = pos_;
    std::uint64_t v = 0;
    while (pos_ < s_.size() && s_[pos_] >= '0' && s_[pos_] <= '9') {
      const std::uint64_t d = static_cast<std::uint64_t>(s_[pos_] - '0');
      if (v > (std::numeric_limits<std::uint64_t>::max() - d) / 10) Fail("integer too large");
      v = v * 10 + d;
      ++pos_;
    }
    if (pos_ == start) Fail("expected a non-negative integer");
    if (pos_ - start > 1 && s_[start] == '0') Fail("leading zero");
    return v;
  }
  Value ParseValue() {
    SkipSpace();
    Value v;
    if (s_.compare(pos_, 4, "null") == 0) {
      pos_ += 4;
    } else if (pos_ < s_.size() && s_[pos_] == '"') {
      v.type = Value::Type::kString;
      v.string = ParseString();
    } else if (Consume('[')) {
      v.type = Value::Type::kArray;
      if (!Consume(']')) {
        do v.array.push_back(ParseInt());
        while (Consume(','));
        Expect(']');
      }
    } else {
      v.type = Value::Type::kInt;
      v.integer = ParseInt();
    }
    return v;
  }

  const std::string& s_;
  std::size_t pos_ = 0;
};

using Value = LineParser::Value;

// One ray of a JSONL line, with the storage its RayView points into.
struct JsonRay {
  RayId id = 0, parent = kNoParent;
  std::uint32_t spawn = 0;
  RayKind kind = RayKind::kPrimary;
  std::uint32_t px = 0, py = 0;
  std::vector<CellId> cells;
  std::vector<std::uint32_t> samples;

  RayView view() const {
    return RayView{id,           parent,         spawn,   kind,    px,          py,
                   cells.data(), samples.data(), nullptr, nullptr, cells.size()};
  }
};

std::uint32_t To32(std::uint64_t v, const char* key) {
  if (v > std::numeric_limits<std::uint32_t>::max()) {
    throw InputError(std::string("\"") + key + "\" does not fit in 32 bits");
  }
  return static_cast<std::uint32_t>(v);
}

const Value& Require(const LineParser::Object& o, const char* key, Value::Type type,
                     bool nullable = false) {
  for (const auto& [k, v] : o) {
    if (k != key) continue;
    if (v.type == type || (nullable && v.type == Value::Type::kNull)) return v;
    throw InputError(std::string("\"") + key + "\" has the wrong type");
  }
  throw InputError(std::string("missing \"") + key + "\"");
}

void CheckKeys(const LineParser::Object& o) {
  static const char* const kKeys[] = {"frame", "id",    "parent", "spawn",
                                      "kind",  "pixel", "cells",  "samples"};
  for (std::size_t i = 0; i < o.size(); ++i) {
    const std::string& k = o[i].first;
    if (std::find(std::begin(kKeys), std::end(kKeys), k) == std::end(kKeys)) {
      throw InputError("unknown key \"" + k + "\"");
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (o[j].first == k) throw InputError("duplicate key \"" + k + "\"");
    }
  }
}

void ReadLinks(const LineParser::Object& o, JsonRay& r) {
  const Value& parent = Require(o, "parent", Value::Type::kInt, true);
  const Value& spawn = Require(o, "spawn", Value::Type::kInt, true);
  if ((parent.type == Value::Type::kNull) != (spawn.type == Value::Type::kNull)) {
    throw InputError("\"parent\" and \"spawn\" must both be null or both be set");
  }
  if (parent.type == Value::Type::kNull) return;
  if (parent.integer >= r.id) throw InputError("\"parent\" must be less than \"id\"");
  r.parent = parent.integer;
  r.spawn = To32(spawn.integer, "spawn");
}

void ReadKind(const LineParser::Object& o, JsonRay& r) {
  const std::string& name = Require(o, "kind", Value::Type::kString).string;
  const std::optional<RayKind> kind = ParseRayKind(name);
  if (!kind) throw InputError("unknown kind \"" + name + "\"");
  if ((*kind == RayKind::kPrimary) != (r.parent == kNoParent)) {
    throw InputError("kind \"" + name + "\" does not match \"parent\"");
  }
  r.kind = *kind;
}

void ReadVisits(const LineParser::Object& o, JsonRay& r) {
  const auto& pixel = Require(o, "pixel", Value::Type::kArray).array;
  if (pixel.size() != 2) throw InputError("\"pixel\" must have 2 elements");
  r.px = To32(pixel[0], "pixel");
  r.py = To32(pixel[1], "pixel");
  const auto& cells = Require(o, "cells", Value::Type::kArray).array;
  const auto& samples = Require(o, "samples", Value::Type::kArray).array;
  if (cells.size() != samples.size()) {
    throw InputError("\"cells\" and \"samples\" differ in length");
  }
  for (std::uint64_t c : cells) r.cells.push_back(To32(c, "cells"));
  for (std::uint64_t s : samples) r.samples.push_back(To32(s, "samples"));
}

JsonRay ParseRayLine(const std::string& line) {
  const LineParser::Object o = LineParser(line).ParseObject();
  CheckKeys(o);
  JsonRay r;
  r.id = Require(o, "id", Value::Type::kInt).integer;
  if (r.id == kNoParent) throw InputError("\"id\" too large");
  ReadLinks(o, r);
  ReadKind(o, r);
  ReadVisits(o, r);
  return r;
}

bool IsBlank(const std::string& line) {
  return line.find_first_not_of(" \t\r") == std::string::npos;
}

}  // namespace

CellTree FromJsonl(std::istream& in, const std::string& name) {
  CellTreeBuilder builder;
  std::string line;
  for (std::size_t number = 1; std::getline(in, line); ++number) {
    if (IsBlank(line)) continue;
    try {
      builder.AddRay(ParseRayLine(line).view());
    } catch (const InputError& e) {
      throw InputError(name + ":" + std::to_string(number) + ": " + e.what());
    }
  }
  if (in.bad()) throw InputError(name + ": read error");
  return builder.Finish();
}

}  // namespace raycell
