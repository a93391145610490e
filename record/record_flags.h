// The options of `raycell record` as its command line holds them, and the one mapping from
// them to RecordOptions. The record command fills RecordFlags from its flags; the study's run
// time against error captures fill them as `raycell record` with the same flags would, so a
// capture made in the study is the one the command makes.
#pragma once

#include <string>
#include <vector>

#include "record/recorder.h"

namespace raycell {

struct RecordFlags {
  RecordFlags() { opt.images_dir = "out/images"; }
  // What the command line sets directly (--scene, --step, --shadow-step, --cutoff, --out,
  // --images, ...), with record's defaults; images go to "out/images/" unless told otherwise.
  RecordOptions opt;
  // What is parsed below: --frames A..B, --cells, --res, --orbit DEGREES or FRAMES:DEGREES,
  // --eye, --target, --up (empty: 0,1,0 or the scene file's), --precision, --image-encoding,
  // --light (repeatable).
  std::string frames, cells = "2x2x2", res = "256x256", orbit, eye, target, up,
                      precision = "double", image_encoding = "srgb";
  std::vector<std::string> lights;
  bool fov_given = false;  // --fov was given (opt.camera.fov_deg), over a scene file's
  bool no_images = false, quiet = false;
};

// The options the flags give. InputError naming the flag on bad text (and for a sequence
// pattern without --frames A..B). A scene file (--scene builtin or FILE.toml) is read here
// and the flags applied to it (docs/scenes.md "Flags over the file"): --grid and
// --all-grids choose its grids, --material and --light replace what it says, --eye,
// --target, --up, --fov, --orbit and --keyframes its camera, --frames its frames; the
// result is opt.scene.description, and the camera and frames come from it.
RecordOptions ToRecordOptions(const RecordFlags& flags);

}  // namespace raycell
