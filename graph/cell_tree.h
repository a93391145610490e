// The Cell Tree of one frame (docs/design.md §1 "Cell Tree", "Generation and bound").
//
// Nodes live in flat arrays indexed by NodeId. Node 0 (kRootNode) is the virtual root: it
// has no cell, no parent and is never counted as work. Every other node is (parent, cell),
// and a node is always created after its parent, so parent(n) < n. A finished tree's arrays
// hold exactly its nodes, 36 bytes each (issue 43: docs/design.md §2 "What a replay holds").
//
// CellTreeBuilder builds the tree while rays stream in, batch by batch, in ray id order.
// Its memory grows with the nodes, plus, to place spawned rays, one NodeId per visit of
// every ray seen so far and 16 bytes per ray (see CellTreeBuilder). Rays read from JSON Lines
// (traces/jsonl.h) come in the order the builder needs.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <ostream>
#include <string>
#include <type_traits>
#include <unordered_map>
#include <vector>

#include "base/mapped_array.h"
#include "base/typed_id.h"
#include "traces/ray_batch.h"

namespace raycell {

// A node of a Cell Tree: its index in the tree's flat arrays (base/typed_id.h). A node and a
// cell never convert into each other: a NodeId is made from a number only explicitly,
// NodeId(i), and gives it back only through index().
class NodeId : public TypedId<NodeId> {
 public:
  using TypedId::TypedId;
  constexpr std::uint32_t index() const { return number(); }
};
static_assert(sizeof(NodeId) == sizeof(std::uint32_t) && std::is_trivially_copyable_v<NodeId>);

inline constexpr NodeId kRootNode{0};
inline constexpr NodeId kNoNode{std::numeric_limits<std::uint32_t>::max()};

class CellTree {
 public:
  // Nodes including the root; node ids are 0 .. size()-1.
  std::size_t size() const { return parked_.empty() ? cell_.size() : parked_size_; }
  // The nodes without the root, in creation order (parents before children):
  // for (NodeId n : tree.nodes()).
  class NodeRange;
  NodeRange nodes() const;
  // Nodes without the root.
  std::size_t node_count() const { return size() - 1; }
  // One more than the largest cell of any node (0 for an empty tree).
  std::uint32_t cell_count() const { return cell_count_; }
  // Rays the tree was built from (rays with no visit included).
  std::uint64_t rays() const { return rays_; }
  // The most rays a tree counts: a node's entering rays and visits are kept in 32 bits, and a
  // ray visits a node at most once, so a tree of at most this many rays never overflows them.
  // The builder refuses a frame of more rays, UnionTree trees of more rays in all, and
  // ContractTree a coarse node of more visits (InputError).
  static constexpr std::uint64_t kMaxRays = std::numeric_limits<std::uint32_t>::max();

  CellId cell(NodeId n) const { return cell_[n.index()]; }      // kNoCell for the root
  NodeId parent(NodeId n) const { return parent_[n.index()]; }  // kNoNode for the root
  // Rays entering from the parent.
  std::uint64_t enter(NodeId n) const { return counted() ? enter_[n.index()] : 0; }
  std::uint64_t samples(NodeId n) const { return counted() ? samples_[n.index()] : 0; }
  // Ray visits (segments) worked in the node: its entering rays plus rays spawned in it.
  std::uint64_t visits(NodeId n) const { return counted() ? visits_[n.index()] : 0; }
  // Whether the tree keeps enter, samples and visits: false for UnionShape's, whose counts read 0.
  bool counted() const { return !samples_.empty(); }
  // Nodes on the path root..n (inclusive) whose cell is cell(n); 0 for the root.
  std::uint32_t generation(NodeId n) const { return generation_[n.index()]; }
  // Children in creation order: first_child, then next_sibling until kNoNode.
  NodeId first_child(NodeId n) const { return first_child_[n.index()]; }
  NodeId next_sibling(NodeId n) const { return next_sibling_[n.index()]; }
  bool is_leaf(NodeId n) const { return first_child_[n.index()] == kNoNode; }
  std::vector<NodeId> children(NodeId n) const;
  // The child of `n` in `cell`, or kNoNode. Linear in the number of children.
  NodeId FindChild(NodeId n, CellId cell) const;

  // One line per node, depth-first, indented: "cell 3 gen 1 enter 2 samples 40".
  std::string ToString() const;

  // A finished tree kept for a later frame while nothing reads it (the frame's own tree during
  // its replays, and the previous frame's where no replay reads it then: runner/driver.cpp)
  // keeps its cells, parents, generations and counts as a stream of varints (each node's parent
  // and cell as steps back from the node and from the parent's cell: about 6 of its 36 bytes a
  // node) and drops its arrays; Unpark reads them back and makes the children links again (in
  // creation order, as AddNode links them), before the tree is read. Only size(), node_count(),
  // cell_count(), rays() and parked() may be read while parked.
  void Park();
  void Unpark();
  bool parked() const { return !parked_.empty(); }
  // The bytes its arrays take (their capacity).
  std::uint64_t Bytes() const;
  // A hash of its size and every node's cell and parent, made when the tree is finished and kept
  // while it is parked: what the plan caches key a tree by (scheduling/plan_cache.h TreeKey),
  // read without reading the nodes again, so a parked tree has it too.
  std::uint64_t ContentKey() const { return has_key_ ? key_ : ComputeKey(); }

 private:
  friend class CellTreeBuilder;
  friend CellTree Union(const std::vector<const CellTree*>& trees, bool counted);
  friend CellTree ContractTree(const CellTree& tree, const std::vector<CellId>& coarse_of,
                               std::vector<NodeId>* image);
  friend CellTree SubTree(const CellTree& tree, const std::vector<NodeId>& nodes);
  CellTree();
  NodeId AddNode(NodeId parent, CellId cell);
  // Links `child` after the last child of `parent` so far (last_child_).
  void Link(NodeId parent, NodeId child) {
    if (last_child_[parent.index()] == kNoNode) {
      first_child_[parent.index()] = child;
    } else {
      next_sibling_[last_child_[parent.index()].index()] = child;
    }
    last_child_[parent.index()] = child;
  }
  // Room for `nodes` nodes (root included) in every array, exactly.
  void Reserve(std::size_t nodes);
  // Done adding nodes: last_child_ freed, every array shrunk to its nodes, generations computed.
  void Finish();
  void ComputeGenerations();
  std::uint64_t ComputeKey() const;

  MappedArray<CellId> cell_;
  MappedArray<NodeId> parent_;
  MappedArray<std::uint32_t> enter_, visits_;  // at most kMaxRays
  MappedArray<std::uint64_t> samples_;
  MappedArray<std::uint32_t> generation_;
  MappedArray<NodeId> first_child_, next_sibling_;
  MappedArray<NodeId> last_child_;  // for appending in creation order; freed by Finish
  std::uint32_t cell_count_ = 0;
  std::uint64_t rays_ = 0;
  std::uint64_t key_ = 0;  // ContentKey, once finished
  bool has_key_ = false;
  // Parked (Park): the nodes as varints, their number, and whether the tree is counted.
  MappedArray<std::uint8_t> parked_;
  std::size_t parked_size_ = 0;
  bool parked_counted_ = false;
};

// The nodes 1 .. size()-1 (the root left out), in creation order.
class CellTree::NodeRange : public IdRange<NodeId> {
 public:
  constexpr explicit NodeRange(std::uint32_t end) : IdRange(1, end) {}
};
inline CellTree::NodeRange CellTree::nodes() const {
  return NodeRange(static_cast<std::uint32_t>(size()));  // AddNode keeps size() below 2^32
}

// The union of several trees (e.g. two consecutive frames'): a node for every distinct
// root-to-node cell path of any of them, its enter, samples and visits summed, rays summed.
// Every root-to-leaf path of each tree is a root-to-node path of the union, so a schedule
// feasible for the union is feasible for each of them. Trees are merged in order: the
// union of A and B numbers its nodes as a builder fed A's rays, then B's, would.
CellTree UnionTree(const std::vector<const CellTree*>& trees);
// UnionTree's nodes, numbered alike, without its counts (enter, samples and visits read 0,
// counted() is false): what a plan or a prediction reads of it (cells, parents, children,
// generations), in 20 bytes a node instead of 36 (issue 43: the union of two 4096-cell frames
// has millions of nodes). rays() is still the sum.
CellTree UnionShape(const std::vector<const CellTree*>& trees);

// The tree a coarser subdivision gives (issue 23's two levels; docs/design.md §5 "Two-level
// scheduling"): every node's cell mapped by `coarse_of` (per cell of the tree), and a node
// whose coarse cell is its parent's merged into the parent's coarse node, as a ray's
// consecutive visits to one coarse cell merge when a capture is regrouped. So each coarse node
// stands for a connected set of the tree's nodes, all in its coarse cell, and the coarse tree
// is the dependency structure of the coarse cells. Counts are summed (enter: only the rays
// entering a coarse node from another coarse cell). `image`, when given, gets per node of
// `tree` its coarse node (the root's: the root). O(nodes x children).
CellTree ContractTree(const CellTree& tree, const std::vector<CellId>& coarse_of,
                      std::vector<NodeId>* image = nullptr);

// The nodes `nodes` of `tree` (node ids, strictly increasing, no root) as a tree of their
// own, numbered in that order: a node whose parent is not among them hangs from the root.
// Cells and counts are kept.
CellTree SubTree(const CellTree& tree, const std::vector<NodeId>& nodes);

// maxGen(c) for every cell c < tree.cell_count(): the largest generation of a node of c
// (0 for a cell without nodes).
std::vector<std::uint32_t> MaxGenerations(const CellTree& tree);
// Sum over cells of maxGen: the fewest fetches of any schedule with a one-cell cache.
std::uint64_t Bound(const CellTree& tree);

// Streams rays into a Cell Tree. Rays must come in strictly increasing id order (frame-local
// ids, as TraceReader::ForEachBatch delivers them); a parent must come before its children.
//
// Rays come one ray tree at a time: a primary ray, then its descendants (the order in which
// the recorder writes them, and `raycell trace cat` prints them). So a spawned ray's parent
// is in the current tree, and to start it at its parent's node of the spawn visit the
// builder keeps the node of every visit of the current tree only (4 bytes per visit plus
// 16 bytes per ray, looked up by binary search): memory grows with the Cell Tree's nodes,
// not with the frame's rays. A ray whose parent is in an earlier tree is an InputError.
class CellTreeBuilder {
 public:
  CellTreeBuilder();
  // Room for a tree of at most `nodes` nodes besides the root (a frame's visits bound them), so
  // that its arrays are never copied as they grow: pages reserved and never written are not
  // resident (a large frame's arrays had been copied about four times over, at 1.25x a step).
  void Reserve(std::uint64_t nodes);
  // Throws InputError naming the ray id on malformed rays: ids not increasing, unknown
  // parent, spawn index out of range, first cell not the parent's spawn cell, a cell
  // repeated consecutively. The tree is unspecified after an error.
  void AddBatch(const RayBatch& batch);
  void AddRay(const RayView& ray);
  // The tree, with generations computed. The builder is empty afterwards.
  CellTree Finish();
  // Nodes so far (without the root).
  std::size_t node_count() const { return tree_.node_count(); }

 private:
  NodeId Child(NodeId parent, CellId cell);
  NodeId StartNode(const RayView& ray);
  NodeId ParentVisitNode(const RayView& ray) const;

  CellTree tree_;
  static constexpr std::uint32_t kScanChildren = 8;
  std::vector<std::uint32_t> child_counts_{0};  // per node; the root's first
  // (parent << 32 | cell) -> child, for nodes with more than kScanChildren children.
  std::unordered_map<std::uint64_t, NodeId> child_index_;
  std::vector<RayId> ray_ids_;            // increasing
  std::vector<std::uint64_t> ray_begin_;  // ray i's visit nodes start at visit_nodes_[this]
  std::vector<NodeId> visit_nodes_;
  RayId last_id_ = 0;
  bool any_ray_ = false;
};

}  // namespace raycell
