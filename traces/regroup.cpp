#include "traces/regroup.h"

#include <string>

#include "base/check.h"

namespace raycell {

RayRegrouper::RayRegrouper(std::vector<CellId> coarse_of_fine)
    : coarse_of_fine_(std::move(coarse_of_fine)) {}

void RayRegrouper::Reset() {
  tree_first_ = 0;
  tree_offset_.clear();
  merged_.clear();
}

RayBatch RayRegrouper::Regroup(const RayBatch& fine) {
  RayBatch out(fine.store_t());
  out.set_first_id(fine.first_id());
  out.Reserve(fine.size(), fine.visit_count());
  for (std::size_t i = 0; i < fine.size(); ++i) {
    const RayView r = fine.ray(i);
    // Named only in messages: not built per ray.
    const auto ray = [&r] { return "ray " + std::to_string(r.id); };
    std::uint32_t spawn = 0;
    if (r.is_primary()) {
      tree_first_ = r.id;
      tree_offset_.clear();
      merged_.clear();
    } else {
      if (r.parent < tree_first_ || r.parent - tree_first_ >= tree_offset_.size()) {
        throw InputError(ray() + ": its parent " + std::to_string(r.parent) +
                         " is not in its ray tree (rays must come one ray tree at a time)");
      }
      const std::size_t p = std::size_t(r.parent - tree_first_);
      const std::uint64_t begin = tree_offset_[p];
      const std::uint64_t end = p + 1 < tree_offset_.size() ? tree_offset_[p + 1] : merged_.size();
      if (r.spawn >= end - begin) {
        throw InputError(ray() + ": spawn visit " + std::to_string(r.spawn) + " of a parent with " +
                         std::to_string(end - begin) + " visits");
      }
      spawn = merged_[begin + r.spawn];
    }
    if (r.id - tree_first_ != tree_offset_.size()) {
      throw InputError(ray() + ": rays of a ray tree must have consecutive ids");
    }
    tree_offset_.push_back(merged_.size());
    out.BeginRay(r.kind, r.parent, spawn, r.pixel_x, r.pixel_y);
    std::uint32_t visits = 0;
    for (std::size_t v = 0; v < r.visit_count; ++v) {
      const std::uint32_t f = r.cells[v].value();
      if (f >= coarse_of_fine_.size()) {
        throw InputError(ray() + ": visit " + std::to_string(v) + " is in cell " +
                         std::to_string(f) + ", not one of the " +
                         std::to_string(coarse_of_fine_.size()) + " fine cells");
      }
      const CellId c = coarse_of_fine_[f];
      const Visit fv = r.visit(v);
      if (visits > 0 && out.cells().back() == c) {  // the same coarse cell: one visit
        const std::uint64_t s = std::uint64_t{out.samples().back()} + fv.samples;
        if (s > UINT32_MAX) throw InputError(ray() + ": merged samples exceed 2^32 - 1");
        out.AddSamplesToLastVisit(fv.samples);
        if (out.store_t()) out.SetLastExit(fv.t_exit);
      } else {
        out.AddVisit(c, fv.samples, fv.t_enter, fv.t_exit);
        ++visits;
      }
      merged_.push_back(visits - 1);
    }
  }
  return out;
}

}  // namespace raycell
