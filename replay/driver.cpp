#include "replay/driver.h"

#include <memory>

#include "base/check.h"
#include "base/checked.h"
#include "graph/analysis.h"
#include "scheduling/scheduler.h"

namespace raycell {
namespace {

void Accumulate(const ReplayResult& f, ReplayResult* t) {
  if (t->levels.empty()) t->levels.assign(f.levels.size(), {});
  for (std::size_t i = 0; i < f.levels.size(); ++i) {
    t->levels[i].name = f.levels[i].name;
    CheckedIncrement(t->levels[i].fetches, f.levels[i].fetches);
    CheckedIncrement(t->levels[i].bytes, f.levels[i].bytes);
  }
  CheckedIncrement(t->fetches, f.fetches);
  if (f.bound) t->bound = CheckedAdd(t->bound.value_or(0), *f.bound);
  t->time = t->time + f.time;
  t->work = t->work + f.work;
  t->stall = t->stall + f.stall;
  t->idle = t->idle + f.idle;
  t->peak_queued_rays = std::max(t->peak_queued_rays, f.peak_queued_rays);
  t->peak_queued_bytes = std::max(t->peak_queued_bytes, f.peak_queued_bytes);
  CheckedIncrement(t->rays, f.rays);
  CheckedIncrement(t->segments, f.segments);
  CheckedIncrement(t->samples, f.samples);
  CheckedIncrement(t->events, f.events);
  CheckedIncrement(t->prefetches, f.prefetches);
  CheckedIncrement(t->prefetch_hits, f.prefetch_hits);
  t->passes = std::max(t->passes, f.passes);
  t->min_converged = t->min_converged && f.min_converged;
}

}  // namespace

namespace {

// A frame's rays (sampled) and its Cell Tree.
struct Frame {
  RayBatch rays{false};
  std::unique_ptr<CellTree> tree;
};

Frame LoadFrame(const TraceReader& reader, std::size_t i, bool need_rays, std::uint32_t k) {
  Frame f;
  if (!need_rays && k == 1) {  // per node the tree is all the replay needs: stream it
    f.tree = std::make_unique<CellTree>(BuildFrameTree(reader, i));
    return f;
  }
  f.rays = SampleRayTrees(reader.LoadFrame(i), k);
  CellTreeBuilder builder;
  builder.AddBatch(f.rays);
  f.tree = std::make_unique<CellTree>(builder.Finish());
  return f;
}

void ScaleBack(ReplayResult& r, std::uint32_t k, std::uint32_t processors) {
  if (k == 1) return;
  const SimTime extra = r.work * (k - 1);
  r.rays = CheckedMul(r.rays, k);
  r.segments = CheckedMul(r.segments, k);
  r.samples = CheckedMul(r.samples, k);
  r.work = r.work * k;
  r.time = r.time + SimTime::Picoseconds(extra.picoseconds() / processors);
}

}  // namespace

TraceReplay ReplayTrace(const TraceReader& reader, const std::vector<std::size_t>& frame_indices,
                        const ReplayConfig& config, const std::function<void(double)>& progress,
                        std::uint32_t sample_every, ReplayObserver* observer) {
  if (sample_every < 1) throw InputError("sampling: 1 in k ray trees needs k >= 1");
  RAYCELL_CHECK(observer == nullptr || sample_every == 1);
  const TraceHeader& h = reader.header();
  const CellId cells = h.cell_count();
  const bool per_ray = EffectiveGranularity(config) == ReplayConfig::Granularity::kRay;
  std::unique_ptr<Scheduler> scheduler = MakeScheduler(config.scheduler, config.seed);
  TraceReplay out;
  std::unique_ptr<CellTree> previous;
  std::size_t previous_index = SIZE_MAX;
  for (std::size_t k = 0; k < frame_indices.size(); ++k) {
    const std::size_t i = frame_indices[k];
    if (i > 0 && previous_index != i - 1) {  // Cell Tree scheduling needs frame i-1's tree
      previous = LoadFrame(reader, i - 1, false, sample_every).tree;
    }
    Frame f = LoadFrame(reader, i, per_ray, sample_every);
    const FrameInfo info{i, f.tree.get(), i > 0 ? previous.get() : nullptr, cells};
    const WorkGraph work = per_ray ? RaySegmentWork(f.rays, cells) : NodeWork(*f.tree, cells);
    ReplayResult r =
        ReplayFrame(work, h.footprints, config, *scheduler, info, Bound(*f.tree), observer);
    ScaleBack(r, sample_every, config.processors.count);
    r.frame = reader.frames()[i].frame;
    Accumulate(r, &out.total);
    out.frames.push_back(std::move(r));
    previous = std::move(f.tree);
    previous_index = i;
    if (progress) progress(double(k + 1) / frame_indices.size());
  }
  const double capacity = double(out.total.time.picoseconds()) * config.processors.count;
  out.total.utilisation = capacity > 0 ? double(out.total.work.picoseconds()) / capacity : 0.0;
  return out;
}

}  // namespace raycell
