// Rays and visits of one frame, as the renderer produces them and the trace stores them
// (docs/design.md §1 "Rays and visits"). A RayBatch is a run of consecutive rays of one frame
// held as a struct of arrays, so a batch of a million shadow rays costs a handful of
// allocations, not a million.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "traces/cell_id.h"

namespace raycell {

using RayId = std::uint64_t;

inline constexpr RayId kNoParent = std::numeric_limits<RayId>::max();

enum class RayKind : std::uint8_t { kPrimary = 0, kReflection = 1, kRefraction = 2, kShadow = 3 };
inline constexpr int kRayKindCount = 4;

// "primary", "reflection", "refraction", "shadow".
const char* ToString(RayKind kind);
std::optional<RayKind> ParseRayKind(std::string_view name);

// One non-empty cell a ray passes through: its cell, the volume samples taken there and
// the ray parameter where it enters and leaves the cell (world units along the ray's
// unit direction).
struct Visit {
  CellId cell{0};
  std::uint32_t samples = 0;
  float t_enter = 0.f;
  float t_exit = 0.f;
  bool operator==(const Visit& o) const {
    return cell == o.cell && samples == o.samples && t_enter == o.t_enter && t_exit == o.t_exit;
  }
};

// Read-only view of one ray inside a RayBatch.
struct RayView {
  RayId id;
  RayId parent;         // kNoParent for primary rays
  std::uint32_t spawn;  // index into the parent's visits; 0 for primary rays
  RayKind kind;
  std::uint32_t pixel_x, pixel_y;
  const CellId* cells;
  const std::uint32_t* samples;
  const float* t_enter;  // nullptr when the batch stores no t
  const float* t_exit;
  std::size_t visit_count;
  bool is_primary() const { return parent == kNoParent; }
  Visit visit(std::size_t i) const {
    return {cells[i], samples[i], t_enter ? t_enter[i] : 0.f, t_exit ? t_exit[i] : 0.f};
  }
};

class RayBatch {
 public:
  explicit RayBatch(bool store_t = true) : store_t_(store_t) {}

  bool store_t() const { return store_t_; }
  std::size_t size() const { return kind_.size(); }
  bool empty() const { return kind_.empty(); }
  std::size_t visit_count() const { return cells_.size(); }
  RayId first_id() const { return first_id_; }
  void set_first_id(RayId id) { first_id_ = id; }

  // Starts a new ray; its visits follow with AddVisit. Returns its index in the batch.
  std::size_t BeginRay(RayKind kind, RayId parent, std::uint32_t spawn, std::uint32_t px,
                       std::uint32_t py);
  void AddVisit(CellId cell, std::uint32_t samples, float t_enter, float t_exit);
  // Adds `samples` to the last visit of the last ray (which must have one).
  void AddSamplesToLastVisit(std::uint32_t samples) { samples_.back() += samples; }
  // Sets the t_exit of the last visit of the last ray (which must have one), if t is stored.
  void SetLastExit(float t_exit) {
    if (store_t_) t_exit_.back() = t_exit;
  }
  // Removes the last ray and its visits.
  void PopRay();
  // Appends all rays of `other`, offsetting parent ids that point inside `other` so they
  // keep pointing at the same rays. `other`'s ids are relative to its first_id().
  void AppendRebased(const RayBatch& other);
  // Renumbers the batch to start at `first_id`, shifting parent ids that point inside it
  // (those >= first_id()) along; ids of parents before the batch are kept.
  void Rebase(RayId first_id);
  void Clear();
  void Reserve(std::size_t rays, std::size_t visits);

  RayView ray(std::size_t i) const;
  std::size_t visit_begin(std::size_t i) const { return visit_begin_[i]; }
  std::size_t visit_end(std::size_t i) const { return visit_begin_[i + 1]; }

  // Raw columns, for the trace writer and tests.
  const std::vector<RayKind>& kinds() const { return kind_; }
  const std::vector<RayId>& parents() const { return parent_; }
  const std::vector<std::uint32_t>& spawns() const { return spawn_; }
  const std::vector<std::uint32_t>& pixel_xs() const { return px_; }
  const std::vector<std::uint32_t>& pixel_ys() const { return py_; }
  const std::vector<CellId>& cells() const { return cells_; }
  const std::vector<std::uint32_t>& samples() const { return samples_; }
  const std::vector<float>& t_enters() const { return t_enter_; }
  const std::vector<float>& t_exits() const { return t_exit_; }

  bool operator==(const RayBatch& o) const;
  bool operator!=(const RayBatch& o) const { return !(*this == o); }

 private:
  bool store_t_;
  RayId first_id_ = 0;
  std::vector<RayKind> kind_;
  std::vector<RayId> parent_;
  std::vector<std::uint32_t> spawn_;
  std::vector<std::uint32_t> px_, py_;
  std::vector<std::uint64_t> visit_begin_{0};
  std::vector<CellId> cells_;
  std::vector<std::uint32_t> samples_;
  std::vector<float> t_enter_, t_exit_;
};

}  // namespace raycell
