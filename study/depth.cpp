#include "study/depth.h"

#include <numeric>

#include "base/check.h"
#include "replay/config.h"
#include "runner/driver.h"
#include "scheduling/cell_tree_scheduler.h"
#include "scheduling/max_work.h"
#include "scheduling/scheduler.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

// The capture of max depth knob `k`: its rays by kind from the trace's index, its Cell Tree
// nodes and its replays under Max Work and Cell Tree scheduling (one pass over the frames).
DepthRow MeasureCapture(const AccuracyOptions& o, const AccuracyKnob& k) {
  DepthRow row;
  row.max_depth = *k.max_depth;
  row.is_default = k.is_default;
  const TraceReader reader = TraceReader::Open(KnobTrace(o, k));
  for (const FrameSummary& f : reader.frames()) {
    row.rays += f.rays;
    for (int kind = 0; kind < kRayKindCount; ++kind) row.rays_by_kind[kind] += f.rays_by_kind[kind];
  }
  std::vector<ReplayConfig> configs;
  for (const SchedulerEntry* scheduler : {&kMaxWorkEntry, &kCellTreeEntry}) {
    ReplayConfig config = DefaultConfig();
    config.scheduler = scheduler;
    config.granularity = ReplayConfig::Granularity::kNode;  // exact with a one-cell cache
    configs.push_back(config);
  }
  std::vector<std::size_t> all(reader.frames().size());
  std::iota(all.begin(), all.end(), std::size_t{0});
  std::vector<ReplayResult> totals(configs.size());
  ReplayFrames(reader, all, configs, {},
               [&](const LoadedFrame& frame, const std::vector<ReplayResult>& results) {
                 row.nodes += frame.tree->node_count();
                 for (std::size_t c = 0; c < results.size(); ++c) {
                   Accumulate(results[c], &totals[c]);
                 }
                 return true;
               });
  for (ReplayResult& t : totals) {
    FinishTotal(1, &t);
    RAYCELL_CHECK_EQ(t.rays, row.rays);  // every ray of the trace was replayed
  }
  row.fetches_maxwork = totals[0].fetches, row.time_maxwork = totals[0].time;
  row.fetches_celltree = totals[1].fetches, row.time_celltree = totals[1].time;
  return row;
}

}  // namespace

DepthStudy MeasureDepth(const AccuracyStudy& accuracy) {
  DepthStudy study;
  study.options = accuracy.options;
  if (!accuracy.measured) {
    study.not_measured = !accuracy.not_measured.empty()
                             ? accuracy.not_measured
                             : "it reads the run time against error section's captures, which "
                               "`--accuracy-frames 0` skipped";
    return study;
  }
  const std::vector<AccuracyKnob>& knobs = AccuracyKnobs();
  RAYCELL_CHECK_EQ(accuracy.rows.size(), knobs.size());
  for (std::size_t i = 0; i < knobs.size(); ++i) {
    if (knobs[i].part != AccuracyPart::kDepth) continue;
    DepthRow row = MeasureCapture(accuracy.options, knobs[i]);
    row.rmse = accuracy.rows[i].error;
    study.rows.push_back(row);
  }
  study.measured = true;
  return study;
}

}  // namespace raycell
