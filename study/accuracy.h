// Run time against error for the knobs that trade one for the other: the renderer's step,
// early-termination cutoff and precision (capture time against the image RMSE to a capture
// with a four times finer step, and the change in Cell Tree scheduling's fetches), the
// renderer's maximum depth of reflection and refraction, 0..5 (against max depth 5 at the
// default step, likewise), and the replay's granularity and sampling (replay time against the
// error in simulated time and the change in fetches). Every capture is made as `raycell record`
// makes it with the knob's flags (RecordFlags), every replay as `raycell replay` makes it, in
// this process, each call timed on the wall clock. The study's depth section (study/depth.h)
// reads the max depth captures again instead of making its own.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace raycell {

enum class AccuracyPart { kReference, kRenderer, kDepth, kGranularity, kSampling };

// One setting of a knob: one row of the table.
struct AccuracyKnob {
  AccuracyPart part = AccuracyPart::kRenderer;
  std::string knob;         // "renderer step", "replay granularity", ...
  std::string value;        // as the table prints it: "0.25", "single", "node", "16"
  bool is_default = false;  // what raycell does unless told otherwise
  // Reference and renderer rows: record's flags beyond the capture's own (unset ones keep
  // record's defaults), and the capture's folder under the accuracy folder.
  std::optional<double> step, shadow_step, cutoff;
  std::string precision;  // "single", or empty for record's default
  // Max depth rows: record's --max-depth (the step record's default).
  std::optional<std::uint32_t> max_depth;
  std::string folder;  // "reference", "step-0.5", "cutoff-0.02", "max-depth-3", ...
  // Granularity and sampling rows: the replay of the default-step capture.
  std::string granularity = "ray";
  std::uint32_t sample = 1;
};

// Every setting measured, in the table's order: the reference (step 0.25, shadow step 0.75),
// step 0.5, 1, 2, 4 (shadow step three times it), cutoff 0.001, 0.02, 0.05, single precision,
// max depth 0, 1, 2, 3 (record's default), 4, 5, replay per ray segment and per Cell Tree
// node, and sampling 1 in k ray trees, k = 1, 2, 4, 8, 16.
const std::vector<AccuracyKnob>& AccuracyKnobs();

// The deepest max depth measured: the max depth rows' reference.
inline constexpr std::uint32_t kDeepestMaxDepth = 5;

struct AccuracyRow {
  std::string knob, value;  // the knob's
  double seconds = 0;       // the record or replay call, wall clock
  // To the most accurate setting of the same part, measured in the same run: the reference
  // capture for the renderer, the max depth 5 capture for the max depth, the replay per ray
  // segment (without sampling) for the replay.
  double time_ratio = 0;
  double error = 0;  // of the kind below; 0 for the reference itself
  // "reference", "image RMSE vs step 0.25", "image RMSE vs max depth 5", "simulated time,
  // relative"
  std::string error_kind;
  double fetch_change = 0;  // (fetches - the reference's) / the reference's
  bool is_default = false;
};

struct AccuracyOptions {
  std::string scene = "builtin", res = "128x128";
  int frames = 4;     // an orbit of 20 degrees over them, in 3x3x3 cells
  std::string out;    // one folder per capture in it: c.rct and frame_NNNN.png
  bool quiet = true;  // false: a line on stderr when the measurement starts
};

struct AccuracyStudy {
  AccuracyOptions options;
  bool measured = false;  // false: not asked for (no frames), or could not be (see below)
  // Why it was not measured, when it was asked for: "the scene `S` cannot be loaded here (...)".
  std::string not_measured;
  std::vector<AccuracyRow> rows;  // when measured: one per AccuracyKnobs() entry, in its order
};

// Why `scene` cannot be loaded here ("the scene `S` cannot be loaded here (...)"), or empty
// when it can: the sections that capture the scene again (a given trace's scene may live
// elsewhere) say so instead of failing.
std::string SceneNotLoadable(const std::string& scene);

// Measures every knob on options.frames frames of the scene (none: nothing measured), or says
// why it cannot (the scene cannot be loaded here: a given trace's scene may live elsewhere).
// InputError on a capture or replay that fails, or a reference with no fetches or no simulated
// time.
AccuracyStudy MeasureAccuracy(const AccuracyOptions& options);

// The capture of a renderer, reference or max depth knob: OUT/FOLDER/c.rct.
std::string KnobTrace(const AccuracyOptions& options, const AccuracyKnob& knob);

}  // namespace raycell
