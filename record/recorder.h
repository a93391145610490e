// `raycell record`: renders the frames of a scene and writes their trace and images.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <ostream>
#include <string>
#include <vector>

#include "record/camera.h"
#include "record/image.h"
#include "record/scene.h"
#include "traces/format.h"
#include "traces/trace_header.h"

namespace raycell {

// Size limits of a capture, checked before anything is loaded or rendered.
//
// Cells: the trace format's limit (traces/format.h: footprints are stored in records of
// runs after the header, so 256x256x256 cells fit whatever their footprints); the renderer
// keeps one bit per cell and works at that size (RecorderAtScale tests).
inline constexpr std::uint64_t kMaxCaptureCells = kTraceMaxCells;  // 16,777,216
inline constexpr std::uint64_t kMaxCaptureFrames = 100000;
// Pixels of one frame: the image is held in memory as linear RGB doubles, 24 bytes a pixel
// (1.5 GiB at the limit, 8192x8192).
inline constexpr std::uint64_t kMaxPixels = std::uint64_t{1} << 26;
// Primary rays of one frame (pixels x samples per pixel): 16 times the 2048x2048 capture of
// BENCHMARKS.md "Capture at scale" (17 M rays, 92 M visits in 8x8x8 cells). Recording and
// analysing stream a frame; replaying it per ray segment holds it in memory (6 GiB there).
inline constexpr std::uint64_t kMaxPrimaryRays = std::uint64_t{1} << 26;
inline constexpr int kMaxThreads = 1024;

struct RecordOptions {
  SceneSpec scene;
  std::vector<int> frames{0};  // frame numbers to record
  std::array<std::uint32_t, 3> cells{2, 2, 2};
  RenderSettings settings;
  CameraPathSpec camera;
  std::string out = "out/capture.rct";  // out/ is git-ignored: never into the sources
  std::string images_dir;               // empty: no images
  // A fine capture that any coarser subdivision can be made of (TraceHeader::regroupable):
  // rays also visit the empty cells they cross, and the header holds each cell's leaves.
  // Sparse footprints of one volume (not a sequence).
  bool regroupable = false;
  // The trace's format version: 5 (kTraceDefaultVersion, the faster to read) or 6 (samples
  // range coded, about a sixth smaller).
  std::uint32_t trace_format = kTraceDefaultVersion;
  PngEncoding image_encoding = PngEncoding::kSrgb;
  int threads = 0;       // 0: all cores
  bool progress = true;  // a bar on stderr, when stderr is a terminal
  // Stops the capture within a frame (Ctrl-C): the frame is dropped.
  const std::atomic<bool>* cancel = nullptr;
  // Asked after each frame but the last with the number of frames finished; returning true
  // stops the capture as an interruption would (the finished frames stay readable in
  // OUT.tmp). For tests.
  std::function<bool(std::size_t frames_done)> stop;
};

struct RecordSummary {
  std::size_t frames = 0;
  std::uint64_t rays = 0, visits = 0, samples = 0, primary_missed = 0;
  double seconds = 0;
  bool interrupted = false;
};

// Parses "WxH". InputError on bad text or a zero size.
std::array<std::uint32_t, 2> ParseResolution(const std::string& text);
// Checks every numeric setting (positive steps, cutoff in [0,1), pixels and pixels x samples
// per pixel within kMaxPixels and kMaxPrimaryRays, ...); InputError naming the option if not.
void ValidateSettings(const RenderSettings& s);
// Checks everything that can be checked before the scene is loaded: the settings, the cell
// grid and frame count against the limits above, threads, the camera options, the footprint
// mode and the grid choice. InputError naming the option and its limit.
void ValidateRecordOptions(const RecordOptions& o);

// Records the capture. Throws InputError on bad input; `log` gets one line per frame.
RecordSummary Record(const RecordOptions& options, std::ostream& log);

}  // namespace raycell
