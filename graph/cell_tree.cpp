#include "graph/cell_tree.h"

#include <algorithm>
#include <sstream>
#include <utility>

#include "base/check.h"
#include "base/hash.h"
#include "base/kept_room.h"
#include "base/varint.h"
#include "traces/format.h"

namespace raycell {

namespace {

// In place: a large array's pages past its items go back to the kernel, nothing is copied (a
// std::vector's shrink_to_fit copied a frame's tree, reserved for its visits, into new arrays
// beside the old: `raycell analyze` of b4096 355 -> 243 MB, BENCHMARKS.md "Memory").
template <typename T>
void FitTo(MappedArray<T>& v) {
  v.shrink_to_fit();  // a no-op when the capacity is already the size
}

// to += add for a node's entering rays or visits, which a tree keeps in 32 bits.
void AddCount(std::uint32_t& to, std::uint64_t add) {
  if (add > CellTree::kMaxRays - to) {
    throw InputError("a Cell Tree node with more than " + std::to_string(CellTree::kMaxRays) +
                     " entering rays or visits (a tree counts them in 32 bits)");
  }
  to += static_cast<std::uint32_t>(add);
}

}  // namespace

// ---------------------------------------------------------------------------- CellTree

CellTree::CellTree() {
  cell_.push_back(kNoCell);
  parent_.push_back(kNoNode);
  enter_.push_back(0);
  visits_.push_back(0);
  samples_.push_back(0);
  generation_.push_back(0);
  first_child_.push_back(kNoNode);
  next_sibling_.push_back(kNoNode);
  last_child_.push_back(kNoNode);
}

std::vector<NodeId> CellTree::children(NodeId n) const {
  std::vector<NodeId> out;
  for (NodeId c = first_child_[n.index()]; c != kNoNode; c = next_sibling_[c.index()])
    out.push_back(c);
  return out;
}

NodeId CellTree::FindChild(NodeId n, CellId cell) const {
  for (NodeId c = first_child_[n.index()]; c != kNoNode; c = next_sibling_[c.index()]) {
    if (cell_[c.index()] == cell) return c;
  }
  return kNoNode;
}

void CellTree::Reserve(std::size_t nodes) {
  cell_.reserve(nodes);
  parent_.reserve(nodes);
  if (counted()) {
    enter_.reserve(nodes);
    visits_.reserve(nodes);
    samples_.reserve(nodes);
  }
  first_child_.reserve(nodes);
  next_sibling_.reserve(nodes);
  last_child_.reserve(nodes);
}

NodeId CellTree::AddNode(NodeId parent, CellId cell) {
  RAYCELL_CHECK_LT(cell_.size(), std::size_t{kNoNode.index()});
  // The arrays grow in place (MappedArray: a large one's pages are moved by mremap, never
  // copied), so a growing tree never holds an old array beside the new one, and only the pages
  // written are resident (issue 43). A builder told its frame's size (CellTreeBuilder::Reserve)
  // does not grow at all.
  if (cell_.size() == cell_.capacity()) Reserve(cell_.size() + cell_.size() / 4 + 64);
  const NodeId id(static_cast<std::uint32_t>(cell_.size()));
  cell_.push_back(cell);
  parent_.push_back(parent);
  if (counted()) {
    enter_.push_back(0);
    samples_.push_back(0);
    visits_.push_back(0);
  }
  first_child_.push_back(kNoNode);
  next_sibling_.push_back(kNoNode);
  last_child_.push_back(kNoNode);
  Link(parent, id);
  cell_count_ = std::max(cell_count_, cell.value() + 1);
  return id;
}

// Each tree in two passes, so that the union's arrays are sized once: the first counts the
// tree's nodes on paths the union lacks so far (those whose parent has no such child), the
// second adds them, as AddNode one by one would. The count is exact but for a tree with two
// children of one cell under one parent, which no builder makes (then Finish shrinks).
CellTree Union(const std::vector<const CellTree*>& trees, bool counted) {
  CellTree u;
  if (!counted) u.enter_.free_room(), u.visits_.free_room(), u.samples_.free_room();
  std::uint64_t rays = 0;
  for (const CellTree* t : trees) rays += t->rays();
  if (counted && rays > CellTree::kMaxRays) {
    throw InputError("the union of " + std::to_string(trees.size()) + " Cell Trees has " +
                     std::to_string(rays) + " rays, more than a tree counts (" +
                     std::to_string(CellTree::kMaxRays) + ")");
  }
  for (const CellTree* t : trees) {
    std::vector<NodeId> image(t->size(), kNoNode);  // t's node -> u's node (kNoNode: new)
    image[kRootNode.index()] = kRootNode;
    std::size_t added = 0;
    for (NodeId n : t->nodes()) {  // parents before children
      const NodeId p = image[t->parent(n).index()];
      image[n.index()] = p == kNoNode ? kNoNode : u.FindChild(p, t->cell(n));
      added += image[n.index()] == kNoNode;
    }
    u.Reserve(u.size() + added);
    for (NodeId n : t->nodes()) {
      NodeId m = image[n.index()];
      if (m == kNoNode) {
        const NodeId p = image[t->parent(n).index()];
        m = u.FindChild(p, t->cell(n));
        if (m == kNoNode) m = u.AddNode(p, t->cell(n));
        image[n.index()] = m;
      }
      if (!counted) continue;
      AddCount(u.enter_[m.index()], t->enter(n));
      u.samples_[m.index()] += t->samples(n);
      AddCount(u.visits_[m.index()], t->visits(n));
    }
  }
  u.rays_ = rays;
  u.Finish();
  return u;
}

CellTree UnionTree(const std::vector<const CellTree*>& trees) { return Union(trees, true); }

std::uint64_t CellTree::Bytes() const {
  const auto of = [](const auto& v) {
    return std::uint64_t{v.capacity()} * sizeof(typename std::decay_t<decltype(v)>::value_type);
  };
  return of(cell_) + of(parent_) + of(enter_) + of(visits_) + of(samples_) + of(generation_) +
         of(first_child_) + of(next_sibling_) + of(last_child_) + of(parked_);
}

CellTree UnionShape(const std::vector<const CellTree*>& trees) { return Union(trees, false); }

CellTree ContractTree(const CellTree& tree, const std::vector<CellId>& coarse_of,
                      std::vector<NodeId>* image) {
  CellTree u;
  std::vector<NodeId> to(tree.size(), kNoNode);
  to[kRootNode.index()] = kRootNode;
  for (NodeId n : tree.nodes()) {  // parents before children
    RAYCELL_CHECK_LT(tree.cell(n).value(), coarse_of.size());
    const CellId c = coarse_of[tree.cell(n).value()];
    const NodeId p = to[tree.parent(n).index()];
    NodeId m = p;
    if (p == kRootNode || u.cell(p) != c) {  // a new coarse node, or one already made
      m = u.FindChild(p, c);
      if (m == kNoNode) m = u.AddNode(p, c);
      AddCount(u.enter_[m.index()], tree.enter(n));
    }
    to[n.index()] = m;
    u.samples_[m.index()] += tree.samples(n);
    AddCount(u.visits_[m.index()], tree.visits(n));
  }
  u.rays_ = tree.rays();
  u.Finish();
  if (image != nullptr) *image = std::move(to);
  return u;
}

CellTree SubTree(const CellTree& tree, const std::vector<NodeId>& nodes) {
  CellTree u;
  u.Reserve(nodes.size() + 1);
  // The k-th of `nodes` becomes node k + 1; a parent, of a smaller id, is found among the
  // nodes before it by binary search: O(k log k) for k nodes, whatever the tree's size (a map
  // over the tree's nodes made every call O(tree): the two-level planner, one call per coarse
  // entry, was quadratic, 10x Max Work's replay at 4096 cells).
  NodeId last = kRootNode;
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    const NodeId n = nodes[k];
    RAYCELL_CHECK(last < n && n.index() < tree.size());
    last = n;
    const NodeId parent = tree.parent(n);
    const auto end = nodes.begin() + std::ptrdiff_t(k);
    const auto at = std::lower_bound(nodes.begin(), end, parent);
    const NodeId p =
        at != end && *at == parent ? NodeId(std::uint32_t(at - nodes.begin()) + 1) : kRootNode;
    const NodeId m = u.AddNode(p, tree.cell(n));
    RAYCELL_CHECK_EQ(m.index(), k + 1);
    u.enter_[m.index()] = static_cast<std::uint32_t>(tree.enter(n));
    u.samples_[m.index()] = tree.samples(n);
    u.visits_[m.index()] = static_cast<std::uint32_t>(tree.visits(n));
  }
  u.Finish();
  return u;
}

void CellTree::Finish() {
  FreeRoom(last_child_);
  FitTo(cell_);
  FitTo(parent_);
  FitTo(enter_);
  FitTo(visits_);
  FitTo(samples_);
  FitTo(first_child_);
  FitTo(next_sibling_);
  ComputeGenerations();
  key_ = ComputeKey();
  has_key_ = true;
}

std::uint64_t CellTree::ComputeKey() const {
  RAYCELL_CHECK(!parked());
  Hash64 h;
  h.Add(size());
  for (std::size_t i = 1; i < cell_.size(); ++i) {
    h.Add(std::uint64_t{cell_[i].value()} << 32 | parent_[i].index());
  }
  return h.Finish();
}

void CellTree::Park() {
  RAYCELL_CHECK(!parked() && last_child_.empty());  // finished
  const std::size_t n = cell_.size();
  const bool counted = this->counted();
  // Pages never written are not resident, and the fit below gives the others past the stream
  // back in place (MappedArray): the stream is never copied.
  MappedArray<std::uint8_t> out;
  out.reserve(n * (counted ? 8 : 3));
  for (std::size_t i = 0; i < n; ++i) {
    const NodeId p = parent_[i];
    // A parent comes before its node (parent(n) < n): its distance, at least 1; 0 for none.
    if (p == kNoNode) {
      AppendVarint(out, 0);
      AppendVarint(out, std::uint32_t(cell_[i].value() + 1));  // kNoCell as 0
    } else {
      AppendVarint(out, i - p.index());
      const std::uint32_t step = cell_[i].value() - cell_[p.index()].value();  // mod 2^32
      AppendVarint(out, (step << 1) ^ (0u - (step >> 31)));  // zigzag of the signed step
    }
    AppendVarint(out, generation_[i]);  // kept: a byte a node, against a walk of the tree again
    if (counted) {
      AppendVarint(out, enter_[i]);
      AppendVarint(out, visits_[i]);
      AppendVarint(out, samples_[i]);
    }
  }
  out.shrink_to_fit();
  parked_size_ = n;
  parked_counted_ = counted;
  FreeRoom(cell_);
  FreeRoom(parent_);
  FreeRoom(first_child_);
  FreeRoom(next_sibling_);
  FreeRoom(enter_);
  FreeRoom(visits_);
  FreeRoom(samples_);
  FreeRoom(generation_);
  parked_ = std::move(out);
}

void CellTree::Unpark() {
  RAYCELL_CHECK(parked());
  const std::size_t n = parked_size_;
  cell_.resize(n);
  parent_.resize(n);
  generation_.resize(n);
  if (parked_counted_) {
    enter_.resize(n);
    visits_.resize(n);
    samples_.resize(n);
  }
  const std::uint8_t* stream = parked_.data();
  std::size_t at = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t back = ReadVarint(stream, &at);
    const std::uint32_t code = ReadVarint(stream, &at);
    if (back == 0) {
      parent_[i] = kNoNode;
      cell_[i] = CellId(code - 1);
    } else {
      const std::uint32_t p = std::uint32_t(i - back);
      parent_[i] = NodeId(p);
      const std::uint32_t step = (code >> 1) ^ (0u - (code & 1));
      cell_[i] = CellId(cell_[p].value() + step);
    }
    generation_[i] = ReadVarint(stream, &at);
    if (parked_counted_) {
      enter_[i] = ReadVarint(stream, &at);
      visits_[i] = ReadVarint(stream, &at);
      samples_[i] = ReadVarint<std::uint64_t>(stream, &at);
    }
  }
  RAYCELL_CHECK(at == parked_.size());
  FreeRoom(parked_);
  // Every tree links a node's children in creation order, which is the order of their ids
  // (AddNode): prepended from the last node back, they come out in that order.
  first_child_.assign(n, kNoNode);
  next_sibling_.assign(n, kNoNode);
  for (std::size_t i = n; i-- > 1;) {
    NodeId& first = first_child_[parent_[i].index()];
    next_sibling_[i] = first;
    first = NodeId(std::uint32_t(i));
  }
}

void CellTree::ComputeGenerations() {
  generation_.assign(size(), 0);
  std::vector<std::uint32_t> on_path(cell_count_, 0);
  std::vector<std::pair<NodeId, bool>> stack;  // (node, leaving)
  for (NodeId c = first_child_[kRootNode.index()]; c != kNoNode; c = next_sibling_[c.index()]) {
    stack.push_back({c, false});
  }
  while (!stack.empty()) {
    const auto [n, leaving] = stack.back();
    stack.pop_back();
    if (leaving) {
      --on_path[cell_[n.index()].value()];
      continue;
    }
    generation_[n.index()] = ++on_path[cell_[n.index()].value()];
    stack.push_back({n, true});
    for (NodeId c = first_child_[n.index()]; c != kNoNode; c = next_sibling_[c.index()])
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
    s << std::string(2 * depth, ' ') << "cell " << cell_[n.index()] << " gen "
      << generation_[n.index()] << " enter " << enter_[n.index()] << " samples "
      << samples_[n.index()] << "\n";
    std::vector<NodeId> kids = children(n);
    for (auto it = kids.rbegin(); it != kids.rend(); ++it) stack.push_back({*it, depth + 1});
  }
  return s.str();
}

std::vector<std::uint32_t> MaxGenerations(const CellTree& tree) {
  std::vector<std::uint32_t> max_gen(tree.cell_count(), 0);
  for (NodeId n : tree.nodes()) {
    max_gen[tree.cell(n).value()] = std::max(max_gen[tree.cell(n).value()], tree.generation(n));
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

void CellTreeBuilder::Reserve(std::uint64_t nodes) {
  // A frame's summary is checked against the frame only once it is read: capped here (2^28
  // nodes, 10 GB of address space), beyond which the arrays grow as nodes come.
  const std::size_t n = std::size_t(std::min<std::uint64_t>(nodes, std::uint64_t{1} << 28)) + 1;
  if (n <= tree_.cell_.capacity()) return;
  tree_.Reserve(n);
  child_counts_.reserve(n);
}

void CellTreeBuilder::AddBatch(const RayBatch& batch) {
  for (std::size_t i = 0; i < batch.size(); ++i) AddRay(batch.ray(i));
}

// Children are found by walking the sibling list while a node has few of them (the common
// case: a handful of cells follow any cell), and through a hash index once it has many.
NodeId CellTreeBuilder::Child(NodeId parent, CellId cell) {
  const std::uint64_t key = (std::uint64_t{parent.index()} << 32) | cell.value();
  if (child_counts_[parent.index()] <= kScanChildren) {
    const NodeId found = tree_.FindChild(parent, cell);
    if (found != kNoNode) return found;
  } else {
    const auto it = child_index_.find(key);
    if (it != child_index_.end()) return it->second;
  }
  const NodeId n = tree_.AddNode(parent, cell);
  if (child_counts_.size() == child_counts_.capacity()) {
    child_counts_.reserve(tree_.cell_.capacity());  // grows with the tree's arrays
  }
  child_counts_.push_back(0);
  if (++child_counts_[parent.index()] == kScanChildren + 1) {
    for (NodeId c = tree_.first_child(parent); c != kNoNode; c = tree_.next_sibling(c)) {
      child_index_.emplace((std::uint64_t{parent.index()} << 32) | tree_.cell(c).value(), c);
    }
  } else if (child_counts_[parent.index()] > kScanChildren) {
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
    ++tree_.enter_[n.index()];
    return n;
  }
  const NodeId n = ParentVisitNode(ray);
  if (tree_.cell(n) != ray.cells[0]) {
    RayError(ray.id, "first cell " + std::to_string(ray.cells[0].value()) + " is not the cell " +
                         std::to_string(tree_.cell(n).value()) + " of parent " +
                         std::to_string(ray.parent) + "'s spawn visit " +
                         std::to_string(ray.spawn));
  }
  return n;
}

void CellTreeBuilder::AddRay(const RayView& ray) {
  for (std::size_t v = 0; v < ray.visit_count; ++v) {
    // The tree keeps arrays indexed by cell: cells are bounded as in a trace.
    if (ray.cells[v].value() >= kTraceMaxCells) {
      RayError(ray.id, "cell " + std::to_string(ray.cells[v].value()) +
                           " is beyond the largest cell " + "grid (" +
                           std::to_string(kTraceMaxCells) + " cells, kTraceMaxCells)");
    }
  }
  if (any_ray_ && ray.id <= last_id_) {
    RayError(ray.id, "ids must increase; previous ray was " + std::to_string(last_id_));
  }
  if (tree_.rays_ == CellTree::kMaxRays) {
    RayError(ray.id, "more than " + std::to_string(CellTree::kMaxRays) +
                         " rays in one Cell Tree (a tree counts a node's rays in 32 bits)");
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
        RayError(ray.id, "cell " + std::to_string(ray.cells[v].value()) + " repeated at visit " +
                             std::to_string(v));
      }
      n = Child(n, ray.cells[v]);
      ++tree_.enter_[n.index()];
    }
    tree_.samples_[n.index()] += ray.samples[v];
    ++tree_.visits_[n.index()];
    visit_nodes_.push_back(n);
  }
}

CellTree CellTreeBuilder::Finish() {
  CellTree tree = std::move(tree_);
  *this = CellTreeBuilder();  // its lookups freed before the tree's arrays are shrunk
  tree.Finish();
  return tree;
}

}  // namespace raycell
