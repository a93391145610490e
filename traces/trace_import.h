// `raycell trace import`: a trace file made from ray paths in JSON Lines (traces/jsonl.h),
// written by raycell or by any other ray tracer, so that replay, sweep, analyze and study
// take captures raycell did not record. docs/jsonl.md documents the defaults of what the
// paths do not say (scene box, footprints, cameras, image size).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "traces/trace_header.h"

namespace raycell {

// Bytes per cell when --footprint is not given: a dense 64^3 brick of 4-byte voxels.
inline constexpr std::uint64_t kImportDefaultFootprint = std::uint64_t{1} << 20;

struct ImportOptions {
  std::string paths;                     // the JSON Lines file (read twice, so not a pipe)
  std::string out;                       // the trace to write
  std::array<std::uint32_t, 3> cells{};  // the cell grid; every cell of the paths below it
  std::uint64_t footprint = kImportDefaultFootprint;  // bytes of every cell, > 0
  std::optional<std::pair<Vec3d, Vec3d>> box;         // default (0,0,0) - (nx,ny,nz)
  std::uint32_t zstd_level = 3;
};

struct ImportSummary {
  std::size_t frames = 0;
  std::size_t renumbered_frames = 0;  // frames whose ids the reader changed
  std::uint64_t rays = 0, visits = 0;
};

// The header of an imported trace of `frames` (frame numbers, in file order) whose pixels
// are all below width x height: producer "raycell 0.1.0 (trace import)", scene
// "import:PATHS", no grids, the box, the grid, `footprint` bytes for every cell (mode
// "uniform"), one camera per frame at CameraKey's defaults (the paths do not say where the
// camera was), RenderSettings' defaults with this width and height and zstd level.
TraceHeader ImportHeader(const ImportOptions& options, const std::vector<std::int32_t>& frames,
                         std::uint32_t width, std::uint32_t height);

// Reads every frame once to check it and find the frames and the image size (nothing is
// written if any line is bad), then again to write the trace through TraceWriter. Memory
// holds one frame. InputError naming the file and line, or the option, on bad input.
ImportSummary ImportJsonl(const ImportOptions& options);

}  // namespace raycell
