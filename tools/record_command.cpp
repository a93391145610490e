// raycell record: render a scene's frames and write their trace (and images).
#include <array>
#include <atomic>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>

#include "base/check.h"
#include "record/record_flags.h"
#include "record/recorder.h"
#include "record/scene_file.h"
#include "tools/commands.h"
#include "traces/subdivision.h"
#include "traces/trace_regroup.h"

namespace raycell {
namespace {

std::atomic<bool> g_cancel{false};

extern "C" void OnSignal(int) { g_cancel.store(true); }

// --cells auto:N (docs/design.md §1 "auto:N"): recorded on the fine grid of 4 x 4 x 4 fine
// cells per cell of its baseline (12x12x12 for auto:27) as a regroupable capture beside OUT,
// then written to OUT with each frame in the cells auto:N chooses for it from the frames before
// it (trace regroup), the fine capture removed. Empty: not auto:N.
std::string AutoCells(RecordFlags* a) {
  if (a->cells.rfind("auto:", 0) != 0) return "";
  const SubdivisionSpec spec = ParseSubdivisionSpec(a->cells, "--cells");
  const std::uint32_t most = kMaxCaptureCells;
  const std::array<std::uint32_t, 3> g = CubicGrid(spec.cells, {most, most, most}, "--cells");
  a->cells =
      std::to_string(4 * g[0]) + "x" + std::to_string(4 * g[1]) + "x" + std::to_string(4 * g[2]);
  a->opt.regroupable = true;
  return spec.ToString();
}

void Run(RecordFlags a, bool print_scene) {
  const std::string auto_spec = print_scene ? std::string() : AutoCells(&a);
  RecordOptions o = ToRecordOptions(a);
  if (print_scene) {
    if (!o.scene.description) {
      throw InputError("--print-scene: --scene '" + o.scene.source +
                       "' is not a scene file (builtin or FILE.toml)");
    }
    std::cout << PrintSceneDescription(*o.scene.description);
    return;
  }
  const std::string out = o.out;
  if (!auto_spec.empty()) o.out = out + ".fine";
  o.cancel = &g_cancel;
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  const RecordSummary s = Record(o, std::cerr);
  if (s.interrupted) std::exit(130);
  if (!auto_spec.empty()) {
    try {
      RegroupTrace(o.out, auto_spec, out);
    } catch (...) {
      std::filesystem::remove(o.out);
      throw;
    }
    std::filesystem::remove(o.out);
    o.out = out;
  }
  std::cerr << "recorded " << s.frames << " frame(s), " << s.rays << " rays, " << s.visits
            << " visits in " << s.seconds << " s -> " << o.out
            << (o.images_dir.empty() ? "" : ", images in " + o.images_dir + "/") << "\n";
}

}  // namespace

void AddRecordCommand(CLI::App& app) {
  auto args = std::make_shared<RecordFlags>();
  RecordOptions& o = args->opt;
  CLI::App* cmd =
      app.add_subcommand("record", "Render a scene and record every ray's path through the cells.");
  cmd->footer(
      "Writes one trace file (zstd frames of Cap'n Proto messages, see traces/trace.capnp)\n"
      "and one PNG per frame. With no options it records frame 0 of the built-in scene\n"
      "(fog, a mirror sphere and a glass icosahedron) at 256x256 in 2x2x2 cells.\n"
      "Fog is rendered as vdb_render renders it (same steps, cutoff, light, absorption,\n"
      "scattering and gain give the same radiance, and the same grid of a file by default).\n"
      "PNGs are sRGB-encoded for display (vdb_render writes linear values, which look\n"
      "darker): compare with vdb_render's images after --image-encoding linear.\n"
      "A ray's visits are the non-empty cells its path crosses, each with the volume samples\n"
      "taken there; empty cells (footprint 0) are crossed without work and never recorded.\n"
      "Ctrl-C stops the capture; the finished frames stay readable in OUT.tmp.\n\n"
      "Examples:\n"
      "  raycell record --scene ../shared/data/mj_smoke.vdb --cells 3x3x3 --orbit 30:360\n"
      "  raycell record --orbit 30:360 --frames 10..19 --out part2.rct   # join the parts\n"
      "                                              # with `raycell trace concat`\n"
      "  raycell record --scene 'fluid_data_%04d.vdb' --frames 150..155 --out fluid.rct\n"
      "  raycell record --material cloud:absorb=0.01:scatter=0.05 --light point:0,3,0\n"
      "  raycell record --scene scenes/glass.toml --res 128x128 --cells 3x3x3\n"
      "  raycell record --scene scenes/glass.toml --orbit 4:30 --print-scene > mine.toml\n\n"
      "Scene files (docs/scenes.md): grids from VDB files or made with OpenVDB's tools\n"
      "(spheres, boxes, platonic solids, CSG, fog from a level set, seeded noise, animation),\n"
      "materials, lights, sky, camera path and frames. The flags override the file:\n"
      "--grid/--all-grids choose its grids, --material changes a grid's keys, --light\n"
      "(any) replaces its lights, --eye/--target/--up/--fov its camera, --orbit or\n"
      "--keyframes its camera path, --frames its frames.");
  cmd->add_option("--scene", o.scene.source,
                  "builtin (scenes/builtin.toml, compiled in), a scene file FILE.toml, a .vdb "
                  "file (fog volumes and level sets), or a printf pattern of one file per "
                  "frame, e.g. fluid_data_%04d.vdb with --frames 150..155")
      ->capture_default_str();
  auto print_scene = std::make_shared<bool>(false);
  cmd->add_flag("--print-scene", *print_scene,
                "write the resolved scene file (defaults filled in, the flags applied) to "
                "stdout and exit: recording it gives the same trace");
  cmd->add_option("--grid", o.scene.grids,
                  "render this float grid of the file, repeatable; default: the first float "
                  "grid (as vdb_render and its -name), every grid of the built-in scene");
  cmd->add_flag("--all-grids", o.scene.all_grids,
                "render every float grid of the file (fog volumes add up)");
  cmd->add_option("--frames", args->frames,
                  "frame numbers A..B (inclusive), default 0 (or every frame of --orbit "
                  "FRAMES:DEGREES); at most " +
                      std::to_string(kMaxCaptureFrames) +
                      " frames. With a camera path, frames A..B of it: each frame gets the "
                      "camera a capture of the whole path gives it");
  cmd->add_option("--cells", args->cells,
                  "cell grid NXxNYxNZ splitting the scene box; at most " +
                      std::to_string(kMaxCaptureCells) +
                      " cells; or auto:N, the recommended N cells, per frame from the frames "
                      "before it (recorded on 4x4x4 fine cells per cell of its baseline grid, "
                      "then regrouped: docs/design.md §1 \"auto:N\")")
      ->capture_default_str();
  cmd->add_option("--res", args->res,
                  "image size WxH (the paper: 256x256); at most " + std::to_string(kMaxPixels) +
                      " pixels (8192x8192)")
      ->capture_default_str();
  cmd->add_option("--spp", o.settings.spp,
                  "samples (primary rays) per pixel, 1..4096; pixels x spp at most " +
                      std::to_string(kMaxPrimaryRays))
      ->capture_default_str();
  cmd->add_option("--max-depth", o.settings.max_depth,
                  "reflection/refraction generations, 0..16; shadow rays are cast at every depth")
      ->capture_default_str();
  cmd->add_option("--step", o.settings.primary_step,
                  "primary-ray step in voxels (vdb_render's -step)")
      ->capture_default_str();
  cmd->add_option("--shadow-step", o.settings.shadow_step,
                  "shadow-ray step in voxels (vdb_render's -shadowstep)")
      ->capture_default_str();
  cmd->add_option("--cutoff", o.settings.cutoff,
                  "early-termination threshold on transmittance, and the density below which a "
                  "sample casts no shadow ray (vdb_render's -cutoff)")
      ->capture_default_str();
  cmd->add_option("--precision", args->precision,
                  "arithmetic of the marcher (sample positions, optical depth, transmittance, "
                  "radiance): double, or single as hardware would; BENCHMARKS.md has the error "
                  "and speed of each")
      ->check(CLI::IsMember({"double", "single"}))
      ->capture_default_str();
  cmd->add_option("--material", o.scene.materials,
                  "per-grid material, repeatable. Fog: GRID:absorb=R,G,B:scatter=R,G,B:gain=G "
                  "(per voxel, as vdb_render; >= 0). Surface: GRID:color=R,G,B:reflect=F:"
                  "transparency=F:ior=N (colour, reflect, transparency in 0..1, reflect + "
                  "transparency <= 1, ior in 1..10)");
  cmd->add_option("--light", args->lights,
                  "light, repeatable: dir:X,Y,Z[:R,G,B] (towards the light) or "
                  "point:X,Y,Z[:R,G,B] (colour in 0..1e30); default the scene's own (files: "
                  "vdb_render's dir:0.3,0.3,0:0.7,0.7,0.7)");
  cmd->add_option("--eye", args->eye, "camera position X,Y,Z (default: frames the scene box)");
  cmd->add_option("--target", args->target, "point the camera looks at (default: box centre)");
  cmd->add_option("--up", args->up, "camera up vector (default 0,1,0, or the scene file's)");
  CLI::Option* fov =
      cmd->add_option("--fov", o.camera.fov_deg,
                      "vertical field of view, degrees in (0, 180) (vdb_render's -fov is the "
                      "horizontal one: equal for square images)")
          ->capture_default_str();
  cmd->add_option("--orbit", args->orbit,
                  "camera path: FRAMES:DEGREES turns DEGREES about the up axis over frames "
                  "0..FRAMES-1 and records them, or the range --frames A..B of them (e.g. "
                  "30:360 --frames 10..19); DEGREES alone turns DEGREES over the frames "
                  "recorded (with --frames A..B: frame A at 0 degrees, so captures of two "
                  "ranges are not parts of one path)");
  cmd->add_option("--keyframes", o.camera.keyframes_file,
                  "camera path from a file of lines 'frame ex ey ez tx ty tz fov', "
                  "interpolated linearly")
      ->check(CLI::ExistingFile);
  cmd->add_option("--footprint", o.scene.footprint_mode,
                  "cell footprint: sparse (allocated leaves) or dense (voxels)")
      ->capture_default_str();
  cmd->add_flag("--regroupable", o.regroupable,
                "a fine capture that any coarser subdivision can be made of (`raycell trace "
                "regroup`, or --cells SPEC of analyze, replay, sweep): rays also visit the "
                "empty cells they cross, and the trace holds each cell's leaves; e.g. "
                "--cells 12x12x12 --regroupable");
  cmd->add_option("--trace-format", o.trace_format,
                  "the trace's format version: 5 (the faster to read), 6 (each visit's samples "
                  "range coded: files about a sixth smaller, read with about a quarter more CPU), "
                  "7 (6 with samples also predicted from earlier visits of the cell) or 8 (7 "
                  "with paths also range coded, predicted from earlier rays through the cell: the "
                  "smallest, the slowest to read)")
      ->check(CLI::IsMember({5, 6, 7, 8}))
      ->capture_default_str();
  cmd->add_option("--out", o.out, "trace file to write")->capture_default_str();
  cmd->add_option("--images", o.images_dir, "folder for frame_NNNN.png")->capture_default_str();
  cmd->add_option("--image-encoding", args->image_encoding,
                  "PNG values: srgb (for display, tagged sRGB) or linear (radiance x 255, "
                  "tagged gamma 1.0, comparable with vdb_render's PNGs)")
      ->capture_default_str();
  cmd->add_flag("--no-images", args->no_images, "do not write images");
  cmd->add_flag("--store-t", o.settings.store_t,
                "also store each visit's t_enter/t_exit (larger traces)");
  cmd->add_option("--zstd-level", o.settings.zstd_level, "zstd compression level 1..19")
      ->capture_default_str();
  cmd->add_option("--threads", o.threads,
                  "rendering threads, 0..1024, 0 = all cores (the trace is the "
                  "same byte for byte whatever this is)")
      ->capture_default_str();
  cmd->add_flag("--quiet", args->quiet, "no progress bar");
  cmd->callback([args, fov, print_scene] {
    args->fov_given = fov->count() > 0;
    Run(*args, *print_scene);
  });
}

}  // namespace raycell
