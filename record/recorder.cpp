#include "record/recorder.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <memory>
#include <sstream>

#include "base/check.h"
#include "base/format.h"
#include "base/parse.h"
#include "base/progress.h"
#include "record/cell_grid.h"
#include "record/renderer.h"
#include "traces/trace_writer.h"

namespace raycell {
namespace {

// The scene box over all frames (sequences may move) and, per cell, the largest footprint
// of any frame (header.footprints; each frame also uses its own to decide emptiness).
void ScanScene(const RecordOptions& o, const Scene* first, TraceHeader* h) {
  const bool seq = VolumeChanges(o.scene);
  Vec3d lo = first->box_lo(), hi = first->box_hi();
  for (std::size_t i = 1; seq && i < o.frames.size(); ++i) {
    const auto s = Scene::Load(o.scene, o.frames[i]);
    lo = {std::min(lo.x, s->box_lo().x), std::min(lo.y, s->box_lo().y),
          std::min(lo.z, s->box_lo().z)};
    hi = {std::max(hi.x, s->box_hi().x), std::max(hi.y, s->box_hi().y),
          std::max(hi.z, s->box_hi().z)};
  }
  h->box_min = lo;
  h->box_max = hi;
  h->footprints = first->Footprints(lo, hi, o.cells, o.scene.footprint_mode);
  for (std::size_t i = 1; seq && i < o.frames.size(); ++i) {
    const auto fp =
        Scene::Load(o.scene, o.frames[i])->Footprints(lo, hi, o.cells, o.scene.footprint_mode);
    for (std::size_t c = 0; c < fp.size(); ++c)
      h->footprints[c] = std::max(h->footprints[c], fp[c]);
  }
}

std::string ImagePath(const std::string& dir, int frame) {
  char name[64];
  std::snprintf(name, sizeof name, "frame_%04d.png", frame);
  return (std::filesystem::path(dir) / name).string();
}

}  // namespace

std::array<std::uint32_t, 2> ParseResolution(const std::string& text) {
  const auto x = text.find_first_of("xX");
  const std::string what = "--res '" + text + "'";
  if (x == std::string::npos) throw InputError(what + ": expected WxH, e.g. 256x256");
  const std::string_view t = text;
  const auto w = ParseInt(t.substr(0, x), what), h = ParseInt(t.substr(x + 1), what);
  if (w < 1 || h < 1 || w > 65536 || h > 65536) {
    throw InputError(what + ": width and height must be in 1..65536");
  }
  return {std::uint32_t(w), std::uint32_t(h)};
}

void ValidateSettings(const RenderSettings& s) {
  auto positive = [](double v, const char* name) {
    if (!(std::isfinite(v) && v > 0)) {
      throw InputError(std::string(name) + ": must be a positive finite number");
    }
  };
  positive(s.primary_step, "--step");
  positive(s.shadow_step, "--shadow-step");
  if (!(s.cutoff >= 0 && s.cutoff < 1)) throw InputError("--cutoff: must be in [0, 1)");
  if (s.width < 1 || s.height < 1) throw InputError("--res: width and height must be positive");
  if (s.spp < 1 || s.spp > 4096) throw InputError("--spp: must be in 1..4096");
  const std::uint64_t pixels = std::uint64_t{s.width} * s.height;
  if (pixels > kMaxPixels) {
    throw InputError("--res " + std::to_string(s.width) + "x" + std::to_string(s.height) + ": " +
                     std::to_string(pixels) + " pixels exceeds the limit of " +
                     std::to_string(kMaxPixels) +
                     " (8192x8192; the image is held in memory, 24 bytes a pixel)");
  }
  if (pixels * s.spp > kMaxPrimaryRays) {
    throw InputError(
        "--res x --spp: " + std::to_string(pixels) + " pixels x " + std::to_string(s.spp) + " = " +
        std::to_string(pixels * s.spp) + " primary rays a frame exceeds the limit of " +
        std::to_string(kMaxPrimaryRays) + " (a frame is analysed and replayed in memory)");
  }
  if (s.max_depth > 16) throw InputError("--max-depth: must be at most 16");
  if (s.zstd_level < 1 || s.zstd_level > 19) throw InputError("--zstd-level: must be in 1..19");
}

void ValidateRecordOptions(const RecordOptions& o) {
  ValidateSettings(o.settings);
  const auto& c = o.cells;
  const std::uint64_t cells = std::uint64_t{c[0]} * c[1] * c[2];
  if (c[0] < 1 || c[1] < 1 || c[2] < 1) throw InputError("--cells: each dimension must be >= 1");
  if (cells > kMaxCaptureCells) {
    throw InputError("--cells " + std::to_string(c[0]) + "x" + std::to_string(c[1]) + "x" +
                     std::to_string(c[2]) + ": " + std::to_string(cells) +
                     " cells exceeds the trace format's limit of " +
                     std::to_string(kMaxCaptureCells) + " cells (e.g. 256x256x256)");
  }
  if (o.frames.empty()) throw InputError("--frames: no frames to record");
  if (o.frames.size() > kMaxCaptureFrames) {
    throw InputError("--frames (or --orbit FRAMES:DEGREES): " + std::to_string(o.frames.size()) +
                     " frames exceeds the trace format's limit of " +
                     std::to_string(kMaxCaptureFrames) + " frames a capture");
  }
  for (std::size_t i = 1; i < o.frames.size(); ++i) {
    if (std::int64_t{o.frames[i]} != std::int64_t{o.frames[i - 1]} + 1) {
      throw InputError("--frames: frame numbers must be consecutive (a range A..B)");
    }
  }
  if (o.threads < 0 || o.threads > kMaxThreads) {
    throw InputError("--threads " + std::to_string(o.threads) + ": must be in 0.." +
                     std::to_string(kMaxThreads) + " (0: all cores)");
  }
  if (o.scene.footprint_mode != "sparse" && o.scene.footprint_mode != "dense") {
    throw InputError("--footprint '" + o.scene.footprint_mode + "': expected sparse or dense");
  }
  if (o.scene.all_grids && !o.scene.grids.empty()) {
    throw InputError("--grid and --all-grids: give one or the other");
  }
  if (o.regroupable && o.scene.footprint_mode != "sparse") {
    throw InputError(
        "--regroupable needs sparse footprints (--footprint sparse): a union of "
        "cells counts each leaf once, and dense footprints have no leaves");
  }
  if (o.regroupable && VolumeChanges(o.scene)) {
    throw InputError(
        "--regroupable: a sequence's (or an animated scene's) leaves change from frame to "
        "frame; record one volume (a .vdb file, a still scene file or the built-in scene)");
  }
  ValidateCameraSpec(o.camera);
  CheckOrbitFrames(o.camera, o.frames);
}

RecordSummary Record(const RecordOptions& o, std::ostream& log) {
  ValidateRecordOptions(o);
  const auto t_start = std::chrono::steady_clock::now();
  std::unique_ptr<Scene> scene = Scene::Load(o.scene, o.frames.front());

  TraceHeader header;
  header.producer = "raycell 0.1.0";
  header.scene = SceneLabel(o.scene);
  header.grids = scene->grids();
  header.cells = o.cells;
  header.footprint_mode = o.scene.footprint_mode;
  header.settings = o.settings;
  ScanScene(o, scene.get(), &header);
  if (o.regroupable) {
    header.regroupable = true;
    header.leaves = scene->Leaves(header.box_min, header.box_max, o.cells);
  }
  const CellGrid cells = CellGrid::Create(header.box_min, header.box_max, o.cells);
  header.path = MakeCameraPathInfo(o.camera, o.frames, header.box_min, header.box_max);
  for (int frame : o.frames) header.cameras.push_back(CameraOf(header.path, frame));
  for (const CameraKey& key : header.cameras) CheckCamera(o.camera, key);

  // The default --out is out/capture.rct (outside every source folder): make its folder.
  // A folder that cannot be made is left to TraceWriter::Create, whose InputError names the
  // file (exit 2), rather than a filesystem_error here.
  const std::filesystem::path out_dir = std::filesystem::path(o.out).parent_path();
  std::error_code ignored;
  if (!out_dir.empty()) std::filesystem::create_directories(out_dir, ignored);
  if (o.trace_format < 5 || o.trace_format > kTraceFormatVersion) {
    throw InputError("trace format " + std::to_string(o.trace_format) +
                     " cannot be written (5 to " + std::to_string(kTraceFormatVersion) + ")");
  }
  TraceWriterOptions writer_options;
  writer_options.format_version = o.trace_format;
  TraceWriter writer = TraceWriter::Create(o.out, header, writer_options);
  // Made once every frame's scene was built and the trace could be created: a bad scene
  // leaves no folder behind.
  if (!o.images_dir.empty()) std::filesystem::create_directories(o.images_dir);
  Progress progress(o.progress);
  RecordSummary sum;
  const bool seq = VolumeChanges(o.scene);
  auto interrupt = [&] {
    progress.Done();
    sum.interrupted = true;
    log << "interrupted: the " << sum.frames << " finished frames are in " << writer.tmp_path()
        << " (readable by `raycell trace`)\n";
  };
  for (std::size_t i = 0; i < o.frames.size(); ++i) {
    const int frame = o.frames[i];
    if (seq && i > 0) scene = Scene::Load(o.scene, frame);
    std::vector<std::uint64_t> frame_footprints;  // a sequence's own, per frame
    if (seq) {
      frame_footprints =
          scene->Footprints(header.box_min, header.box_max, o.cells, o.scene.footprint_mode);
    }
    RenderJob job;
    job.scene = scene.get();
    job.cells = &cells;
    job.footprints = seq ? &frame_footprints : &header.footprints;
    job.all_cells = o.regroupable;
    job.camera = header.cameras[i];
    job.settings = o.settings;
    job.threads = o.threads;
    job.cancel = o.cancel;
    job.sink = [&](const RayBatch& b) { writer.Append(b); };
    const std::string label = "frame " + std::to_string(frame) + " (" + std::to_string(i + 1) +
                              "/" + std::to_string(o.frames.size()) + ")";
    job.progress = [&](double f) { progress.Update((i + f) / o.frames.size(), label); };
    const auto t0 = std::chrono::steady_clock::now();
    Image image(o.settings.width, o.settings.height);
    FrameStats st;
    writer.BeginFrame(frame);
    if (!RenderFrame(job, &image, &st)) {
      interrupt();
      break;
    }
    writer.EndFrame();
    if (!o.images_dir.empty()) {
      WritePng(image, ImagePath(o.images_dir, frame), o.image_encoding);
    }
    ++sum.frames;
    sum.rays += st.rays, sum.visits += st.visits, sum.samples += st.samples;
    sum.primary_missed += st.primary_missed;
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    progress.Done();
    log << "frame " << frame << ": " << st.rays << " rays (" << st.rays_by_kind[0] << " primary, "
        << st.rays_by_kind[1] << " reflection, " << st.rays_by_kind[2] << " refraction, "
        << st.rays_by_kind[3] << " shadow), " << st.visits << " visits, " << st.samples
        << " samples, " << FormatFixed(secs, 2) << " s\n";
    if (o.stop && i + 1 < o.frames.size() && o.stop(sum.frames)) {
      interrupt();
      break;
    }
  }
  if (!sum.interrupted) writer.Finish();
  sum.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return sum;
}

}  // namespace raycell
