#include "traces/regroup.h"

#include <string>

#include "base/check.h"

namespace raycell {

RayRegrouper::RayRegrouper(std::vector<CellId> coarse_of_fine)
    : coarse_of_fine_(std::move(coarse_of_fine)) {}

void RayRegrouper::Reset() {
  tree_first_ = 0;
  next_id_ = 0;
  tree_offset_.clear();
  tree_out_.clear();
  merged_.clear();
  merged_cell_.clear();
}

RayBatch RayRegrouper::Regroup(const RayBatch& fine) {
  constexpr std::uint32_t kLeading = UINT32_MAX;  // a dropped visit before any kept one
  RayBatch out(fine.store_t());
  out.set_first_id(next_id_);
  out.Reserve(fine.size(), fine.visit_count());
  for (std::size_t i = 0; i < fine.size(); ++i) {
    const RayView r = fine.ray(i);
    // Named only in messages: not built per ray.
    const auto ray = [&r] { return "ray " + std::to_string(r.id); };
    std::uint32_t spawn = 0;
    RayId parent = kNoParent;
    CellId spawn_cell = kNoCell;
    if (r.is_primary()) {
      tree_first_ = r.id;
      tree_offset_.clear();
      tree_out_.clear();
      merged_.clear();
      merged_cell_.clear();
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
      parent = tree_out_[p];
      if (parent == kNoParent) throw InputError(ray() + ": its parent visits only empty cells");
      spawn = merged_[begin + r.spawn];
      spawn_cell = merged_cell_[begin + r.spawn];
    }
    if (r.id - tree_first_ != tree_offset_.size()) {
      throw InputError(ray() + ": rays of a ray tree must have consecutive ids");
    }
    // The ray's visits in the subdivision: consecutive visits in one cell merged, visits to
    // an empty cell dropped, their samples (and spawns) going to the visit before them, or to
    // the first one when none is before (a capture's rule for a sample between its visits).
    kept_.clear();
    fine_to_kept_.clear();
    std::uint64_t leading = 0;
    for (std::size_t v = 0; v < r.visit_count; ++v) {
      const std::uint32_t f = r.cells[v].value();
      if (f >= coarse_of_fine_.size()) {
        throw InputError(ray() + ": visit " + std::to_string(v) + " is in cell " +
                         std::to_string(f) + ", not one of the " +
                         std::to_string(coarse_of_fine_.size()) + " fine cells");
      }
      const CellId c = coarse_of_fine_[f];
      const Visit fv = r.visit(v);
      if (c == kNoCell) {
        if (kept_.empty()) {
          leading += fv.samples;
          fine_to_kept_.push_back(kLeading);
        } else {
          kept_.back().samples += fv.samples;
          fine_to_kept_.push_back(std::uint32_t(kept_.size() - 1));
        }
        continue;
      }
      if (!kept_.empty() && kept_.back().cell == c) {
        kept_.back().samples += fv.samples;
        kept_.back().t_exit = fv.t_exit;
      } else {
        kept_.push_back({c, fv.samples, fv.t_enter, fv.t_exit});
      }
      fine_to_kept_.push_back(std::uint32_t(kept_.size() - 1));
    }
    // A spawned ray starts with its spawn visit's cell, as a capture on these cells starts it:
    // a zero-length visit there when the ray's first cell is another (its start point lies
    // outside the spawn cell) or it has no other.
    std::uint32_t shift = 0;
    if (!r.is_primary() && (kept_.empty() || kept_.front().cell != spawn_cell)) {
      const float t = r.visit_count > 0 ? r.visit(0).t_enter : 0.f;
      kept_.insert(kept_.begin(), {spawn_cell, 0, t, t});
      shift = 1;
    }
    tree_offset_.push_back(merged_.size());
    if (kept_.empty()) {  // a primary ray in empty cells only: not recorded
      if (leading != 0) {
        throw InputError(ray() + ": " + std::to_string(leading) +
                         " samples in cells that are empty (footprint 0)");
      }
      for (std::size_t v = 0; v < r.visit_count; ++v) {
        merged_.push_back(0);
        merged_cell_.push_back(kNoCell);
      }
      tree_out_.push_back(kNoParent);
      continue;
    }
    kept_.front().samples += leading;
    for (std::uint32_t k : fine_to_kept_) {
      const std::uint32_t m = k == kLeading ? 0 : k + shift;
      merged_.push_back(m);
      merged_cell_.push_back(kept_[m].cell);
    }
    out.BeginRay(r.kind, parent, spawn, r.pixel_x, r.pixel_y);
    for (const Kept& k : kept_) {
      if (k.samples > UINT32_MAX) throw InputError(ray() + ": merged samples exceed 2^32 - 1");
      out.AddVisit(k.cell, std::uint32_t(k.samples), k.t_enter, k.t_exit);
    }
    tree_out_.push_back(next_id_++);
  }
  return out;
}

}  // namespace raycell
