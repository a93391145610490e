#include "study/accuracy.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <numeric>
#include <sstream>

#include "base/check.h"
#include "record/record_flags.h"
#include "record/recorder.h"
#include "record/scene.h"
#include "replay/config.h"
#include "replay/replayer.h"
#include "runner/driver.h"
#include "study/image_error.h"
#include "traces/trace_reader.h"

namespace raycell {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

AccuracyKnob Renderer(const char* knob, const char* value) {
  AccuracyKnob k;
  k.part = AccuracyPart::kRenderer;
  k.knob = std::string("renderer ") + knob;
  k.value = value;
  k.folder = std::string(knob) + "-" + value;
  return k;
}

AccuracyKnob Replay(AccuracyPart part, const char* knob, std::string value) {
  AccuracyKnob k;
  k.part = part;
  k.knob = knob;
  k.value = std::move(value);
  return k;
}

std::vector<AccuracyKnob> MakeKnobs() {
  std::vector<AccuracyKnob> knobs;
  AccuracyKnob reference = Renderer("step", "0.25");
  reference.part = AccuracyPart::kReference;
  reference.step = 0.25, reference.shadow_step = 0.75;
  reference.folder = "reference";
  knobs.push_back(reference);
  // Each value as record's --step reads it (CLI11: strtold, then double) is the literal here.
  const std::pair<const char*, double> steps[] = {{"0.5", 0.5}, {"1", 1}, {"2", 2}, {"4", 4}};
  for (const auto& [text, step] : steps) {
    AccuracyKnob k = Renderer("step", text);
    k.step = step, k.shadow_step = 3 * step;
    k.is_default = step == 1;
    knobs.push_back(k);
  }
  const std::pair<const char*, double> cutoffs[] = {
      {"0.001", 0.001}, {"0.02", 0.02}, {"0.05", 0.05}};
  for (const auto& [text, cutoff] : cutoffs) {
    AccuracyKnob k = Renderer("cutoff", text);
    k.cutoff = cutoff;
    knobs.push_back(k);
  }
  AccuracyKnob single = Renderer("precision", "single");  // step 1, as the default
  single.precision = "single";
  knobs.push_back(single);
  for (std::uint32_t depth = 0; depth <= kDeepestMaxDepth; ++depth) {
    AccuracyKnob k;
    k.part = AccuracyPart::kDepth;
    k.knob = "max depth";
    k.value = std::to_string(depth);
    k.max_depth = depth;
    k.is_default = depth == RenderSettings{}.max_depth;
    k.folder = "max-depth-" + k.value;
    knobs.push_back(k);
  }
  for (const char* granularity : {"ray", "node"}) {
    AccuracyKnob k = Replay(AccuracyPart::kGranularity, "replay granularity", granularity);
    k.granularity = granularity;
    k.is_default = k.granularity == "node";
    knobs.push_back(k);
  }
  for (const std::uint32_t sample : {1, 2, 4, 8, 16}) {
    AccuracyKnob k =
        Replay(AccuracyPart::kSampling, "replay sampling 1 in k (per ray)", std::to_string(sample));
    k.sample = sample;
    k.is_default = sample == 1;
    knobs.push_back(k);
  }
  return knobs;
}

// What `raycell record --scene S --res R --orbit F:20 --cells 3x3x3 --out DIR/c.rct --images
// DIR --quiet` with the knob's flags records, into DIR = OUT/FOLDER; the call's seconds.
double RecordKnob(const AccuracyOptions& o, const AccuracyKnob& k) {
  const fs::path dir = fs::path(o.out) / k.folder;
  fs::create_directories(dir);
  RecordFlags flags;
  flags.opt.scene.source = o.scene;
  flags.res = o.res;
  flags.orbit = std::to_string(o.frames) + ":20";
  flags.cells = "3x3x3";
  flags.opt.out = (dir / "c.rct").string();
  flags.opt.images_dir = dir.string();
  flags.quiet = true;
  if (k.step) flags.opt.settings.primary_step = *k.step;
  if (k.shadow_step) flags.opt.settings.shadow_step = *k.shadow_step;
  if (k.cutoff) flags.opt.settings.cutoff = *k.cutoff;
  if (!k.precision.empty()) flags.precision = k.precision;
  if (k.max_depth) flags.opt.settings.max_depth = *k.max_depth;
  const RecordOptions options = ToRecordOptions(flags);
  std::ostringstream log;  // one line per frame, not shown
  const Clock::time_point start = Clock::now();
  Record(options, log);
  return SecondsSince(start);
}

std::vector<Rgb8Image> Frames(const AccuracyOptions& o, const AccuracyKnob& k) {
  std::vector<Rgb8Image> frames;
  for (int i = 0; i < o.frames; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%04d.png", i);
    frames.push_back(ReadPng8((fs::path(o.out) / k.folder / name).string()));
  }
  return frames;
}

struct Replayed {
  double seconds = 0;
  std::uint64_t fetches = 0, time_ps = 0;
};

// What `raycell replay TRACE --granularity G --sample K` reports in total (the default
// configuration otherwise, every frame); the seconds of opening the trace and replaying it.
Replayed ReplayKnob(const std::string& trace, const std::string& granularity,
                    std::uint32_t sample) {
  const Clock::time_point start = Clock::now();
  ReplayConfig config = DefaultConfig();
  ApplyOverride(config, "granularity", granularity, "--granularity");
  ValidateConfig(config, "the configuration");
  const TraceReader reader = TraceReader::Open(trace);
  std::vector<std::size_t> frames(reader.frames().size());
  std::iota(frames.begin(), frames.end(), std::size_t{0});
  const TraceReplay t = ReplayTrace(reader, frames, config, {}, sample);
  return {SecondsSince(start), t.total.fetches, t.total.time.picoseconds()};
}

// Bits in a number's binary form: 0 for 0, 1 for 1, 64 for 2^63.
int BitLength(std::uint64_t v) { return v ? 64 - __builtin_clzll(v) : 0; }

// num / den (den > 0) rounded to the nearest double, ties to even, as Python's int / int
// divides, whatever the size of the integers (a division of doubles would round them first
// from 2^53 up): the quotient scaled by 2^k into [2^52, 2^53), rounded on its remainder.
double IntegerRatio(std::uint64_t num, std::uint64_t den) {
  RAYCELL_CHECK(den > 0);
  if (num == 0) return 0.0;
  using U128 = unsigned __int128;
  int k = 52 + BitLength(den) - BitLength(num);  // the quotient then has 52 or 53 bits
  const auto scaled = [&](int shift, U128* q, U128* r, U128* d) {
    const U128 n = shift >= 0 ? U128{num} << shift : U128{num};
    *d = shift >= 0 ? U128{den} : U128{den} << -shift;
    *q = n / *d, *r = n % *d;
  };
  U128 q, r, d;
  scaled(k, &q, &r, &d);
  if (q < (U128{1} << 52)) scaled(++k, &q, &r, &d);
  RAYCELL_CHECK(q >= (U128{1} << 52) && q < (U128{1} << 53));
  if (2 * r > d || (2 * r == d && (q & 1))) ++q;  // to nearest, ties to even
  return std::ldexp(double(std::uint64_t(q)), -k);
}

// (value - reference) / reference, as Python computes it from the two integers. InputError
// when the reference is 0.
double Change(std::uint64_t value, std::uint64_t reference, const std::string& what) {
  if (reference == 0) throw InputError("run time against error: " + what + " is 0");
  const double magnitude =
      IntegerRatio(value >= reference ? value - reference : reference - value, reference);
  return value >= reference ? magnitude : -magnitude;
}

double AbsChange(std::uint64_t value, std::uint64_t reference, const std::string& what) {
  return std::abs(Change(value, reference, what));
}

// The max depth knob of kDeepestMaxDepth, the max depth rows' reference.
const AccuracyKnob& Deepest() {
  for (const AccuracyKnob& k : AccuracyKnobs()) {
    if (k.max_depth == kDeepestMaxDepth) return k;
  }
  RAYCELL_CHECK(false);
  return AccuracyKnobs().front();
}

// A capture measured against a reference capture: its seconds, frames and Cell Tree
// scheduling's fetches.
struct Captured {
  double seconds = 0;
  std::vector<Rgb8Image> frames;
  std::uint64_t fetches = 0;
};

Captured Capture(const AccuracyOptions& o, const AccuracyKnob& k) {
  Captured c;
  c.seconds = RecordKnob(o, k);
  c.frames = Frames(o, k);
  c.fetches = ReplayKnob(KnobTrace(o, k), "ray", 1).fetches;
  return c;
}

const AccuracyKnob& Find(AccuracyPart part, bool is_default) {
  for (const AccuracyKnob& k : AccuracyKnobs()) {
    if (k.part == part && k.is_default == is_default) return k;
  }
  RAYCELL_CHECK(false);
  return AccuracyKnobs().front();
}

AccuracyRow Row(const AccuracyKnob& k, double seconds, double time_ratio, double error,
                const std::string& error_kind, double fetch_change) {
  return {k.knob, k.value, seconds, time_ratio, error, error_kind, fetch_change, k.is_default};
}

// A renderer or max depth row: capture `c` against the reference capture `base` (`what`:
// "step 0.25", "max depth 5").
AccuracyRow CaptureRow(const AccuracyKnob& k, const Captured& c, const Captured& base,
                       const std::string& what) {
  return Row(k, c.seconds, c.seconds / base.seconds, ImageRmse(c.frames, base.frames),
             "image RMSE vs " + what, Change(c.fetches, base.fetches, what + "'s fetches"));
}

// A replay row: replay `r` against the replay `base` it is measured from (`what`: "per ray
// segment", "without sampling").
AccuracyRow ReplayRow(const AccuracyKnob& k, const Replayed& r, const Replayed& base,
                      const std::string& what) {
  return Row(k, r.seconds, r.seconds / base.seconds,
             AbsChange(r.time_ps, base.time_ps, "the simulated time " + what),
             "simulated time, relative", Change(r.fetches, base.fetches, "the fetches " + what));
}

}  // namespace

std::string KnobTrace(const AccuracyOptions& o, const AccuracyKnob& k) {
  return (fs::path(o.out) / k.folder / "c.rct").string();
}

const std::vector<AccuracyKnob>& AccuracyKnobs() {
  static const std::vector<AccuracyKnob> knobs = MakeKnobs();
  return knobs;
}

std::string SceneNotLoadable(const std::string& scene) {
  try {
    SceneSpec spec;
    spec.source = scene;
    Scene::Load(spec, 0);
  } catch (const InputError& e) {
    return "the scene `" + scene + "` cannot be loaded here (" + e.what() + ")";
  }
  return "";
}

AccuracyStudy MeasureAccuracy(const AccuracyOptions& o) {
  AccuracyStudy study;
  study.options = o;
  if (o.frames <= 0) return study;  // not asked for
  study.not_measured = SceneNotLoadable(o.scene);
  if (!study.not_measured.empty()) return study;
  if (!o.quiet) {
    std::cerr << "measuring run time against error: " << o.frames << " frame(s) of `" << o.scene
              << "` at " << o.res << " in 3x3x3 cells, captures in " << o.out << "/\n";
  }
  fs::create_directories(o.out);
  const AccuracyKnob& reference = AccuracyKnobs().front();
  RAYCELL_CHECK(reference.part == AccuracyPart::kReference);
  const Captured finest = Capture(o, reference);
  study.rows.push_back(Row(reference, finest.seconds, 1.0, 0.0, "reference", 0.0));
  // The max depth rows' reference, captured when the first of them is measured.
  Captured deepest;
  const std::string deepest_name = "max depth " + std::to_string(kDeepestMaxDepth);
  // The replay rows replay the capture at the renderer's default settings.
  const std::string trace = KnobTrace(o, Find(AccuracyPart::kRenderer, true));
  Replayed per_segment, unsampled;
  for (const AccuracyKnob& k : AccuracyKnobs()) {
    switch (k.part) {
      case AccuracyPart::kReference:
        break;
      case AccuracyPart::kRenderer:
        study.rows.push_back(CaptureRow(k, Capture(o, k), finest, "step 0.25"));
        break;
      case AccuracyPart::kDepth: {
        if (deepest.frames.empty()) deepest = Capture(o, Deepest());
        const bool is_deepest = k.max_depth == kDeepestMaxDepth;
        study.rows.push_back(
            CaptureRow(k, is_deepest ? deepest : Capture(o, k), deepest, deepest_name));
        break;
      }
      case AccuracyPart::kGranularity: {
        const Replayed r = ReplayKnob(trace, k.granularity, k.sample);
        if (k.granularity == "ray") per_segment = r;  // the first row, the baseline
        RAYCELL_CHECK(per_segment.seconds > 0);
        study.rows.push_back(ReplayRow(k, r, per_segment, "per ray segment"));
        break;
      }
      case AccuracyPart::kSampling: {
        // Sampling saves time where segments are replayed one by one: against the same replay
        // without sampling, measured once before the sampled ones.
        if (unsampled.seconds == 0) unsampled = ReplayKnob(trace, "ray", 1);
        const Replayed r = ReplayKnob(trace, k.granularity, k.sample);
        study.rows.push_back(ReplayRow(k, r, unsampled, "without sampling"));
        break;
      }
    }
  }
  study.measured = true;
  return study;
}

}  // namespace raycell
