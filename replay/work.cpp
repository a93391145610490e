#include "replay/work.h"

#include <numeric>

#include "base/check.h"

namespace raycell {
namespace {

std::uint64_t Sum(const std::vector<std::uint64_t>& v) {
  return std::accumulate(v.begin(), v.end(), std::uint64_t{0});
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

std::uint64_t WorkGraph::total_samples() const { return Sum(samples); }
std::uint64_t WorkGraph::total_segments() const { return Sum(segments); }
std::uint64_t WorkGraph::total_rays() const { return Sum(rays_started); }

WorkGraph RaySegmentWork(const RayBatch& frame, CellId cells) {
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
  return w;
}

WorkGraph NodeWork(const CellTree& tree, CellId cells) {
  WorkGraph w;
  w.cells = cells;
  Resize(w, tree.node_count());
  std::vector<std::pair<UnitId, UnitId>> edges;
  for (NodeId n = 1; n < tree.size(); ++n) {
    const UnitId u = n - 1;
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
      edges.emplace_back(tree.parent(n) - 1, u);
    }
  }
  BuildSuccessors(w, edges);
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
