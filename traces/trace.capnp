# raycell trace file schema, format version 7 (docs/design.md §3 "The trace"). The format's
# constants and limits are in traces/format.h.
#
# A trace file (".rct") is a sequence of zstd frames:
#   1. one zstd frame holding one Record message whose union is `header`, then one or more
#      Records `footprints` holding the cells' footprints in cell order (at most 2^20 runs
#      each, so a grid of 2^24 cells fits however its footprints vary). Version 1 files have
#      the footprints in Header.footprints and no `footprints` records;
#   2. per captured frame, one zstd frame holding one or more Record messages whose union
#      is `batch` (by default at most 65536 rays, 2^18 in versions 6 to 8, and about 2^20
#      visits each, so every message stays far below Cap'n Proto's 64 MiB traversal limit),
#      then exactly one Record
#      `frameEnd`; a frame without rays has only the `frameEnd`;
#   3. a zstd skippable frame (magic 0x184D2A5B) holding the index: one Index message
#      (unpacked, standard framing) followed by a 24-byte trailer:
#        UInt64 LE  hash64 of the Index message bytes (see "Checksums" below)
#        UInt64 LE  byte length of the Index message
#        8 bytes    "RCTINDEX"
#      The trailer ends the file, so a reader finds the index from the last 32 bytes.
# Every message uses the standard (unpacked) Cap'n Proto stream framing, so
#   zstd -dc FILE | capnp decode traces/trace.capnp Record
# prints the whole file (zstd skips the index frame).
#
# Column encoding. Ray and visit data are struct-of-arrays lists. Integer columns are a
# `Column`: one byte per value, escaping big values into a UInt64 list. Signed deltas are
# zigzag-coded first: zigzag(d) = (d << 1) ^ (d >> 63), so 0,-1,1,-2,2 -> 0,1,2,3,4.
# Rays are coded against earlier rays of the same batch (never of another batch, so every
# batch decodes on its own), so that runs of similar rays, such as the dozens of shadow rays
# a primary ray casts from one pixel, become runs of equal bytes, which zstd stores in almost
# nothing. For ray i of a batch (its id is firstId + i):
#   previous ray         ray i-1 of the batch; none for ray 0.
#   sibling              the previous ray, when it has the same parent as ray i (two primary
#                        rays count as siblings: neither has a parent); else none.
#   group start          a ray that is not primary and has no sibling (the first of a run
#                        of rays cast from one parent).
#   ordinal              (version 5) 0, or the previous ray's ordinal + 1 when the previous
#                        ray has the same parent and the same kind as ray i: the ray's place
#                        in its run of siblings of its kind.
#   reference ray        version 5: for a primary ray, the last primary ray before it in the
#                        batch. For another ray, by the batch's referenceRule: 0, the sibling
#                        rule, as in versions 1-4 (below); 1, the corresponding rule: for a
#                        ray whose parent is in the batch, the last ray before it in the
#                        batch that has the same kind, the same ordinal and a parent in the
#                        batch of the same kind as its parent (the corresponding ray of the
#                        previous pixel, typically: the shadow ray cast from the same place
#                        along the previous pixel's primary ray) if there is one, else its
#                        sibling; for a ray whose parent is before the batch, its sibling;
#                        else none.
#                        Versions 1-4 (and the sibling rule): for a primary ray, the last primary ray before it in
#                        the batch; for a ray with a sibling that is not primary, its sibling;
#                        for a group start whose parent is in the batch, the last group start
#                        before it in the batch that has the same kind and whose parent is in
#                        the batch and has the same kind as its parent; else none.
#   last non-shadow ray  the last ray before ray i in the batch whose kind is not shadow; may
#                        be none.
# Ray heads. Each ray has one head byte:
#   bits 0-1  kind: 0 primary, 1 reflection, 2 refraction, 3 shadow.
#   bits 2-3  parent code: 0 = the parent is the last non-shadow ray; 1 = the parent is the
#             previous ray's parent (the previous ray is not primary); 2 = id - parentId
#             (>= 1) is the next value of `parents`; 3 is invalid. Primary rays have no
#             parent and code 0.
#   bits 4-5  spawn code: with p = the sibling's spawn (0 when there is no sibling), code
#             0, 1 or 2 means spawn = p + code; 3 means the spawn is the next value of
#             `spawns`. Primary rays have spawn 0 and code 0.
#   bit 6     new path: set, the visit count and cells are the next values of primaryPaths
#             (primary rays) or secondaryPaths (other rays), or in version 8 the next path of
#             pathCode; clear, they are those of the reference ray (which must exist).
#   bit 7     new pixel: set, the next two values of `pixels` are zigzag(x - previous ray's x)
#             and zigzag(y - previous ray's y), taking (0, 0) for the previous pixel of ray 0;
#             clear, the pixel is the previous ray's ((0, 0) for ray 0).
# The writer uses the lowest parent and spawn code that applies and clears bits 6 and 7
# whenever it can. Heads are run-length coded: `heads` has one byte per run of consecutive
# rays with equal heads and `headRuns` the run's length minus 1.
# Paths (version 5). A path (in primaryPaths or secondaryPaths) is its visit count, then per
# visit the step to its cell from the previous visit's cell; the first visit's step starts
# from the predicted cell: for a ray whose parent is in the batch and has more than `spawn`
# visits, the parent's cell at visit `spawn`; else the reference ray's first cell if it has
# a visit; else the first cell of the last ray before it in the batch that has a visit; else
# cell 0. A step from cell (x, y, z) (cell = x + nx*(y + ny*z)) to (x+dx, y+dy, z+dz) is one
# value (dx+2) + 5*(dy+2) + 25*(dz+2) (0..124) when |dx|, |dy| and |dz| are at most 2, else
# 125 followed by zigzag(dx), zigzag(dy), zigzag(dz); a step leaving the grid is invalid.
# (Versions 1-4: the first visit's cell id, then zigzag(cell - previous visit's cell).)
# Version 8: in a batch whose pathCode is not empty, new paths are not in primaryPaths and
# secondaryPaths (empty) but range coded in Batch.pathCode, ray by ray in ray order, with version 6's coder (see "Samples"): a path is
# its symbols, the step codes above (0..125) from the same predicted cell and then 126, the
# end (so no visit count). A symbol is coded in its context: g the ray's group (as in
# "Samples"), its place on the path (0 the first symbol, 1 the second, 2 later), h the ray's
# hint (the class, as in version 7's table, of the step by which its parent entered the cell
# it spawned the ray in: 27 at the parent's first visit, 28 for a primary ray, a parent outside
# the batch or a spawn past its visits), the cell the step leaves and the classes i and j of
# the steps into it and before that (i = 27 before the first step, j = h for the first two
# symbols). Its prediction: from the second symbol on, when the reference ray visits the cell
# (searched as samples are matched), the reference's symbol out of that visit (its step to its
# next visit, or 126 at its last); else the batch's path table: 2^14 slots, key
# k = (((cell * 3 + g) * 28 + i) * 29 + j) + 1 in slot (k * 0x9E3779B97F4A7C15 mod 2^64) >> 50,
# holding the symbol last coded under k (a slot holding another key is a miss); every symbol
# decoded replaces its slot's. Where there is a prediction, one bit (0: the symbol is the
# prediction) under model ((g * 3 + place) * 4 + o) * 3 + src, with o the previous symbol's
# outcome (0 none, 1 held, 2 failed, 3 no prediction) and src 0 for the table, 2 for the
# reference agreeing with the table, 1 for it alone; where there is none or it failed, the
# symbol's 7 bits, most significant first, in a bit tree (node 1, then 2*node + bit; a symbol
# above 126 is invalid) of tree t = 0 (first symbol), 1 + h (second) or 30 (later), model set
# (g * 31 + t) * 2 + f, f 1 when a prediction failed. After symbol 125 its zigzag(dx),
# zigzag(dy), zigzag(dz) follow, each coded as a sample value (length, tree, plain bits) in
# context 0, 1, 2 by axis. Every model starts at 1024 in every batch, the table empty.
# Samples. Version 5: the samples of visit v of a ray are predicted from the reference ray's
# visit of the same cell, searched from the reference visit after the last one matched (the
# first, at the ray's first visit) among at most 4 visits (kSampleMatchWindow); the residual
# zigzag(samples - that visit's samples) is stored when one is found, else the samples
# themselves. primarySamples (visits of primary rays), secondarySamples (of reflection and
# refraction rays) and shadowSamples (of shadow rays) hold them in ray and visit order.
# Versions 1-4: the prediction is the reference ray's samples at visit v when it has more
# than v visits, and secondarySamples holds the visits of every ray that is not primary.
# Version 6: the same values (residual or samples, per visit of every ray of the batch, in
# ray and visit order) are range coded in Batch.sampleCode, the three samples columns empty.
# The coder is LZMA's binary range coder (traces/sample_coder.h): 32-bit range, carries
# propagated through a cache byte, 5 bytes flushed at the end; a bit with probability p/2048
# of being 0 splits the range at (range >> 11) * p, and p then moves by (2048 - p) >> 4 after
# a 0 or by -(p >> 4) after a 1 (p starts at 1024); a plain bit halves the range. The code
# must end exactly at the last byte. A value v is coded as u = v + 1: its length e =
# floor(log2 u) in unary (bit i, 1 while e > i, for i < min(e + 1, 40)), then the top
# min(e, 3) bits of u below its leading one in a bit tree (node 1, then 2*node + bit), then
# its remaining bits as plain bits, most significant first. Every bit model belongs to the
# visit's context: c = ((((g * 2 + n) * 2 + m) * 7 + s) * 2 + l) * 8 + q, where g is the ray's
# group (0 primary, 1 reflection or refraction, 2 shadow), n its new-path bit, m 1 when the
# value is a residual, s the size class (0, 1, 2-3, 4-7, 8-15, 16-31, >= 32 -> 0..6) of the
# predicting visit's samples when it is a residual, else of the ray's previous visit's
# samples (0 at its first visit), l 1 at the ray's last visit, and q the ray's previous
# value: 0 at its first visit, 1 when that was not a residual, else its residual clamped to
# -2..3, plus 4. Each context has its own length bits and its own tree for each length up
# to 12 (longer lengths share the tree of 12). All models start anew in every batch.
# Version 7: version 6 but for what some values are predicted from, in a batch whose
# visitTable is set (else the batch's samples are coded as version 6's). Each batch keeps a visit
# table, empty at its start: per key (the ray's group g, the visit's cell, and the classes of
# the steps into and out of it: the sign of each axis's difference, (sx+1) + 3(sy+1) + 9(sz+1),
# or 27 at the ray's first visit for the step in and at its last for the step out), the
# samples of the last visit of the batch with that key. The table has 2^15 slots; key
# k = ((cell * 3 + g) * 28 + in) * 28 + out + 1 goes to slot (k * 0x9E3779B97F4A7C15 mod 2^64)
# >> 49, which holds one key: a slot holding another key is a miss. After each visit is
# decoded its key and samples replace the slot's. A visit whose key is found (samples t):
# if the reference has no visit of the cell (no version 6 residual), the value is
# zigzag(samples - t), coded as a residual predicted from t (m = 1, s of t) with p = 1; if it
# has one (samples r) and the ray has a path of its own, the value is zigzag(samples - t) with
# p = 3 when r = t, else p = 2; otherwise (a miss, or the ray repeats its reference's path) the
# value and context are version 6's with p = 0. The context is c + 1344 * p (c as version 6's,
# m and s those of the value coded), and q after the visit follows the value coded.
# Versions 1-5: each samples column is zero-run coded: a run of n >= 1
# consecutive zero residuals is written as the digits of n in bijective base 2, least
# significant first, digit 1 as the value 0 and digit 2 as the value 1; any other residual r
# is written as r + 1. A run ends at the first value >= 2 or at the end of the column. For
# example the residuals 0 0 0 5 0 are written 0 0 6 0 (3 = 1 + 1*2).
# Limits. A batch holds at most 2^22 rays and 2^25 visits; a ray at most 2^20 visits. A file
# has at most 2^24 cells (nx*ny*nz), 2^18 frames (cameras, index entries), 1024 grids, and
# 4096 bytes in each text field.
#
# Checksums. hash64 is raycell's 64-bit word hash (Hash64 in traces/trace_writer.h):
#   h = seed; for each 64-bit word w: h = rotl64(h ^ (w * P2), 31) * P1;
#   finally h ^= h >> 33; h *= P2; h ^= h >> 29; h *= P3; h ^= h >> 32
# with P1 = 0x9E3779B185EBCA87, P2 = 0xC2B2AE3D27D4EB4F, P3 = 0x165667B19E3779F9 and
# seed = 0x52435431 ("RCT1"). Byte strings are hashed as little-endian words, the last one
# zero-padded, followed by one word holding the byte length.
# A frame's checksum hashes its decoded logical content, ray by ray in id order: for each
# ray the words kind, parent (0xFFFFFFFFFFFFFFFF for primary rays), spawn, pixel x,
# pixel y, visit count, then per visit cell, samples and, when the header's
# settings.storeT is set, (bits(tEnter) << 32 | bits(tExit)). It does not depend on how
# the rays were split into batches.

@0x9a71f44186422e45;

using Cxx = import "/capnp/c++.capnp";
$Cxx.namespace("raycell::schema");

const formatVersion :UInt32 = 7;
# The format version this schema describes; Header.formatVersion of files written with it.
# Version 6 differs only in its sample code's predictions (no visit table; see "Samples").
# Version 5 differs only in its samples: in primarySamples, secondarySamples and
# shadowSamples, zero-run coded, and no Batch.sampleCode (see "Samples").
# Version 4 differs only in its batch encoding (see "Column encoding": reference rays, paths
# as cell ids and deltas, no Batch.shadowSamples); its header and records are version 5's.
# Version 3 differs only in having no Header.regroupable, leafCount and subdivision (read as
# false, 0 and the uniform grid) and no leafBytes or cellLeaves records.
# Version 2 differs only in having no Header.path (the camera path is not recorded; readers
# take it as unknown, kind ""); version 1 also in where the footprints are
# (Header.footprints).

# Every message of the file has this root, so one `capnp decode` reads the whole file.
struct Record {
  union {
    header @0 :Header;
    # First message of the file, alone in the first zstd frame.
    batch @1 :Batch;
    # A run of consecutive rays of one frame.
    frameEnd @2 :FrameEnd;
    # Last message of each frame's zstd frame.
    footprints @3 :Footprints;
    # Cell footprints, after the header in its zstd frame (version 2).
    leafBytes @4 :Footprints;
    # A regroupable capture's leaves (version 4), after the footprints: the bytes of leaves
    # firstCell.. (here a leaf number), as runs; they cover leaves 0..Header.leafCount-1.
    cellLeaves @5 :CellLeaves;
    # A regroupable capture's leaves per cell (version 4), after the leafBytes records.
  }
}

struct Vec3 {
  x @0 :Float64;  # world units
  y @1 :Float64;  # world units
  z @2 :Float64;  # world units
}

struct Grid {
  name @0 :Text;
  # Grid name in its .vdb file ("density", "surface", ...).
  role @1 :Text;
  # "fog" (density volume) or "surface" (level set).
  source @2 :Text;
  # The file the grid came from, or "builtin".
  voxelSize @3 :Float64;
  # Edge length of one voxel, world units.
  leafCount @4 :UInt64;
  # Number of allocated leaf nodes of the grid.
}

struct Camera {
  frame @0 :Int32;
  # Frame number this camera renders (e.g. 150 for fluid_data_0150.vdb).
  eye @1 :Vec3;
  # Camera position, world space.
  target @2 :Vec3;
  # Point the camera looks at, world space.
  up @3 :Vec3;
  # Up vector, world space (not necessarily normalised).
  fovDeg @4 :Float64;
  # Vertical field of view, degrees.
}

struct Settings {
  width @0 :UInt32;
  # Image width, pixels.
  height @1 :UInt32;
  # Image height, pixels.
  spp @2 :UInt32;
  # Primary rays per pixel.
  maxDepth @3 :UInt32;
  # Maximum depth of secondary rays (a primary ray has depth 0).
  primaryStep @4 :Float64;
  # Volume sampling step of primary, reflection and refraction rays, in voxels of the
  # finest fog grid (as vdb_render's --step).
  shadowStep @5 :Float64;
  # Volume sampling step of shadow rays, same unit.
  cutoff @6 :Float64;
  # Early-termination threshold on transmittance (unitless, 0..1).
  storeT @7 :Bool;
  # Batches carry Batch.tEnter/tExit (one Float32 per visit each).
  zstdLevel @8 :UInt32;
  # zstd compression level the file was written with.
  singlePrecision @9 :Bool;
  # The marcher computed in single precision (Float32) rather than double; files written
  # before this field read as double.
}

struct Header {
  formatVersion @0 :UInt32;
  # File format version (see `formatVersion` above). Readers reject newer versions.
  producer @1 :Text;
  # Program and version that wrote the file, e.g. "raycell 0.1.0".
  scene @2 :Text;
  # The scene as given on the command line (--scene).
  grids @3 :List(Grid);
  # The OpenVDB grids of the scene.
  boxMin @4 :Vec3;
  # Minimum corner of the world-space scene box that the cells split.
  boxMax @5 :Vec3;
  # Maximum corner of that box.
  cellsX @6 :UInt32;
  # Number of cells along x (nx); cell = x + nx*(y + ny*z).
  cellsY @7 :UInt32;
  # Number of cells along y (ny).
  cellsZ @8 :UInt32;
  # Number of cells along z (nz).
  footprints @9 :List(UInt64);
  # Version 1: bytes a processor loads to work in each cell, indexed by cell; nx*ny*nz
  # entries. Version 2: empty; the footprints are in `footprints` records.
  footprintMode @10 :Text;
  # How footprints were computed: "sparse" (allocated leaves) or "dense" (all voxels).
  cameras @11 :List(Camera);
  # The camera of every frame the capture holds, in frame order: frames
  # cameras[0].frame..cameras[last].frame, consecutive, a range of `path`.
  settings @12 :Settings;
  # Renderer settings of the capture.
  path @13 :CameraPath;
  # The whole camera path the cameras are a range of (version 3; absent before).
  regroupable @14 :Bool;
  # Version 4: a fine capture (`raycell record --regroupable`) that any coarser subdivision
  # can be made of (docs/design.md §1 "Subdivisions"). Its rays also visit the empty cells
  # (footprint 0) they cross, with 0 samples, from where they enter the box (a primary ray
  # that meets no non-empty cell is kept when it crosses the box) to where they end, or to the
  # box exit when they run past their last non-empty cell. The leafBytes and cellLeaves
  # records give each cell's leaves; footprints are sparse.
  leafCount @15 :UInt64;
  # Regroupable: the number of leaves (allocated leaf nodes and active tiles overlapping a
  # cell). Otherwise 0.
  subdivision @16 :Subdivision;
  # Version 4: the cells' shapes when the trace was regrouped from a fine capture; spec ""
  # (and absent before version 4): the uniform grid cellsX x cellsY x cellsZ of the box.
}

# The cells of a trace regrouped from a fine capture (version 4): each cell a box of the
# fine grid's cells. A subdivision that is not uniform has cellsX = the cell count and
# cellsY = cellsZ = 1; cells are numbered by the lowest corner of their box (z, then y, then
# x), so a uniform one numbers them as a grid captured directly.
struct Subdivision {
  spec @0 :Text;
  # The SPEC it was made by (traces/subdivision.h): "3x3x3", "kd:27:footprint",
  # "kd:budget:256KiB", "octree:256KiB", "dynamic:27". "": the cells are the captured grid.
  fineX @1 :UInt32;
  # Cells of the fine grid along x.
  fineY @2 :UInt32;
  # Cells of the fine grid along y.
  fineZ @3 :UInt32;
  # Cells of the fine grid along z.
  boxes @4 :List(FineBox);
  # Per cell, its box. "dynamic:N": per frame of the file, in frame order, N boxes each
  # (frame f's cell c is boxes[f * N + c]). The boxes of a frame tile the fine grid.
  frameFootprints @5 :List(UInt64);
  # "dynamic:N" only: per box, the footprint of that cell in that frame (Header footprints
  # are each cell's largest over the frames). Empty otherwise.
}

# A box of fine cells [lo, hi) on each axis.
struct FineBox {
  loX @0 :UInt32;
  loY @1 :UInt32;
  loZ @2 :UInt32;
  hiX @3 :UInt32;
  hiY @4 :UInt32;
  hiZ @5 :UInt32;
}

# A regroupable capture's leaves of consecutive cells (version 4): the records cover cells
# 0..nx*ny*nz-1 in order, each continuing where the previous one ended.
struct CellLeaves {
  firstCell @0 :UInt64;
  # The record's first cell.
  counts @1 :Column;
  # Per cell from firstCell: the number of leaves it overlaps.
  leaves @2 :Column;
  # Per cell, its leaves in increasing number: the first's number, then for each later one
  # its number minus the previous one's minus 1.
}

# How the camera of every frame is made (version 3). A capture of frames A..B of a path holds
# the cameras a capture of the whole path has for those frames, and the same path; so
# captures of consecutive ranges of one path join (`raycell trace concat`) into the capture
# of their union.
struct CameraPath {
  kind @0 :Text;
  # "still": the camera (eye, target, up, fovDeg) of every frame. "orbit": frame f's eye is
  # `eye` turned by orbitDegrees * (f - firstFrame) / frameCount degrees about `up` through
  # `target`, for the path's frames firstFrame..firstFrame+frameCount-1. "keyframes": frame
  # f's eye, target and fov interpolated linearly between the two `keys` around f (the first
  # or last key's outside them), up `up`. Empty: not recorded (imported traces).
  firstFrame @1 :Int32;
  # Orbit: the path's first frame. Otherwise 0.
  frameCount @2 :UInt32;
  # Orbit: the path's number of frames (>= 1). Otherwise 0: the path has every frame.
  eye @3 :Vec3;
  # Still and orbit: the eye (of frame firstFrame, for an orbit), world space.
  target @4 :Vec3;
  # Still and orbit: the point looked at, world space.
  up @5 :Vec3;
  # Up vector of every frame (normalised for an orbit), world space.
  fovDeg @6 :Float64;
  # Still and orbit: vertical field of view, degrees.
  orbitDegrees @7 :Float64;
  # Orbit: degrees turned over the path's frameCount frames (frame firstFrame+frameCount
  # would be turned by all of them).
  keys @8 :List(Camera);
  # Keyframes: the key frames in increasing frame order (their `up` is the path's `up`).
}

# Footprints of consecutive cells (version 2): the records after the header cover cells
# 0..nx*ny*nz-1 in order, each continuing where the previous one ended, as runs of cells with
# equal footprints (empty cells, footprint 0, come in long runs). A record has at most 2^20
# runs.
struct Footprints {
  firstCell @0 :UInt64;
  # The record's first cell: the number of cells the records before it cover.
  values @1 :Column;
  # Per run, in cell order: the footprint of its cells, the bytes a processor loads to work
  # in one of them.
  runs @2 :Column;
  # Per run: its number of cells minus 1 (as many values as `values`).
}

# One integer column: value i is narrow[i] when narrow[i] < 255; narrow[i] == 255 is an
# escape and the value is the next unused entry of `wide`. Fixed width, so zstd sees
# aligned repeating bytes.
struct Column {
  narrow @0 :List(UInt8);
  # One byte per value; 0..254 literal, 255 = escape.
  wide @1 :List(UInt64);
  # Escaped values, in column order; one per 255 in `narrow`.
}

# A run of consecutive rays of one frame, coded as described in "Column encoding" above.
# Ray ids are frame-local and consecutive: ray i of the batch has id firstId + i.
struct Batch {
  frame @0 :Int32;
  # Frame number (as in Camera.frame and FrameEnd.frame) these rays belong to.
  firstId @1 :UInt64;
  # Frame-local id of the first ray of the batch (the number of rays before it in the frame).
  heads @2 :List(UInt8);
  # One head byte per run of consecutive rays with equal heads (see "Ray heads").
  headRuns @3 :Column;
  # Per entry of `heads`: the number of rays of the run minus 1. The batch's ray count is
  # the sum of the run lengths.
  parents @4 :Column;
  # Per ray with parent code 2, in ray order: id - parentId (>= 1).
  spawns @5 :Column;
  # Per ray with spawn code 3, in ray order: spawn, the index into the parent's visits of the
  # visit that spawned the ray.
  pixels @6 :Column;
  # Per ray with the new-pixel bit, in ray order: zigzag(x - previous ray's x), then
  # zigzag(y - previous ray's y); x is the image column and y the image row of the pixel the
  # ray feeds.
  primaryPaths @7 :Column;
  # Per primary ray with the new-path bit, in ray order: its visit count (the number of
  # non-empty cells it passes through), then per visit its step code (version 5, see
  # "Paths"); versions 1-4: the first visit's cell id, and for every later visit
  # zigzag(cell - previous visit's cell).
  secondaryPaths @8 :Column;
  # The same for the rays with the new-path bit that are not primary.
  primarySamples @9 :Column;
  # Zero-run coded residuals (see "Samples") of the visits of primary rays. Samples are the
  # volume samples taken in a visit's cell (the work done there). Empty in version 6.
  secondarySamples @10 :Column;
  # The same for the visits of reflection and refraction rays (versions 1-4: of every ray
  # that is not primary). Empty in version 6.
  tEnter @11 :List(Float32);
  # Per visit of the batch (the visits of ray 0, then of ray 1, ...), only when
  # settings.storeT (else empty): ray parameter where the ray enters the cell, world units
  # along its unit direction.
  tExit @12 :List(Float32);
  # Per visit, only when settings.storeT: ray parameter where it leaves the cell.
  shadowSamples @13 :Column;
  # Version 5: the zero-run coded residuals of the visits of shadow rays (secondarySamples
  # then holds those of reflection and refraction rays only). Empty before version 5 and in
  # version 6.
  referenceRule @14 :UInt8;
  # Version 5: how a ray that is not primary finds its reference ray (see "Column
  # encoding"): 0 the sibling rule, 1 the corresponding rule. The writer codes each batch
  # both ways and keeps the one whose columns have the lower order-0 entropy (the
  # corresponding ray is the nearer at high resolutions, the sibling at low ones). 0 before
  # version 5.
  sampleCode @15 :Data;
  # Versions 6 and 7: the samples of every visit of the batch, in ray and visit order, range coded
  # (see "Samples"); primarySamples, secondarySamples and shadowSamples are then empty.
  # Empty before version 6.
  visitTable @16 :Bool;
  # Version 7: the samples are also predicted from the visit table (see "Samples"); false,
  # they are coded as version 6 codes them. The writer codes each batch both ways (with the
  # reference rule chosen with the table) and keeps the smaller sample code. False before
  # version 7.
  pathCode @17 :Data;
  # Version 8: the new paths of every ray of the batch, in ray order, range coded (see "Paths");
  # primaryPaths and secondaryPaths are then empty. Empty before version 8, and in a version 8
  # batch whose paths are in those columns: the writer keeps the path code where it is smaller
  # than zstd's code (level 3) of the two columns' bytes alone.
}

# Totals of one frame, written after its last batch (and repeated in the index).
struct FrameEnd {
  frame @0 :Int32;
  # Frame number.
  rays @1 :UInt64;
  # Number of rays in the frame.
  visits @2 :UInt64;
  # Number of visits of all its rays.
  samples @3 :UInt64;
  # Sum of the samples of all its visits.
  raysByKind @4 :List(UInt64);
  # Rays per kind, indexed by kind (primary, reflection, refraction, shadow); 4 entries.
  checksum @5 :UInt64;
  # hash64 of the frame's decoded rays (see "Checksums" above).
}

# The index, in the skippable frame at the end of the file. Lets a reader open any frame
# without decoding the others.
struct Index {
  formatVersion @0 :UInt32;
  # Same as Header.formatVersion.
  headerLength @1 :UInt64;
  # Byte length of the header's zstd frame (which starts at offset 0).
  frames @2 :List(IndexEntry);
  # One entry per frame, in file order.
}

struct IndexEntry {
  frame @0 :Int32;
  # Frame number.
  offset @1 :UInt64;
  # Byte offset of the frame's zstd frame from the start of the file.
  length @2 :UInt64;
  # Byte length of that zstd frame (frames are contiguous: offset + length is the next
  # frame's offset, or the index frame's offset for the last one).
  rays @3 :UInt64;
  # As FrameEnd.rays.
  visits @4 :UInt64;
  # As FrameEnd.visits.
  samples @5 :UInt64;
  # As FrameEnd.samples.
  raysByKind @6 :List(UInt64);
  # As FrameEnd.raysByKind.
  checksum @7 :UInt64;
  # As FrameEnd.checksum.
  storedHash @8 :UInt64;
  # hash64 of the frame's zstd frame as stored (its `length` bytes from `offset`; "Checksums"
  # above), so a copy of the frame can be checked without decoding it (`raycell trace
  # concat`). 0: not recorded (files written before it was; a reader then decodes the frame).
}
