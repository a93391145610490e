#include "study/subdivisions.h"

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <numeric>
#include <sstream>

#include "base/check.h"
#include "base/format.h"
#include "record/record_flags.h"
#include "record/recorder.h"
#include "replay/config.h"
#include "replay/replayer.h"
#include "runner/driver.h"
#include "scheduling/cell_tree_scheduler.h"
#include "scheduling/max_work.h"
#include "study/accuracy.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

namespace fs = std::filesystem;

}  // namespace

std::vector<std::uint64_t> NonEmptyFootprints(const std::vector<std::uint64_t>& footprints) {
  std::vector<std::uint64_t> f;
  for (std::uint64_t b : footprints) {
    if (b != 0) f.push_back(b);
  }
  std::sort(f.begin(), f.end());
  return f;
}

std::uint64_t MedianFootprint(const std::vector<std::uint64_t>& sorted) {
  RAYCELL_CHECK(!sorted.empty());
  return sorted[(sorted.size() - 1) / 2];
}

std::vector<std::string> SubdivisionSpecs(std::uint64_t cache_bytes) {
  const std::string budget = std::to_string(cache_bytes) + "B";
  return {"3x3x3",      "kd:27:footprint",     "kd:27:work",
          "kd:27:sqrt", "kd:budget:" + budget, "octree:" + budget,
          "dynamic:27", "dynamic:27:sqrt",     "grid:27:crossings"};
}

SubdivisionStudy MeasureSubdivisions(const SubdivisionOptions& o) {
  SubdivisionStudy study;
  study.options = o;
  if (o.frames <= 0) return study;
  study.not_measured = SceneNotLoadable(o.scene);
  if (!study.not_measured.empty()) return study;
  SceneSpec spec;
  spec.source = o.scene;
  if (VolumeChanges(spec)) {  // an animated scene file: its leaves change every frame
    study.not_measured =
        "the scene `" + o.scene + "` is animated: a regroupable capture needs one volume";
    return study;
  }
  if (!o.quiet) {
    std::cerr << "measuring subdivisions: " << o.frames << " frame(s) of `" << o.scene << "` at "
              << o.res << ", one capture on " << o.fine << " cells regrouped, in " << o.out
              << "/\n";
  }
  fs::create_directories(o.out);
  const std::string fine = (fs::path(o.out) / "fine.rct").string();
  RecordFlags flags;
  flags.opt.scene.source = o.scene;
  flags.res = o.res;
  flags.orbit = std::to_string(o.frames) + ":" + FormatReal(3.75 * o.frames);
  flags.cells = o.fine;
  flags.opt.regroupable = true;
  flags.opt.out = fine;
  flags.no_images = true;
  flags.quiet = true;
  std::ostringstream log;  // one line per frame, not shown
  RecordOptions record = ToRecordOptions(flags);
  record.images_dir.clear();
  record.progress = false;
  Record(record, log);

  study.cache_bytes =
      MedianFootprint(NonEmptyFootprints(TraceReader::Open(fine, "3x3x3").header().footprints));
  for (const std::string& spec : SubdivisionSpecs(study.cache_bytes)) {
    const TraceReader reader = TraceReader::Open(fine, spec);
    const std::vector<std::uint64_t> f = NonEmptyFootprints(reader.header().footprints);
    std::vector<std::size_t> frames(reader.frames().size());
    std::iota(frames.begin(), frames.end(), std::size_t{0});
    for (const SchedulerEntry* scheduler : {&kMaxWorkEntry, &kCellTreeEntry}) {
      ReplayConfig config = DefaultConfig();
      config.scheduler = scheduler;
      ApplyOverride(config, "level.cache.capacity", std::to_string(study.cache_bytes) + "B",
                    "the subdivision section");
      ValidateConfig(config, "the subdivision section's configuration");
      const ReplayResult t = ReplayTrace(reader, frames, config, {}, 1).total;
      SubdivisionRow row;
      row.spec = spec;
      row.scheduler = scheduler->name;
      row.cells = std::uint32_t(f.size());
      row.footprint_min = f.front(), row.footprint_median = MedianFootprint(f),
      row.footprint_max = f.back();
      row.fetches = t.fetches;
      RAYCELL_CHECK_LE(2u, t.levels.size());
      row.cache_bytes = t.levels[0].bytes;
      row.board_bytes = t.levels[1].bytes;
      row.stall_ps = t.stall.picoseconds();
      row.time_ps = t.time.picoseconds();
      study.rows.push_back(row);
    }
  }
  study.measured = true;
  return study;
}

}  // namespace raycell
