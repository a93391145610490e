// Scene loading, the built-in scene and cell footprints. One of the two translation units
// that include OpenVDB (with renderer.cpp).
#include <openvdb/io/File.h>
#include <openvdb/tools/Composite.h>
#include <openvdb/tools/LevelSetPlatonic.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <openvdb/tools/LevelSetUtil.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <sstream>

#include "base/check.h"
#include "base/parse.h"
#include "record/cell_grid.h"
#include "record/scene_vdb.h"
#include "record/vec3.h"

namespace raycell {
namespace {

double ParseNumber(const std::string& text, const std::string& what) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || !std::isfinite(v)) {
    throw InputError(what + ": '" + text + "' is not a finite number");
  }
  return v;
}

Vec3d ParseTriple(const std::string& text, const std::string& what) {
  const auto parts = Split(text, ',');
  if (parts.size() != 3) throw InputError(what + ": expected X,Y,Z, got '" + text + "'");
  return {ParseNumber(parts[0], what), ParseNumber(parts[1], what), ParseNumber(parts[2], what)};
}

Rgb ParseRgb(const std::string& text, const std::string& what) {
  // One number means grey.
  if (text.find(',') == std::string::npos) {
    const double v = ParseNumber(text, what);
    return {v, v, v};
  }
  const Vec3d v = ParseTriple(text, what);
  return {v.x, v.y, v.z};
}

void RequireNonNegative(const Rgb& c, const std::string& what) {
  if (c.r < 0 || c.g < 0 || c.b < 0) throw InputError(what + ": must not be negative");
}

void RequireAtMost(const Rgb& c, double limit, const std::string& what, const char* why) {
  if (c.r > limit || c.g > limit || c.b > limit) {
    std::ostringstream s;
    s << what << ": must be at most " << limit << " (" << why << ")";
    throw InputError(s.str());
  }
}

// Light colours are bounded so that radiance fits a float in the single-precision marcher
// (it never exceeds the sum of the lights: surface colours and albedos are at most 1).
constexpr double kMaxLight = 1e30;

double ParseFraction(const std::string& text, const std::string& what) {
  const double v = ParseNumber(text, what);
  if (v < 0 || v > 1) throw InputError(what + ": must be in [0, 1], got " + text);
  return v;
}

void ApplyFogKey(FogMaterial& m, const std::string& key, const std::string& value,
                 const std::string& what) {
  if (key == "absorb") {
    m.absorption = ParseRgb(value, what);
    RequireNonNegative(m.absorption, what);
  } else if (key == "scatter") {
    m.scattering = ParseRgb(value, what);
    RequireNonNegative(m.scattering, what);
  } else if (key == "gain") {
    m.shadow_gain = ParseNumber(value, what);
    if (m.shadow_gain < 0) throw InputError(what + ": must not be negative");
  } else {
    throw InputError(what + ": unknown fog material key (known: absorb, scatter, gain)");
  }
}

void ApplySurfaceKey(SurfaceMaterial& m, const std::string& key, const std::string& value,
                     const std::string& what) {
  if (key == "color") {
    m.color = ParseRgb(value, what);
    RequireNonNegative(m.color, what);
    RequireAtMost(m.color, 1.0, what, "a surface reflects at most the light it gets");
  } else if (key == "reflect") {
    m.reflectivity = ParseFraction(value, what);
  } else if (key == "transparency") {
    m.transparency = ParseFraction(value, what);
  } else if (key == "ior") {
    m.ior = ParseNumber(value, what);
    if (!(m.ior >= 1.0 && m.ior <= 10.0)) throw InputError(what + ": must be in [1, 10]");
  } else {
    throw InputError(what +
                     ": unknown surface material key (known: color, reflect, transparency, ior)");
  }
}

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
  for (std::size_t i = 1; i < fields.size(); ++i) {
    const auto eq = fields[i].find('=');
    if (eq == std::string::npos) throw InputError(what + ": '" + fields[i] + "' is not key=value");
    const std::string key = fields[i].substr(0, eq), value = fields[i].substr(eq + 1);
    const std::string kwhat = what + " key '" + key + "'";
    fog ? ApplyFogKey(*fog, key, value, kwhat) : ApplySurfaceKey(*surface, key, value, kwhat);
  }
  if (surface && surface->reflectivity + surface->transparency > 1.0) {
    throw InputError(what + ": reflect + transparency must not exceed 1");
  }
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

void AddGrid(Scene::Impl& s, openvdb::FloatGrid::Ptr grid, const std::string& source) {
  if (grid->empty() || grid->activeVoxelCount() == 0) return;
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

// Keeps only the chosen grids of the built-in scene.
void SelectBuiltin(Scene::Impl& s, const SceneSpec& spec) {
  for (const auto& g : s.infos) s.float_grids.push_back(g.name);
  const auto chosen = ChooseGrids(s.float_grids, spec, "builtin", true);
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

openvdb::FloatGrid::Ptr Named(openvdb::FloatGrid::Ptr g, const std::string& name) {
  g->setName(name);
  return g;
}

// The built-in scene, made with OpenVDB itself: a fog cloud of three blobs, a mirror sphere
// and a glass icosahedron, lit by one directional light, so that reflection, refraction and
// shadow rays all occur.
void BuildBuiltin(Scene::Impl& s) {
  using openvdb::Vec3f;
  const float vs = 0.025f, band = 3.0f;
  auto cloud =
      openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(0.75f, Vec3f(0, 0, 0), vs, band);
  auto blob2 = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
      0.5f, Vec3f(0.6f, 0.35f, -0.2f), vs, band);
  auto blob3 = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
      0.45f, Vec3f(-0.55f, 0.25f, 0.25f), vs, band);
  openvdb::tools::csgUnion(*cloud, *blob2);
  openvdb::tools::csgUnion(*cloud, *blob3);
  openvdb::tools::sdfToFogVolume(*cloud, 0.45f);  // density ramps up over 0.45 units
  cloud->setName("cloud");
  AddGrid(s, cloud, "builtin");
  s.fogs.back().material = FogMaterial{{0.004, 0.006, 0.008}, {0.03, 0.03, 0.03}, 0.2};

  AddGrid(s,
          Named(openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
                    0.5f, Vec3f(1.35f, -0.35f, 0.45f), vs, band),
                "mirror"),
          "builtin");
  s.surfaces.back().material = SurfaceMaterial{{0.9, 0.9, 0.95}, 0.85, 0.0, 1.5};

  auto glass = openvdb::tools::createLevelSetIcosahedron<openvdb::FloatGrid>(
      0.9f, Vec3f(-1.3f, -0.3f, 0.6f), vs, band);
  AddGrid(s, Named(glass, "glass"), "builtin");
  s.surfaces.back().material = SurfaceMaterial{{0.85, 1.0, 0.9}, 0.05, 0.85, 1.5};

  s.lights.push_back(Light{Light::Type::kDirectional, {0.4, 0.8, 0.45}, {1.0, 0.95, 0.85}});
  s.sky_top = {0.30, 0.42, 0.65};
  s.sky_bottom = {0.06, 0.06, 0.08};
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

void ValidateLight(const Light& l, const std::string& what) {
  if (!IsFinite(l.v)) throw InputError(what + ": position or direction must be finite");
  if (!(std::isfinite(l.color.r) && std::isfinite(l.color.g) && std::isfinite(l.color.b))) {
    throw InputError(what + ": colour must be finite");
  }
  RequireNonNegative(l.color, what);
  RequireAtMost(l.color, kMaxLight, what, "radiance must fit a float");
  if (l.type == Light::Type::kDirectional && !(Length(l.v) > 0)) {
    throw InputError(what + ": direction must not be zero");
  }
}

Light ParseLight(const std::string& text) {
  const auto f = Split(text, ':');
  const std::string what = "--light '" + text + "'";
  if (f.size() < 2 || f.size() > 3 || (f[0] != "dir" && f[0] != "point")) {
    throw InputError(what + ": expected dir:X,Y,Z[:R,G,B] or point:X,Y,Z[:R,G,B]");
  }
  Light l;
  l.type = f[0] == "dir" ? Light::Type::kDirectional : Light::Type::kPoint;
  l.v = ParseTriple(f[1], what);
  if (f.size() == 3) {
    l.color = ParseRgb(f[2], what);
  }
  ValidateLight(l, what);
  return l;
}

bool IsSequencePattern(const std::string& source) { return source.find('%') != std::string::npos; }

std::string FrameFile(const std::string& source, int frame) {
  if (!IsSequencePattern(source)) return source;
  char buf[4096];
  const int n = std::snprintf(buf, sizeof buf, source.c_str(), frame);
  if (n < 0 || n >= int(sizeof buf)) throw InputError("--scene '" + source + "': bad pattern");
  return buf;
}

Scene::Scene(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Scene::~Scene() = default;

std::unique_ptr<Scene> Scene::Load(const SceneSpec& spec, int frame) {
  InitOpenVdb();
  auto s = std::make_unique<Impl>();
  if (spec.source == "builtin") {
    BuildBuiltin(*s);
    SelectBuiltin(*s, spec);
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
