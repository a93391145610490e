// One printer per replay result: every output of a ReplayResult (`raycell replay` as a
// table, JSON and CSV, and `raycell sweep`'s rows) is the StatsTable built here, printed by
// base/table.h, so a statistic is named, ordered and formatted in one place.
#pragma once

#include "base/table.h"
#include "replay/replayer.h"

namespace raycell {

// Which columns an output has beyond the core ones.
struct ResultColumns {
  bool extras = false;  // prefetches, prefetch_hits, min_converged
  bool levels = false;  // per memory level: JSON "levels":[{name, fetches, bytes}], CSV and
                        // text NAME_fetches, NAME_bytes
};
inline constexpr ResultColumns kSweepColumns{false, false};       // `raycell sweep` rows
inline constexpr ResultColumns kReplayCsvColumns{false, true};    // `replay --format csv`
inline constexpr ResultColumns kReplayJsonColumns{true, true};    // `replay --format json`
inline constexpr ResultColumns kReplayTableColumns{false, true};  // `replay --format table`

// Appends, in this order: fetches, bound (no value where it does not hold), time_ps,
// time_bound_ps, work_ps, stall_ps, idle_ps, utilisation (4 decimals), peak_queued_rays,
// peak_queued_bytes, rays, segments, samples; then the extras and levels `columns` asks for.
void AddResult(const ReplayResult& result, const ResultColumns& columns, StatsTable* table);
StatsTable ToStatsTable(const ReplayResult& result, const ResultColumns& columns);

}  // namespace raycell
