#include "runner/result_table.h"

namespace raycell {

void AddResult(const ReplayResult& r, const ResultColumns& columns, StatsTable* t) {
  t->AddCount("fetches", r.fetches);
  if (r.bound) {
    t->AddCount("bound", *r.bound);
  } else {
    t->AddNone("bound");
  }
  t->AddCount("time_ps", r.time.picoseconds())
      .AddCount("time_bound_ps", r.time_bound.picoseconds())
      .AddCount("work_ps", r.work.picoseconds())
      .AddCount("stall_ps", r.stall.picoseconds())
      .AddCount("idle_ps", r.idle.picoseconds())
      .AddFixed("utilisation", r.utilisation, 4)
      .AddCount("peak_queued_rays", r.peak_queued_rays)
      .AddCount("peak_queued_bytes", r.peak_queued_bytes)
      .AddCount("rays", r.rays)
      .AddCount("segments", r.segments)
      .AddCount("samples", r.samples);
  if (columns.extras) {
    t->AddCount("prefetches", r.prefetches)
        .AddCount("prefetch_hits", r.prefetch_hits)
        .AddBool("min_converged", r.min_converged)
        .AddCount("decisions", r.decisions)
        .AddCount("decision_steps", r.decision_steps)
        .AddCount("scheduler_bytes", r.scheduler_bytes);
  }
  if (columns.levels) {
    StatTables levels;
    for (const LevelStats& l : r.levels) {
      levels.emplace_back();
      levels.back()
          .AddText("name", l.name)
          .AddCount("fetches", l.fetches)
          .AddCount("bytes", l.bytes);
    }
    t->AddTables("levels", std::move(levels));
  }
}

StatsTable ToStatsTable(const ReplayResult& result, const ResultColumns& columns) {
  StatsTable t;
  AddResult(result, columns, &t);
  return t;
}

}  // namespace raycell
