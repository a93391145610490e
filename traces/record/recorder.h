// `raycell record`: renders the frames of a scene and writes their trace and images.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "traces/record/camera.h"
#include "traces/record/scene.h"
#include "traces/trace_header.h"

namespace raycell {

struct RecordOptions {
  SceneSpec scene;
  std::vector<int> frames{0};  // frame numbers to record
  std::array<std::uint32_t, 3> cells{2, 2, 2};
  RenderSettings settings;
  CameraPathSpec camera;
  std::string out = "capture.rct";
  std::string images_dir;  // empty: no images
  int threads = 0;         // 0: all cores
  bool progress = true;    // a bar on stderr, when stderr is a terminal
  const std::atomic<bool>* cancel = nullptr;
};

struct RecordSummary {
  std::size_t frames = 0;
  std::uint64_t rays = 0, visits = 0, samples = 0, primary_missed = 0;
  double seconds = 0;
  bool interrupted = false;
};

// Parses "WxH". InputError on bad text or a zero size.
std::array<std::uint32_t, 2> ParseResolution(const std::string& text);
// Checks every numeric setting (positive steps, cutoff in [0,1), ...); InputError if not.
void ValidateSettings(const RenderSettings& s);

// Records the capture. Throws InputError on bad input; `log` gets one line per frame.
RecordSummary Record(const RecordOptions& options, std::ostream& log);

}  // namespace raycell
