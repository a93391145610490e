// Scene loading, scene files' grids (record/scene_file.h) and cell footprints. One of the two
// translation units that include OpenVDB (with renderer.cpp).
#include <openvdb/io/File.h>
#include <openvdb/tools/Composite.h>
#include <openvdb/tools/LevelSetPlatonic.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <openvdb/tools/LevelSetUtil.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/Prune.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <sstream>

#include "base/check.h"
#include "base/parse.h"
#include "record/cell_grid.h"
#include "record/scene_file.h"
#include "record/scene_vdb.h"
#include "record/vec3.h"

namespace raycell {
namespace {

void ApplyMaterial(Scene::Impl& s, const std::string& text, const std::string& source) {
  const auto fields = Split(text, ':');
  const std::string& grid = fields[0];
  const std::string what = "--material '" + text + "'";
  if (fields.size() < 2) throw InputError(what + ": expected GRID:key=value[:key=value...]");
  FogMaterial* fog = nullptr;
  SurfaceMaterial* surface = nullptr;
  for (auto& f : s.fogs)
    if (f.grid->getName() == grid) fog = &f.material;
  for (auto& f : s.surfaces)
    if (f.grid->getName() == grid) surface = &f.material;
  if (!fog && !surface) {
    if (std::find(s.float_grids.begin(), s.float_grids.end(), grid) != s.float_grids.end()) {
      throw InputError(what + ": grid '" + grid + "' is not rendered (choose it with --grid " +
                       grid + ", or --all-grids)");
    }
    throw InputError(what + ": " + source + " has no float grid '" + grid +
                     "' (float grids: " + Join(s.float_grids, ", ") + ")");
  }
  ApplyMaterialFields(fields, what, fog, surface);
}

openvdb::BBoxd WorldBox(const openvdb::FloatGrid& grid, openvdb::Vec3d ilo, openvdb::Vec3d ihi) {
  openvdb::BBoxd box;
  for (int c = 0; c < 8; ++c) {
    const openvdb::Vec3d p((c & 1) ? ihi.x() : ilo.x(), (c & 2) ? ihi.y() : ilo.y(),
                           (c & 4) ? ihi.z() : ilo.z());
    box.expand(grid.indexToWorld(p));
  }
  return box;
}

openvdb::BBoxd PaddedActiveBox(const openvdb::FloatGrid& grid) {
  const openvdb::CoordBBox b = grid.evalActiveVoxelBoundingBox();
  return WorldBox(grid, b.min().asVec3d() - openvdb::Vec3d(1),
                  b.max().asVec3d() + openvdb::Vec3d(1));
}

GridInfo MakeInfo(const openvdb::FloatGrid& grid, const std::string& role,
                  const std::string& source) {
  return GridInfo{grid.getName(), role, source, grid.voxelSize()[0], grid.tree().leafCount()};
}

// NaN or infinite values would poison every sample near them: refuse the grid.
void CheckFinite(const openvdb::FloatGrid& grid, const std::string& source) {
  for (auto it = grid.cbeginValueOn(); it; ++it) {
    if (!std::isfinite(*it)) {
      const openvdb::Coord ijk = it.getCoord();
      throw InputError(source + ": grid '" + grid.getName() + "' holds a non-finite value (" +
                       std::to_string(*it) + ") at voxel " + std::to_string(ijk.x()) + "," +
                       std::to_string(ijk.y()) + "," + std::to_string(ijk.z()));
    }
  }
  if (!std::isfinite(grid.background())) {
    throw InputError(source + ": grid '" + grid.getName() + "' has a non-finite background");
  }
}

// Adds a non-empty grid as a surface (a level set) or fog; false for an empty one.
bool AddGrid(Scene::Impl& s, openvdb::FloatGrid::Ptr grid, const std::string& source) {
  if (grid->empty() || grid->activeVoxelCount() == 0) return false;
  CheckFinite(*grid, source);
  if (!grid->hasUniformVoxels() || !grid->transform().isLinear()) {
    throw InputError(source + ": grid '" + grid->getName() +
                     "' has non-uniform voxels or a non-linear transform; raycell needs "
                     "uniform linear grids");
  }
  if (grid->getGridClass() == openvdb::GRID_LEVEL_SET) {
    s.surfaces.push_back({grid, SurfaceMaterial{}});
    s.infos.push_back(MakeInfo(*grid, "surface", source));
  } else {
    s.fogs.push_back({grid, FogMaterial{}});
    s.infos.push_back(MakeInfo(*grid, "fog", source));
  }
  return true;
}

void InitOpenVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

// The grids to render among a source's float grids `names`: vdb_render's rule by default
// (the first one; all of them where `default_all`), else what spec.grids or spec.all_grids
// say.
std::vector<std::string> ChooseGrids(const std::vector<std::string>& names, const SceneSpec& spec,
                                     const std::string& source, bool default_all) {
  if (spec.all_grids && !spec.grids.empty()) {
    throw InputError("--grid and --all-grids: give one or the other");
  }
  if (spec.all_grids || (spec.grids.empty() && default_all)) return names;
  if (spec.grids.empty()) {
    return names.empty() ? names : std::vector<std::string>{names.front()};
  }
  std::vector<std::string> chosen;
  for (const std::string& g : spec.grids) {
    if (std::find(names.begin(), names.end(), g) == names.end()) {
      throw InputError("--grid '" + g + "': " + source + " has no float grid '" + g +
                       "' (float grids: " + Join(names, ", ") + ")");
    }
    if (std::find(chosen.begin(), chosen.end(), g) == chosen.end()) chosen.push_back(g);
  }
  return chosen;
}

// Reads the chosen float grids of a file. Grids are listed as vdb_render lists them
// (OpenVDB's grid table, ordered by name), so that by default both render the same one.
void LoadFile(Scene::Impl& s, const std::string& path, const SceneSpec& spec) {
  std::vector<std::string> chosen;
  std::string others;
  try {
    openvdb::io::File file(path);
    file.open();
    openvdb::io::File::NameIterator name = file.beginName();
    const openvdb::GridPtrVecPtr metas = file.readAllGridMetadata();
    for (std::size_t i = 0; i < metas->size(); ++i, ++name) {
      const openvdb::GridBase& meta = *(*metas)[i];
      if (meta.isType<openvdb::FloatGrid>()) {
        s.float_grids.push_back(*name);
      } else {
        others += (others.empty() ? "" : ", ") + *name + " (" + meta.valueType() + ")";
      }
    }
    chosen = ChooseGrids(s.float_grids, spec, path, false);
    for (const std::string& g : chosen) {
      AddGrid(s, openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid(g)), path);
    }
    file.close();
  } catch (const openvdb::Exception& e) {
    throw InputError(path + ": cannot read as an OpenVDB file: " + e.what());
  }
  if (s.float_grids.empty()) {
    throw InputError(path + ": no non-empty float grid" +
                     (others.empty() ? std::string() : " (found: " + others + ")") +
                     "; raycell renders float fog volumes and level sets");
  }
  if (s.fogs.empty() && s.surfaces.empty()) {
    throw InputError(path + ": no non-empty float grid: " + Join(chosen, ", ") +
                     " has no active voxels (float grids: " + Join(s.float_grids, ", ") +
                     "; choose with --grid NAME or --all-grids)");
  }
}

// Keeps only the grids of a scene file chosen by spec.grids / spec.all_grids (by default all
// of them, as vdb_render renders every grid of a scene it builds).
void SelectGrids(Scene::Impl& s, const SceneSpec& spec) {
  for (const auto& g : s.infos) s.float_grids.push_back(g.name);
  const auto chosen = ChooseGrids(s.float_grids, spec, spec.source, true);
  auto keep = [&](const auto& layer) {
    return std::find(chosen.begin(), chosen.end(), layer.grid->getName()) != chosen.end();
  };
  auto drop = [&](auto& layers) {
    layers.erase(
        std::remove_if(layers.begin(), layers.end(), [&](const auto& l) { return !keep(l); }),
        layers.end());
  };
  drop(s.fogs);
  drop(s.surfaces);
  s.infos.erase(std::remove_if(s.infos.begin(), s.infos.end(),
                               [&](const GridInfo& g) {
                                 return std::find(chosen.begin(), chosen.end(), g.name) ==
                                        chosen.end();
                               }),
                s.infos.end());
}

int PlatonicFaces(const std::string& type) {
  if (type == "tetrahedron") return 4;
  if (type == "cube") return 6;
  if (type == "octahedron") return 8;
  if (type == "dodecahedron") return 12;
  RAYCELL_CHECK(type == "icosahedron");
  return 20;
}

openvdb::Vec3f ToVec3f(Vec3d v) { return openvdb::Vec3f(float(v.x), float(v.y), float(v.z)); }

// One shape's level set, made by OpenVDB's own tools at the grid's voxel size and band.
openvdb::FloatGrid::Ptr MakeShape(const ShapeDesc& shape, const GridDesc& g) {
  const float vs = float(g.voxel), band = float(g.band);
  if (shape.type == "sphere") {
    return openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
        float(shape.radius), ToVec3f(shape.center), vs, band);
  }
  if (shape.type == "box") {
    // The spheres' and solids' transform: a linear one of the float voxel size.
    const auto xform = openvdb::math::Transform::createLinearTransform(double(vs));
    const openvdb::math::BBox<openvdb::Vec3s> box(ToVec3f(shape.min), ToVec3f(shape.max));
    return openvdb::tools::createLevelSetBox<openvdb::FloatGrid>(box, *xform, band);
  }
  return openvdb::tools::createLevelSetPlatonic<openvdb::FloatGrid>(
      PlatonicFaces(shape.type), float(shape.scale), ToVec3f(shape.center), vs, band);
}

// The shapes joined in order: ((s1 op2 s2) op3 s3) ...
openvdb::FloatGrid::Ptr MakeShapes(const GridDesc& g, int frame) {
  const std::vector<ShapeDesc> shapes = ShapesAtFrame(g, frame);
  openvdb::FloatGrid::Ptr grid = MakeShape(shapes.front(), g);
  for (std::size_t i = 1; i < shapes.size(); ++i) {
    openvdb::FloatGrid::Ptr next = MakeShape(shapes[i], g);
    switch (shapes[i].op) {
      case ShapeDesc::Op::kUnion:
        openvdb::tools::csgUnion(*grid, *next);
        break;
      case ShapeDesc::Op::kDifference:
        openvdb::tools::csgDifference(*grid, *next);
        break;
      case ShapeDesc::Op::kIntersection:
        openvdb::tools::csgIntersection(*grid, *next);
        break;
    }
  }
  return grid;
}

// The float grid `name` of a VDB file (empty: the first float grid, in the order vdb_render
// lists them).
openvdb::FloatGrid::Ptr ReadFileGrid(const std::string& path, const std::string& name,
                                     const std::string& what) {
  try {
    openvdb::io::File file(path);
    file.open();
    openvdb::io::File::NameIterator it = file.beginName();
    const openvdb::GridPtrVecPtr metas = file.readAllGridMetadata();
    std::vector<std::string> floats;
    for (std::size_t i = 0; i < metas->size(); ++i, ++it) {
      if ((*metas)[i]->isType<openvdb::FloatGrid>()) floats.push_back(*it);
    }
    if (floats.empty()) throw InputError(what + ": " + path + " has no float grid");
    const std::string chosen = name.empty() ? floats.front() : name;
    if (std::find(floats.begin(), floats.end(), chosen) == floats.end()) {
      throw InputError(what + ": " + path + " has no float grid '" + chosen +
                       "' (float grids: " + Join(floats, ", ") + ")");
    }
    auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid(chosen));
    file.close();
    return grid;
  } catch (const openvdb::Exception& e) {
    throw InputError(what + ": " + path + ": cannot read as an OpenVDB file: " + e.what());
  }
}

// Multiplies every active voxel's density by the noise factor; voxels it zeroes become
// inactive, and leaves left with none are freed (empty space between the clouds).
void ApplyNoise(openvdb::FloatGrid& grid, const NoiseDesc& noise, const std::string& what) {
  // Noise is per voxel: the active tiles become voxels, so a grid with more active voxels
  // than a made grid may hold (a file's large tiles) is refused before they are made.
  const double voxels = double(grid.activeVoxelCount());
  if (voxels > kMaxGridVoxels) {
    throw InputError(what + ": noise would make its " + std::to_string(grid.activeVoxelCount()) +
                     " active voxels into leaves, beyond the limit of 2^27");
  }
  grid.tree().voxelizeActiveTiles();
  for (auto it = grid.beginValueOn(); it; ++it) {
    const openvdb::Coord c = it.getCoord();
    const double f = NoiseFactor(noise, c.x(), c.y(), c.z());
    if (f == 0) {
      it.setValue(0.0f);
      it.setValueOff();
    } else {
      it.setValue(float(double(*it) * f));
    }
  }
  openvdb::tools::pruneInactive(grid.tree());
}

// Scale, then rotation about the axis, then translation, on top of the grid's own transform;
// the frame's animation added. Nothing is changed when all of it is the identity.
void ApplyTransform(openvdb::FloatGrid& grid, const GridDesc& g, int frame) {
  const Vec3d t = g.translate + g.animate.translate * double(frame);
  const double degrees = g.degrees + g.animate.rotate * double(frame);
  openvdb::math::Transform& xf = grid.transform();
  if (g.scale != 1) xf.postScale(g.scale);
  if (degrees != 0) {
    const Vec3d a = Normalize(g.axis);
    xf.postMult(openvdb::math::rotation<openvdb::Mat4d>(openvdb::Vec3d(a.x, a.y, a.z),
                                                        degrees * 3.14159265358979323846 / 180));
  }
  if (t.x != 0 || t.y != 0 || t.z != 0) xf.postTranslate(openvdb::Vec3d(t.x, t.y, t.z));
}

// The grid `g` of a scene file at frame `frame`, made or read, and added with its material.
void AddSceneGrid(Scene::Impl& s, const SceneDescription& d, const GridDesc& g, int frame) {
  const std::string what = d.name + ": grid '" + g.name + "'";
  openvdb::FloatGrid::Ptr grid;
  if (g.from_file()) {
    const std::string path = FrameFile(g.file, frame);
    grid = ReadFileGrid(path, g.vdb_grid, what);
    if (!g.fog && grid->getGridClass() != openvdb::GRID_LEVEL_SET) {
      throw InputError(what + ": role = \"surface\" needs a level set; " + path + "'s grid '" +
                       grid->getName() + "' is not one (give role = \"fog\")");
    }
    CheckFinite(*grid, path);
  } else {
    try {
      grid = MakeShapes(g, frame);
    } catch (const InputError& e) {
      throw InputError(d.name + ": " + e.what());
    }
  }
  if (g.fog && grid->getGridClass() == openvdb::GRID_LEVEL_SET) {
    // Density ramps up over `ramp` world units inside the surface (0: the interior band).
    g.ramp > 0 ? openvdb::tools::sdfToFogVolume(*grid, float(g.ramp))
               : openvdb::tools::sdfToFogVolume(*grid);
  }
  if (g.noise.on) ApplyNoise(*grid, g.noise, what);
  ApplyTransform(*grid, g, frame);
  grid->setName(g.name);
  if (!AddGrid(s, grid, g.from_file() ? g.file : d.name)) {
    throw InputError(what + " is empty at frame " + std::to_string(frame) +
                     " (no active voxel: shapes that do not meet, or noise above every voxel)");
  }
  if (g.fog) {
    s.fogs.back().material = g.fog_material;
  } else {
    s.surfaces.back().material = g.surface_material;
  }
}

// A scene file's grids, lights and sky at one frame.
void BuildDescription(Scene::Impl& s, const SceneDescription& d, int frame) {
  for (const GridDesc& g : d.grids) AddSceneGrid(s, d, g, frame);
  s.lights = d.lights;
  s.sky_top = d.sky_top;
  s.sky_bottom = d.sky_bottom;
}

void ComputeBox(Scene::Impl& s) {
  openvdb::BBoxd box;
  for (const auto& f : s.fogs) box.expand(PaddedActiveBox(*f.grid));
  for (const auto& f : s.surfaces) box.expand(PaddedActiveBox(*f.grid));
  s.lo = box.min();
  s.hi = box.max();
}

// Calls fn(cell) for every cell of `grid` that the world box b overlaps (closed on both
// sides). The cell of a coordinate is CellGrid::AxisCell's, exact against the grid's planes,
// so a leaf overlaps a coarse cell exactly when it overlaps one of the finer cells it is a
// union of (docs/design.md §1 "Subdivisions").
template <typename Fn>
void ForCellsOverlapping(const openvdb::BBoxd& b, const CellGrid& grid, Fn&& fn) {
  const Vec3d lo = grid.lo(), hi = grid.hi();
  if (b.max().x() < lo.x || b.min().x() > hi.x || b.max().y() < lo.y || b.min().y() > hi.y ||
      b.max().z() < lo.z || b.min().z() > hi.z) {
    return;
  }
  const std::uint32_t x0 = grid.AxisCell(0, b.min().x()), x1 = grid.AxisCell(0, b.max().x());
  const std::uint32_t y0 = grid.AxisCell(1, b.min().y()), y1 = grid.AxisCell(1, b.max().y());
  const std::uint32_t z0 = grid.AxisCell(2, b.min().z()), z1 = grid.AxisCell(2, b.max().z());
  for (std::uint32_t z = z0; z <= z1; ++z)
    for (std::uint32_t y = y0; y <= y1; ++y)
      for (std::uint32_t x = x0; x <= x1; ++x) fn(grid.CellIndex({x, y, z}).value());
}

// Calls fn(bytes, box) for every allocated leaf and active tile of the grid, with its sampling
// region (below).
template <typename Fn>
void ForEachLeaf(const openvdb::FloatGrid& grid, Fn&& fn) {
  const openvdb::Vec3d pad(0.5);
  for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf) {
    const openvdb::Vec3d o = leaf->origin().asVec3d();
    fn(std::uint64_t(leaf->memUsage()),
       WorldBox(grid, o - pad, o + openvdb::Vec3d(leaf->DIM) + pad));
  }
  for (auto it = grid.cbeginValueOn(); it; ++it) {
    if (!it.isTileValue()) continue;
    openvdb::CoordBBox cb;
    it.getBoundingBox(cb);
    fn(std::uint64_t(sizeof(float)),
       WorldBox(grid, cb.min().asVec3d() - pad, cb.max().asVec3d() + openvdb::Vec3d(1) + pad));
  }
}

// Sparse footprint: every allocated leaf (and active tile) whose sampling region overlaps a
// cell costs that cell the leaf's bytes. The region is the node's index box [origin,
// origin + dim], where VolumeRayIntersector's spans put samples, padded by half a voxel
// against rounding.
void AddSparse(const openvdb::FloatGrid& grid, const CellGrid& cells,
               std::vector<std::uint64_t>& fp) {
  ForEachLeaf(grid, [&](std::uint64_t bytes, const openvdb::BBoxd& box) {
    ForCellsOverlapping(box, cells, [&](std::uint32_t c) { fp[c] += bytes; });
  });
}

// Dense footprint: voxels of the grid's active box inside the cell, 4 bytes each.
void AddDense(const openvdb::FloatGrid& grid, const CellGrid& cells,
              std::vector<std::uint64_t>& fp) {
  const openvdb::BBoxd active = PaddedActiveBox(grid);
  const double voxel = grid.voxelSize()[0];
  ForCellsOverlapping(active, cells, [&](std::uint32_t c) {
    const Box3d b = cells.CellBounds(CellId(c));
    const double cl[3] = {b.lo.x, b.lo.y, b.lo.z}, ch[3] = {b.hi.x, b.hi.y, b.hi.z};
    double voxels = 1;
    for (int a = 0; a < 3; ++a) {
      const double ov = std::min(ch[a], active.max()[a]) - std::max(cl[a], active.min()[a]);
      voxels *= std::max(0.0, std::ceil(ov / voxel));
    }
    fp[c] += std::uint64_t(voxels) * sizeof(float);
  });
}

}  // namespace

Scene::Scene(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Scene::~Scene() = default;

std::unique_ptr<Scene> Scene::Load(const SceneSpec& spec, int frame) {
  InitOpenVdb();
  auto s = std::make_unique<Impl>();
  if (spec.description) {
    BuildDescription(*s, *spec.description, frame);
    SelectGrids(*s, spec);
  } else if (IsSceneFile(spec.source)) {
    BuildDescription(*s, LoadSceneDescription(spec.source), frame);
    SelectGrids(*s, spec);
  } else {
    LoadFile(*s, FrameFile(spec.source, frame), spec);
    s->lights.push_back(Light{});
  }
  for (const auto& m : spec.materials) ApplyMaterial(*s, m, spec.source);
  if (!spec.lights.empty()) s->lights = spec.lights;
  for (auto& l : s->lights) {
    ValidateLight(l, "light");
    if (l.type == Light::Type::kDirectional) l.v = Normalize(l.v);
  }
  ComputeBox(*s);
  return std::unique_ptr<Scene>(new Scene(std::move(s)));
}

std::unique_ptr<Scene> Scene::WithMaterials(const std::vector<std::string>& materials,
                                            const std::string& source) const {
  auto s = std::make_unique<Impl>(*impl_);
  for (const auto& m : materials) ApplyMaterial(*s, m, source);
  return std::unique_ptr<Scene>(new Scene(std::move(s)));
}

const std::vector<GridInfo>& Scene::grids() const { return impl_->infos; }
Vec3d Scene::box_lo() const { return {impl_->lo.x(), impl_->lo.y(), impl_->lo.z()}; }
Vec3d Scene::box_hi() const { return {impl_->hi.x(), impl_->hi.y(), impl_->hi.z()}; }
const std::vector<Light>& Scene::lights() const { return impl_->lights; }

Rgb Scene::background(Vec3d d) const {
  const double w = 0.5 * (d.y + 1.0);
  const Rgb& a = impl_->sky_bottom;
  const Rgb& b = impl_->sky_top;
  return {a.r + (b.r - a.r) * w, a.g + (b.g - a.g) * w, a.b + (b.b - a.b) * w};
}

std::vector<std::uint64_t> Scene::Footprints(Vec3d lo, Vec3d hi, std::array<std::uint32_t, 3> dims,
                                             const std::string& mode) const {
  if (mode != "sparse" && mode != "dense") {
    throw InputError("--footprint '" + mode + "': expected sparse or dense");
  }
  const CellGrid cells = CellGrid::Create(lo, hi, dims);
  std::vector<std::uint64_t> fp(cells.cell_count(), 0);
  auto add = [&](const openvdb::FloatGrid& g) {
    mode == "sparse" ? AddSparse(g, cells, fp) : AddDense(g, cells, fp);
  };
  for (const auto& f : impl_->fogs) add(*f.grid);
  for (const auto& f : impl_->surfaces) add(*f.grid);
  return fp;
}

CellLeaves Scene::Leaves(Vec3d lo, Vec3d hi, std::array<std::uint32_t, 3> dims) const {
  const CellGrid cells = CellGrid::Create(lo, hi, dims);
  CellLeaves out;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;  // (cell, leaf)
  auto add = [&](const openvdb::FloatGrid& g) {
    ForEachLeaf(g, [&](std::uint64_t bytes, const openvdb::BBoxd& box) {
      const std::size_t before = pairs.size();
      const auto leaf = std::uint32_t(out.bytes.size());
      ForCellsOverlapping(box, cells, [&](std::uint32_t c) { pairs.emplace_back(c, leaf); });
      if (pairs.size() > before) out.bytes.push_back(bytes);
    });
  };
  for (const auto& f : impl_->fogs) add(*f.grid);
  for (const auto& f : impl_->surfaces) add(*f.grid);
  // Counting sort by cell; leaves stay in increasing order within a cell.
  out.begin.assign(std::size_t{cells.cell_count()} + 1, 0);
  for (const auto& [c, l] : pairs) ++out.begin[c + 1];
  for (std::size_t c = 0; c < cells.cell_count(); ++c) out.begin[c + 1] += out.begin[c];
  out.leaves.resize(pairs.size());
  std::vector<std::uint64_t> next(out.begin.begin(), out.begin.end() - 1);
  for (const auto& [c, l] : pairs) out.leaves[next[c]++] = l;
  return out;
}

}  // namespace raycell
