#include "traces/ray_batch.h"

#include "base/check.h"

namespace raycell {

const char* ToString(RayKind kind) {
  switch (kind) {
    case RayKind::kPrimary:
      return "primary";
    case RayKind::kReflection:
      return "reflection";
    case RayKind::kRefraction:
      return "refraction";
    case RayKind::kShadow:
      return "shadow";
  }
  return "unknown";
}

std::optional<RayKind> ParseRayKind(std::string_view name) {
  for (int k = 0; k < kRayKindCount; ++k) {
    if (name == ToString(static_cast<RayKind>(k))) return static_cast<RayKind>(k);
  }
  return std::nullopt;
}

std::size_t RayBatch::BeginRay(RayKind kind, RayId parent, std::uint32_t spawn, std::uint32_t px,
                               std::uint32_t py) {
  kind_.push_back(kind);
  parent_.push_back(parent);
  spawn_.push_back(spawn);
  px_.push_back(px);
  py_.push_back(py);
  visit_begin_.push_back(cells_.size());
  return kind_.size() - 1;
}

void RayBatch::AddVisit(CellId cell, std::uint32_t samples, float t_enter, float t_exit) {
  RAYCELL_CHECK(!kind_.empty());
  cells_.push_back(cell);
  samples_.push_back(samples);
  if (store_t_) {
    t_enter_.push_back(t_enter);
    t_exit_.push_back(t_exit);
  }
  visit_begin_.back() = cells_.size();
}

void RayBatch::PopRay() {
  RAYCELL_CHECK(!kind_.empty());
  kind_.pop_back();
  parent_.pop_back();
  spawn_.pop_back();
  px_.pop_back();
  py_.pop_back();
  visit_begin_.pop_back();
  const std::size_t n = visit_begin_.back();
  cells_.resize(n);
  samples_.resize(n);
  if (store_t_) {
    t_enter_.resize(n);
    t_exit_.resize(n);
  }
}

void RayBatch::AppendRebased(const RayBatch& other) {
  RAYCELL_CHECK(other.store_t_ == store_t_ || !store_t_);
  const RayId offset = first_id_ + size();
  kind_.insert(kind_.end(), other.kind_.begin(), other.kind_.end());
  for (RayId p : other.parent_) {
    parent_.push_back(p == kNoParent ? kNoParent : p - other.first_id_ + offset);
  }
  spawn_.insert(spawn_.end(), other.spawn_.begin(), other.spawn_.end());
  px_.insert(px_.end(), other.px_.begin(), other.px_.end());
  py_.insert(py_.end(), other.py_.begin(), other.py_.end());
  const std::uint64_t base = cells_.size();
  for (std::size_t i = 1; i < other.visit_begin_.size(); ++i) {
    visit_begin_.push_back(base + other.visit_begin_[i]);
  }
  cells_.insert(cells_.end(), other.cells_.begin(), other.cells_.end());
  samples_.insert(samples_.end(), other.samples_.begin(), other.samples_.end());
  if (store_t_) {
    t_enter_.insert(t_enter_.end(), other.t_enter_.begin(), other.t_enter_.end());
    t_exit_.insert(t_exit_.end(), other.t_exit_.begin(), other.t_exit_.end());
  }
}

void RayBatch::Rebase(RayId first_id) {
  for (RayId& p : parent_) {
    if (p != kNoParent && p >= first_id_) p = p - first_id_ + first_id;
  }
  first_id_ = first_id;
}

void RayBatch::Clear() {
  kind_.clear();
  parent_.clear();
  spawn_.clear();
  px_.clear();
  py_.clear();
  visit_begin_.assign(1, 0);
  cells_.clear();
  samples_.clear();
  t_enter_.clear();
  t_exit_.clear();
}

void RayBatch::Reserve(std::size_t rays, std::size_t visits) {
  kind_.reserve(rays);
  parent_.reserve(rays);
  spawn_.reserve(rays);
  px_.reserve(rays);
  py_.reserve(rays);
  visit_begin_.reserve(rays + 1);
  cells_.reserve(visits);
  samples_.reserve(visits);
  if (store_t_) {
    t_enter_.reserve(visits);
    t_exit_.reserve(visits);
  }
}

RayView RayBatch::ray(std::size_t i) const {
  const std::size_t b = visit_begin_[i];
  return RayView{first_id_ + i,
                 parent_[i],
                 spawn_[i],
                 kind_[i],
                 px_[i],
                 py_[i],
                 cells_.data() + b,
                 samples_.data() + b,
                 store_t_ ? t_enter_.data() + b : nullptr,
                 store_t_ ? t_exit_.data() + b : nullptr,
                 visit_begin_[i + 1] - b};
}

bool RayBatch::operator==(const RayBatch& o) const {
  return store_t_ == o.store_t_ && first_id_ == o.first_id_ && kind_ == o.kind_ &&
         parent_ == o.parent_ && spawn_ == o.spawn_ && px_ == o.px_ && py_ == o.py_ &&
         visit_begin_ == o.visit_begin_ && cells_ == o.cells_ && samples_ == o.samples_ &&
         t_enter_ == o.t_enter_ && t_exit_ == o.t_exit_;
}

}  // namespace raycell
