#include "replay/work.h"

#include <algorithm>
#include <numeric>
#include <string>

#include "base/check.h"
#include "base/checked.h"
#include "base/kept_room.h"
#include "replay/time_bound.h"

namespace raycell {
namespace {

std::uint64_t Sum(const std::vector<std::uint64_t>& v) {
  std::uint64_t sum = 0;
  for (std::uint64_t x : v) CheckedIncrement(sum, x);
  return sum;
}

// Fills succ from (unit, successor) pairs, keeping their order per unit.
void BuildSuccessors(WorkGraph& w, const std::vector<std::pair<UnitId, UnitId>>& edges) {
  w.succ_begin.assign(w.size() + 1, 0);
  for (const auto& e : edges) ++w.succ_begin[e.first + 1];
  std::partial_sum(w.succ_begin.begin(), w.succ_begin.end(), w.succ_begin.begin());
  w.succ.resize(edges.size());
  std::vector<UnitId> fill(w.succ_begin.begin(), w.succ_begin.end() - 1);
  for (const auto& e : edges) w.succ[fill[e.first]++] = e.second;
}

void Resize(WorkGraph& w, std::size_t n) {
  w.cell.resize(n);
  w.samples.resize(n);
  w.queued_rays.resize(n);
  w.segments.resize(n);
  w.rays_started.resize(n);
}

}  // namespace

// The totals and the packed units, once the columns are complete.
void Finish(WorkGraph& w) {
  w.totals = {Sum(w.samples), Sum(w.segments), Sum(w.rays_started)};
  w.packed.clear();
  // First the records in unit order, a sequential pass (succ_begin in first_child for now),
  // so that the breadth-first pass below reads one record per unit, not four columns.
  std::vector<WorkGraph::Packed> by_unit(w.size() + 1);
  for (std::size_t u = 0; u < w.size(); ++u) {
    if (w.samples[u] > UINT32_MAX || w.queued_rays[u] > UINT32_MAX) return;  // columns, then
    by_unit[u] = {w.cell[u], std::uint32_t(w.samples[u]), std::uint32_t(w.queued_rays[u]),
                  w.succ_begin[u]};
  }
  by_unit.back().first_child = w.succ_begin.back();
  // Breadth first: entry i stands for unit order[i]; its successors get the next entries.
  // Every unit must be reached exactly once (a forest from the roots), else the columns.
  std::vector<UnitId> order;
  order.reserve(w.size());
  std::vector<bool> reached(w.size(), false);
  const auto reach = [&](UnitId u) {
    if (reached[u]) return false;
    reached[u] = true;
    order.push_back(u);
    return true;
  };
  for (UnitId u : w.roots) {
    if (!reach(u)) return;
  }
  w.packed.resize(w.size() + 1);
  for (std::size_t i = 0; i < order.size(); ++i) {
    const UnitId u = order[i];
    const WorkGraph::Packed r = by_unit[u];
    w.packed[i] = {r.cell, r.samples, r.queued_rays, std::uint32_t(order.size())};
    for (UnitId k = r.first_child; k < by_unit[u + 1].first_child; ++k) {
      if (!reach(w.succ[k])) {
        w.packed.clear();
        return;
      }
    }
  }
  if (order.size() != w.size()) {  // some units unreachable
    w.packed.clear();
    return;
  }
  w.packed.back() = {kNoCell, 0, 0, std::uint32_t(w.size())};
}

WorkGraph RaySegmentWork(const RayBatch& frame, std::uint32_t cells) {
  RAYCELL_CHECK_EQ(frame.first_id(), RayId{0});
  RAYCELL_CHECK_LT(frame.visit_count(), std::size_t{UINT32_MAX});
  WorkGraph w;
  w.cells = cells;
  Resize(w, frame.visit_count());
  std::vector<std::pair<UnitId, UnitId>> edges;
  edges.reserve(frame.visit_count());
  for (std::size_t r = 0; r < frame.size(); ++r) {
    const auto begin = UnitId(frame.visit_begin(r)), end = UnitId(frame.visit_end(r));
    if (begin == end) continue;
    const RayView ray = frame.ray(r);
    for (UnitId u = begin; u < end; ++u) {
      w.cell[u] = ray.cells[u - begin];
      w.samples[u] = ray.samples[u - begin];
      w.segments[u] = 1;
      w.queued_rays[u] = u == begin && !ray.is_primary() ? 0 : 1;
      if (u + 1 < end) edges.emplace_back(u, u + 1);
    }
    w.rays_started[begin] = 1;
    if (ray.is_primary()) {
      w.roots.push_back(begin);
    } else {
      edges.emplace_back(UnitId(frame.visit_begin(ray.parent) + ray.spawn), begin);
    }
  }
  BuildSuccessors(w, edges);
  Finish(w);
  w.shape = ShapeOf(w);
  return w;
}

void RaySegmentWorkBuilder::Reserve(const FrameSummary& summary) {
  // A summary is checked against its frame only once the frame is read: cap what it asks.
  const std::uint64_t rays = std::min<std::uint64_t>(summary.rays, UINT32_MAX);
  const std::uint64_t primary =
      std::min<std::uint64_t>(summary.rays_by_kind[std::size_t(RayKind::kPrimary)], rays);
  visit_begin_.reserve(rays);
  w_.compact.roots.reserve(primary);
  w_.compact.spawned.reserve(rays - primary);
  // Two varints of 1-2 bytes a visit, usually.
  w_.compact.stream.reserve(std::min<std::uint64_t>(summary.visits, UINT32_MAX / 4) * 4);
}

void RaySegmentWorkBuilder::AddBatch(const RayBatch& batch) {
  WorkGraph::Compact& c = w_.compact;
  if (batch.first_id() != rays_) {
    throw InputError("per-segment work: batch starts at ray " + std::to_string(batch.first_id()) +
                     ", expected " + std::to_string(rays_));
  }
  for (std::size_t r = 0; r < batch.size(); ++r) {
    const RayView ray = batch.ray(r);
    const std::size_t n = ray.visit_count;
    visit_begin_.push_back(std::uint32_t(visits_));  // the parent's visits: up to the next ray's
    ++rays_;
    if (n == 0) continue;  // no work, no spawned rays (as in RaySegmentWork)
    if (visits_ + n >= UINT32_MAX || c.stream.size() >= UINT32_MAX - 20 * n) {
      throw InputError("per-segment work: frame of more than 2^32 visits or stream bytes");
    }
    const WorkGraph::CompactUnit first{std::uint32_t(c.stream.size()), 0};
    if (ray.is_primary()) {
      c.roots.push_back(first);
    } else {
      const RayId parent = ray.parent;
      if (parent >= ray.id || ray.spawn >= visit_begin_[parent + 1] - visit_begin_[parent]) {
        throw InputError("per-segment work: ray " + std::to_string(ray.id) +
                         " has an unknown parent or spawn visit");
      }
      // `at` the parent visit's number until Finish makes it its record's offset.
      c.spawned.push_back({visit_begin_[parent] + ray.spawn, first});
    }
    for (std::size_t v = 0; v < n; ++v) {
      AppendVarint(c.stream, ray.cells[v].value() * 2 + (v + 1 == n ? 1 : 0));
      AppendVarint(c.stream, ray.samples[v]);
      CheckedIncrement(w_.totals.samples, std::uint64_t{ray.samples[v]});
    }
    visits_ += n;
    ++w_.totals.rays;
    w_.totals.segments += n;
  }
}

WorkGraph RaySegmentWorkBuilder::Finish() {
  FreeRoom(visit_begin_);
  WorkGraph::Compact& c = w_.compact;
  c.units = visits_;
  // The rays spawned at one visit together, in ray order (their first records' offsets
  // increase with the ray id).
  std::sort(c.spawned.begin(), c.spawned.end(),
            [](const WorkGraph::Spawned& a, const WorkGraph::Spawned& b) {
              return a.at != b.at ? a.at < b.at : a.unit.offset < b.unit.offset;
            });
  // Each `at` from the visit's number to its record's offset, in one pass over the stream (both
  // increase together, so the order stays).
  {
    std::uint32_t offset = 0, visit = 0;
    for (WorkGraph::Spawned& s : c.spawned) {
      for (; visit < s.at; ++visit) {
        ReadVarint(c.stream.data(), &offset);
        ReadVarint(c.stream.data(), &offset);
      }
      s.at = offset;
    }
  }
  const auto first_spawned = [&c](std::uint32_t offset) {
    return std::uint32_t(
        std::lower_bound(c.spawned.begin(), c.spawned.end(), offset,
                         [](const WorkGraph::Spawned& s, std::uint32_t o) { return s.at < o; }) -
        c.spawned.begin());
  };
  for (WorkGraph::CompactUnit& u : c.roots) u.spawned = first_spawned(u.offset);
  for (WorkGraph::Spawned& s : c.spawned) s.unit.spawned = first_spawned(s.unit.offset);
  WorkGraph out = std::move(w_);
  out.shape = ShapeOf(out);
  w_ = WorkGraph{};
  w_.cells = out.cells;
  visits_ = 0;
  rays_ = 0;
  return out;
}

WorkGraph NodeWork(const CellTree& tree, std::uint32_t cells) {
  WorkGraph w;
  w.cells = cells;
  Resize(w, tree.node_count());
  std::vector<std::pair<UnitId, UnitId>> edges;
  for (NodeId n : tree.nodes()) {
    const UnitId u = n.index() - 1;
    w.cell[u] = tree.cell(n);
    w.samples[u] = tree.samples(n);
    w.queued_rays[u] = tree.enter(n);
    w.segments[u] = tree.visits(n);
    // Rays begin here: primary rays entering a child of the root, and spawned rays (the
    // visits that did not enter).
    w.rays_started[u] =
        (tree.parent(n) == kRootNode ? tree.enter(n) : 0) + (tree.visits(n) - tree.enter(n));
    if (tree.parent(n) == kRootNode) {
      w.roots.push_back(u);
    } else {
      edges.emplace_back(tree.parent(n).index() - 1, u);
    }
  }
  BuildSuccessors(w, edges);
  Finish(w);
  w.shape = ShapeOf(w);
  w.per_node = true;
  return w;
}

WorkGraph PackedNodeWork(const CellTree& tree, std::uint32_t cells) {
  for (NodeId n : tree.nodes()) {
    if (tree.samples(n) > UINT32_MAX || tree.enter(n) > UINT32_MAX) return NodeWork(tree, cells);
  }
  WorkGraph w;
  w.cells = cells;
  // Unit n - 1 stands for node n, as in NodeWork; its successors are the node's children in
  // creation order (NodeWork's edges, made in node order). Breadth first from the root's
  // children, as Finish lays the records out.
  std::vector<NodeId> order;
  order.reserve(tree.node_count());
  for (NodeId c = tree.first_child(kRootNode); c != kNoNode; c = tree.next_sibling(c)) {
    order.push_back(c);
  }
  w.roots.reserve(order.size());
  for (NodeId c : order) w.roots.push_back(c.index() - 1);
  w.packed.resize(tree.node_count() + 1);
  for (std::size_t i = 0; i < order.size(); ++i) {
    const NodeId n = order[i];
    w.packed[i] = {tree.cell(n), std::uint32_t(tree.samples(n)), std::uint32_t(tree.enter(n)),
                   std::uint32_t(order.size())};
    CheckedIncrement(w.totals.samples, tree.samples(n));
    CheckedIncrement(w.totals.segments, tree.visits(n));
    CheckedIncrement(w.totals.rays, (tree.parent(n) == kRootNode ? tree.enter(n) : 0) +
                                        (tree.visits(n) - tree.enter(n)));
    for (NodeId c = tree.first_child(n); c != kNoNode; c = tree.next_sibling(c)) {
      order.push_back(c);
    }
  }
  RAYCELL_CHECK_EQ(order.size(), tree.node_count());  // every node hangs from the root
  w.packed.back() = {kNoCell, 0, 0, std::uint32_t(order.size())};
  w.shape = ShapeOf(w);
  w.per_node = true;
  return w;
}

RayBatch SampleRayTrees(const RayBatch& frame, std::uint32_t k) {
  RAYCELL_CHECK(k >= 1);
  RayBatch out(frame.store_t());
  std::vector<RayId> new_id(frame.size(), kNoParent);
  std::uint64_t tree = 0;
  bool keep = false;
  for (std::size_t r = 0; r < frame.size(); ++r) {
    const RayView ray = frame.ray(r);
    if (ray.is_primary()) keep = tree++ % k == 0;
    if (!keep) continue;
    new_id[r] = out.size();
    const RayId parent = ray.is_primary() ? kNoParent : new_id[ray.parent - frame.first_id()];
    out.BeginRay(ray.kind, parent, ray.spawn, ray.pixel_x, ray.pixel_y);
    for (std::size_t v = 0; v < ray.visit_count; ++v) {
      const Visit visit = ray.visit(v);
      out.AddVisit(visit.cell, visit.samples, visit.t_enter, visit.t_exit);
    }
  }
  return out;
}

}  // namespace raycell
