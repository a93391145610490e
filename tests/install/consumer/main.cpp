// Built against an installed raycell (tests/install/install_test.sh): writes a trace of two
// frames with TraceWriter, reads it back with TraceReader and exits 0 only when every frame
// read holds exactly the rays written (their count, kinds, parents, spawns, pixels and every
// visit), so the installed headers, libraries and their dependencies make a working reader
// and writer. Usage: consumer OUT.rct
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "base/check.h"
#include "traces/ray_batch.h"
#include "traces/trace_header.h"
#include "traces/trace_reader.h"
#include "traces/trace_writer.h"

namespace {

using raycell::CellId;
using raycell::kNoParent;
using raycell::RayBatch;
using raycell::RayKind;

// 2x2x2 cells, a camera per frame (frames 4 and 5), t stored so t_enter/t_exit round-trip.
raycell::TraceHeader Header() {
  raycell::TraceHeader h;
  h.producer = "raycell install test";
  h.scene = "builtin:smoke";
  h.box_min = {-1, -1, -1};
  h.box_max = {1, 1, 1};
  h.cells = {2, 2, 2};
  h.footprints = {100, 200, 300, 400, 500, 600, 700, 800};
  for (std::int32_t f = 4; f <= 5; ++f)
    h.cameras.push_back({f, {0, 0, 3}, {0, 0, 0}, {0, 1, 0}, 40});
  h.settings.store_t = true;
  return h;
}

// Frame 4: a primary ray through cells 0, 1, 3, a shadow ray from its second visit, a
// reflection ray from its third, and a primary ray that hits nothing.
RayBatch Frame4() {
  RayBatch b(true);
  b.BeginRay(RayKind::kPrimary, kNoParent, 0, 10, 20);
  b.AddVisit(CellId(0), 12, 0.5f, 1.0f);
  b.AddVisit(CellId(1), 7, 1.0f, 1.75f);
  b.AddVisit(CellId(3), 3, 1.75f, 2.0f);
  b.BeginRay(RayKind::kShadow, 0, 1, 10, 20);
  b.AddVisit(CellId(1), 4, 0.0f, 0.25f);
  b.AddVisit(CellId(5), 9, 0.25f, 1.5f);
  b.BeginRay(RayKind::kReflection, 0, 2, 10, 20);
  b.AddVisit(CellId(3), 1, 0.0f, 0.125f);
  b.BeginRay(RayKind::kPrimary, kNoParent, 0, 11, 20);
  return b;
}

// Frame 5: one primary ray through cells 7 and 6 and a refraction ray from its first visit.
RayBatch Frame5() {
  RayBatch b(true);
  b.BeginRay(RayKind::kPrimary, kNoParent, 0, 0, 0);
  b.AddVisit(CellId(7), 100000, 0.25f, 0.5f);
  b.AddVisit(CellId(6), 2, 0.5f, 3.0f);
  b.BeginRay(RayKind::kRefraction, 0, 0, 0, 0);
  b.AddVisit(CellId(7), 5, 0.0f, 0.75f);
  return b;
}

// Which column of `read` differs from `written` ("" when none), compared here rather than by
// RayBatch::operator==, which the installed library provides.
std::string Difference(const RayBatch& read, const RayBatch& written) {
  if (read.first_id() != written.first_id()) return "first id";
  if (read.kinds() != written.kinds()) return "kinds";
  if (read.parents() != written.parents()) return "parents";
  if (read.spawns() != written.spawns()) return "spawns";
  if (read.pixel_xs() != written.pixel_xs() || read.pixel_ys() != written.pixel_ys()) {
    return "pixels";
  }
  for (std::size_t i = 0; i < written.size(); ++i) {
    if (read.ray(i).visit_count != written.ray(i).visit_count) {
      return "visit count of ray " + std::to_string(i);
    }
  }
  if (read.cells() != written.cells()) return "cells";
  if (read.samples() != written.samples()) return "samples";
  if (read.t_enters() != written.t_enters() || read.t_exits() != written.t_exits()) return "t";
  return "";
}

int Fail(const std::string& what) {
  std::fprintf(stderr, "consumer: %s\n", what.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) return Fail("usage: consumer OUT.rct");
  const std::string path = argv[1];
  const std::vector<std::int32_t> numbers = {4, 5};
  const std::vector<RayBatch> frames = {Frame4(), Frame5()};
  try {
    raycell::TraceWriter w = raycell::TraceWriter::Create(path, Header());
    for (std::size_t i = 0; i < frames.size(); ++i) {
      w.BeginFrame(numbers[i]);
      w.Append(frames[i]);
      w.EndFrame();
    }
    w.Finish();

    const raycell::TraceReader r = raycell::TraceReader::Open(path);
    if (!r.warning().empty()) return Fail("reader warning: " + r.warning());
    if (r.frames().size() != frames.size()) {
      return Fail("frames read: " + std::to_string(r.frames().size()) + ", written " +
                  std::to_string(frames.size()));
    }
    for (std::size_t i = 0; i < frames.size(); ++i) {
      if (r.frames()[i].frame != numbers[i]) return Fail("frame number " + std::to_string(i));
      const RayBatch read = r.LoadFrame(i);
      if (read.size() != frames[i].size() || read.visit_count() != frames[i].visit_count()) {
        return Fail("frame " + std::to_string(numbers[i]) + ": " + std::to_string(read.size()) +
                    " rays, " + std::to_string(read.visit_count()) + " visits read, " +
                    std::to_string(frames[i].size()) + " and " +
                    std::to_string(frames[i].visit_count()) + " written");
      }
      const std::string diff = Difference(read, frames[i]);
      if (!diff.empty()) {
        return Fail("frame " + std::to_string(numbers[i]) + ": " + diff + " differ");
      }
    }
  } catch (const raycell::InputError& e) {
    return Fail(std::string("InputError: ") + e.what());
  }
  std::printf("consumer: 2 frames, %zu and %zu rays, read back equal\n", frames[0].size(),
              frames[1].size());
  return 0;
}
