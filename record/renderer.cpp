// The recording renderer. One of the two translation units that include OpenVDB (with
// scene.cpp).
//
// Every ray is first cut into its visits: the non-empty cells its chord through the scene
// box crosses (CellDDA). A ray that meets no non-empty cell is not traced; the others are
// searched over their whole chord through the box, whatever the cells (see Path), and
// empty space costs nothing (VolumeRayIntersector skips to allocated leaves, which lie in
// non-empty cells). Each volume sample is counted in the visit holding it. A ray's visits end where
// it ends: early termination, a surface hit, or the box exit.
//
// Fog volumes are integrated front to back exactly as OpenVDB's vdb_render does (same step
// positions, transmittance, cutoff and shadow-ray gain), every lit sample casting one shadow
// ray per light. Level sets are surfaces: sphere-traced within their narrow band, refined by
// bisection, and shaded with diffuse light (shadow rays), mirror reflection and Snell
// refraction with total internal reflection, up to the maximum depth.
#include "record/renderer.h"

#include <openvdb/math/Ray.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/RayIntersector.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>

#include "base/check.h"
#include "base/parallel.h"
#include "record/camera.h"
#include "record/scene_vdb.h"

namespace raycell {
namespace {

using RayT = openvdb::math::Ray<double>;
using TimeSpan = RayT::TimeSpan;
using Intersector = openvdb::tools::VolumeRayIntersector<openvdb::FloatGrid>;
using Accessor = openvdb::FloatGrid::ConstAccessor;
using Sampler = openvdb::tools::BoxSampler;

constexpr double kAmbient = 0.04;     // surfaces' unshadowed ambient term
constexpr int kBisections = 6;        // refinement of a level-set crossing
constexpr double kSpawnOffset = 0.5;  // in voxels: spawned rays start off the surface

// The marcher computes in Real (float or double, RenderSettings::single_precision): ray
// origins and directions, sample positions, optical depths, transmittance and radiance.
// Geometry it does not own stays in double: the camera, the cell DDA, OpenVDB's intersector
// (whose spans are rounded to Real) and the trilinear sampler (whose Real position widens
// exactly).
template <class Real>
using Vec = openvdb::math::Vec3<Real>;

template <class Real>
Vec<Real> FromVec(const Vec3d& v) {
  return {Real(v.x), Real(v.y), Real(v.z)};
}
template <class Real>
Vec<Real> FromRgb(const Rgb& c) {
  return {Real(c.r), Real(c.g), Real(c.b)};
}
template <class Real>
Vec3d ToVec(const Vec<Real>& v) {
  return {double(v.x()), double(v.y()), double(v.z())};
}
template <class Real>
openvdb::Vec3d ToVdb(const Vec<Real>& v) {
  return {double(v.x()), double(v.y()), double(v.z())};
}
// Grey media (equal coefficients in every channel, the default) need one exp, not three.
template <class Real>
Vec<Real> ExpOf(const Vec<Real>& v) {
  if (v.x() == v.y() && v.y() == v.z()) return Vec<Real>(std::exp(v.x()));
  return {std::exp(v.x()), std::exp(v.y()), std::exp(v.z())};
}

// The visits of one ray while it is traced: the non-empty cells of its chord, with samples.
// Work is searched for over the whole chord through the scene box, [chord_lo, chord_hi],
// which no cell grid changes (OpenVDB's intersectors skip the empty space, so the empty
// cells cost nothing): the samples are then the same whatever the cells, and a capture
// regrouped from a finer grid agrees with one recorded on the coarse cells. A sample or spawn
// in a gap between the visits (an empty cell, where only a sample at the
// edge of a leaf's region can fall) goes to the visit before it. A regroupable capture
// (`all`) also keeps the empty cells of the chord, and gives such a sample or spawn the empty
// cell holding it: regrouping applies the same rule in the cells it makes
// (traces/regroup.h), so a capture on those cells is reproduced.
class Path {
 public:
  void Build(const CellGrid& grid, const std::vector<bool>& nonempty, bool all, const Vec3d& o,
             const Vec3d& d, double tmax, std::optional<CellId> start) {
    cells_.clear(), t0_.clear(), t1_.clear(), samples_.clear();
    cursor_ = 0;
    all_ = all;
    any_full_ = false;
    CellDDA dda(grid, o, d, 0.0, tmax, start);
    bool first_segment = true;
    for (CellSegment s; dda.Next(&s);) {
      if (first_segment) chord_lo_ = s.t0, first_segment = false;
      chord_hi_ = s.t1;
      const bool full = nonempty[s.cell.value()];
      if (!full && !all) continue;
      any_full_ |= full;
      cells_.push_back(s.cell), t0_.push_back(s.t0), t1_.push_back(s.t1);
      samples_.push_back(0);
    }
  }
  bool empty() const { return !any_full_; }  // no non-empty cell: nothing to trace
  std::size_t size() const { return cells_.size(); }
  // Where the ray enters the scene box (or starts) and leaves it (or ends); only when
  // !empty().
  double chord_lo() const { return chord_lo_; }
  double chord_hi() const { return chord_hi_; }
  CellId cell(std::size_t i) const { return cells_[i]; }
  // Index of the visit holding t (t inside [t_lo, t_hi]; a t in a gap between visits goes to
  // the visit before it).
  std::uint32_t VisitAt(double t) const {
    auto it = std::upper_bound(t0_.begin(), t0_.end(), t);
    return it == t0_.begin() ? 0 : std::uint32_t(it - t0_.begin() - 1);
  }
  // Counts a sample at t; t must not decrease between calls.
  std::uint32_t AddSampleInOrder(double t) {
    while (cursor_ + 1 < t0_.size() && t >= t0_[cursor_ + 1]) ++cursor_;
    ++samples_[cursor_];
    return std::uint32_t(cursor_);
  }
  void AddSamples(double t, std::uint32_t n) { samples_[VisitAt(t)] += n; }
  // The ray ends at t_end: later visits are dropped, the last one ends at t_end. A ray that
  // ran past its last non-empty cell (`ran_out`) keeps, in a regroupable capture, the empty
  // cells after it up to the box exit.
  void Truncate(double t_end, bool ran_out) {
    if (all_ && ran_out) return;
    const std::size_t keep = VisitAt(t_end) + 1;
    cells_.resize(keep), t0_.resize(keep), t1_.resize(keep), samples_.resize(keep);
    t1_.back() = std::max(t0_.back(), std::min(t1_.back(), t_end));
  }
  double t0(std::size_t i) const { return t0_[i]; }
  double t1(std::size_t i) const { return t1_[i]; }
  std::uint32_t samples(std::size_t i) const { return samples_[i]; }

 private:
  std::vector<CellId> cells_;
  std::vector<double> t0_, t1_;
  std::vector<std::uint32_t> samples_;
  std::size_t cursor_ = 0;
  bool any_full_ = false;  // a non-empty cell among the visits
  double chord_lo_ = 0, chord_hi_ = 0;
  bool all_ = false;
};

// The rays of one pixel in the order they are started (parents before children), each with
// its visits, until they are flushed into the row's batch.
class PixelRecord {
 public:
  int Open(RayKind kind, int parent, std::uint32_t spawn) {
    rays_.push_back({kind, parent, spawn, 0, 0});
    return int(rays_.size()) - 1;
  }
  void Close(int slot, const Path& p) {
    Pending& r = rays_[slot];
    r.begin = std::uint32_t(pool_.size());
    for (std::size_t i = 0; i < p.size(); ++i) {
      pool_.push_back({p.cell(i), p.samples(i), float(p.t0(i)), float(p.t1(i))});
    }
    r.end = std::uint32_t(pool_.size());
  }
  RayKind kind(int slot) const { return rays_[slot].kind; }
  // Forgets the last opened ray (a primary ray that met no non-empty cell).
  void DropLast() { rays_.pop_back(); }
  void FlushTo(RayBatch& out, std::uint32_t px, std::uint32_t py) {
    const RayId base = out.size();
    for (const Pending& r : rays_) {
      out.BeginRay(r.kind, r.parent < 0 ? kNoParent : base + RayId(r.parent), r.spawn, px, py);
      for (std::uint32_t v = r.begin; v < r.end; ++v) {
        out.AddVisit(pool_[v].cell, pool_[v].samples, pool_[v].t0, pool_[v].t1);
      }
    }
    rays_.clear();
    pool_.clear();
  }

 private:
  struct Pending {
    RayKind kind;
    int parent;
    std::uint32_t spawn, begin, end;
  };
  struct PendingVisit {
    CellId cell;
    std::uint32_t samples;
    float t0, t1;
  };
  std::vector<Pending> rays_;
  std::vector<PendingVisit> pool_;
};

// One grid as a thread sees it: its own intersector (shallow copy) and accessor.
template <class Real>
struct GridCtx {
  using V3 = Vec<Real>;
  GridCtx(const Intersector& master, const openvdb::FloatGrid& g)
      : grid(&g),
        inter(master),
        acc(g.getConstAccessor()),
        vs(Real(g.voxelSize()[0])),
        inv_vs(Real(1) / vs) {}
  const openvdb::FloatGrid* grid;
  Intersector inter;
  Accessor acc;
  Real vs, inv_vs;
  // A world ray in this grid's index space: the position at world t is eye + dir * t.
  struct IndexRay {
    V3 eye, dir;
  };
  IndexRay ToIndex(const V3& o, const V3& d) const {
    const V3 eye(grid->worldToIndex(ToVdb(o)));
    return {eye, V3(grid->worldToIndex(ToVdb<Real>(o + d))) - eye};
  }
  float Sample(const IndexRay& r, Real t) {
    return Sampler::sample(acc, ToVdb<Real>(r.eye + r.dir * t));
  }
  float SampleAt(const V3& world) { return Sampler::sample(acc, grid->worldToIndex(ToVdb(world))); }
  // World-t spans of active leaves along the current ray within [ta, tb].
  void Spans(const V3& o, const V3& d, double ta, double tb, std::vector<TimeSpan>* out) {
    out->clear();
    if (!inter.setWorldRay(RayT(ToVdb(o), ToVdb(d), ta, tb))) return;
    inter.hits(*out);
    for (auto& s : *out) s.t0 *= vs, s.t1 *= vs;  // index t -> world t (uniform scale)
  }
};

template <class Real>
struct Hit {
  Real t = 0;
  int surface = -1;
};

// Everything a thread needs; scratch is kept per ray depth so that a parent's state
// survives while its children are traced.
template <class Real>
struct ThreadCtx {
  std::vector<GridCtx<Real>> fogs, surfaces;
  std::vector<Path> paths;
  std::vector<std::vector<TimeSpan>> spans, merged;
  std::vector<std::vector<Real>> surface_samples;
  std::vector<Real> densities;  // [fog grid]: the last FogAt's
  std::vector<std::vector<typename GridCtx<Real>::IndexRay>> fog_rays;  // [depth][fog grid]
  PixelRecord rec;
  std::uint32_t px = 0, py = 0;  // the pixel being traced (for the sample probe)
};

template <class Real>
class FrameTracer {
 public:
  using V3 = Vec<Real>;
  using Ctx = ThreadCtx<Real>;

  explicit FrameTracer(const RenderJob& job)
      : job_(job), s_(job.scene->impl()), set_(job.settings) {
    // One bit per cell: at 256^3 cells the DDA's lookups stay in cache (2 MiB, where the
    // footprints are 128 MiB).
    nonempty_.reserve(job.footprints->size());
    for (std::uint64_t f : *job.footprints) nonempty_.push_back(f != 0);
    // Reserved first: a copied intersector is shallow, only the master owns its tree.
    fog_masters_.reserve(s_.fogs.size());
    surface_masters_.reserve(s_.surfaces.size());
    for (const auto& f : s_.fogs) fog_masters_.emplace_back(*f.grid);
    for (const auto& f : s_.surfaces) surface_masters_.emplace_back(*f.grid);
    double min_vs = 0;
    for (const auto& f : s_.fogs) {
      const double vs = f.grid->voxelSize()[0];
      min_vs = min_vs == 0 ? vs : std::min(min_vs, vs);
    }
    primary_step_ = Real(set_.primary_step * min_vs);
    shadow_step_ = Real(set_.shadow_step * min_vs);
    cutoff_ = Real(set_.cutoff);
    for (const auto& f : s_.fogs) {
      const V3 sc = FromRgb<Real>(f.material.scattering);
      const V3 ext = FromRgb<Real>(f.material.absorption) + sc;
      fog_mats_.push_back({ext, sc, Ratio(sc, ext), Real(f.material.shadow_gain)});
    }
    for (const auto& f : s_.surfaces) {
      const SurfaceMaterial& m = f.material;
      surface_mats_.push_back(
          {FromRgb<Real>(m.color), Real(m.reflectivity), Real(m.transparency), Real(m.ior)});
    }
    for (const Light& l : s_.lights) {
      lights_.push_back(
          {l.type == Light::Type::kPoint, FromVec<Real>(l.v), FromRgb<Real>(l.color)});
    }
  }

  Ctx MakeContext() const {
    Ctx c;
    for (std::size_t i = 0; i < s_.fogs.size(); ++i)
      c.fogs.emplace_back(fog_masters_[i], *s_.fogs[i].grid);
    for (std::size_t i = 0; i < s_.surfaces.size(); ++i)
      c.surfaces.emplace_back(surface_masters_[i], *s_.surfaces[i].grid);
    const std::size_t levels = set_.max_depth + 2;
    c.paths.resize(levels);
    c.spans.resize(levels);
    c.merged.resize(levels);
    c.surface_samples.resize(levels);
    c.densities.assign(c.fogs.size(), Real(0));
    c.fog_rays.assign(levels, std::vector<typename GridCtx<Real>::IndexRay>(c.fogs.size()));
    return c;
  }

  // Traces all rays of row y into `out` (ids relative to the row) and the image row.
  std::uint64_t RenderRow(Ctx& c, std::uint32_t y, RayBatch& out, Image& img) const {
    const PinholeCamera cam = PinholeCamera::Create(job_.camera, set_.width, set_.height);
    std::uint64_t missed = 0;
    c.py = y;
    for (std::uint32_t x = 0; x < set_.width; ++x) {
      c.px = x;
      V3 sum(Real(0));
      for (std::uint32_t s = 0; s < set_.spp; ++s) {
        const auto [jx, jy] = Jitter(x, y, s);
        const V3 o = FromVec<Real>(cam.eye()), d = FromVec<Real>(cam.Direction(x + jx, y + jy));
        sum += Trace(c, o, d, RayKind::kPrimary, -1, 0, 0, std::nullopt, &missed);
      }
      c.rec.FlushTo(out, x, y);
      sum *= Real(1) / Real(set_.spp);
      RAYCELL_CHECK(std::isfinite(sum.x()) && std::isfinite(sum.y()) && std::isfinite(sum.z()));
      img.at(x, y) = {double(sum.x()), double(sum.y()), double(sum.z())};
    }
    return missed;
  }

 private:
  struct FogCoeffs {
    V3 extinction, scattering;  // per voxel of the grid, per unit density
    V3 albedo;                  // scattering / extinction (0 where extinction is 0)
    Real shadow_gain;
  };
  struct SurfaceCoeffs {
    V3 color;
    Real reflectivity, transparency, ior;
  };
  struct LightR {
    bool point;
    V3 v, color;
  };

  std::pair<double, double> Jitter(std::uint32_t x, std::uint32_t y, std::uint32_t s) const {
    if (set_.spp == 1) return {0.5, 0.5};
    auto hash = [](std::uint64_t v) {
      v ^= v >> 33, v *= 0xff51afd7ed558ccdULL, v ^= v >> 33, v *= 0xc4ceb9fe1a85ec53ULL;
      return double((v ^ (v >> 33)) >> 11) * 0x1.0p-53;
    };
    const std::uint64_t key = (std::uint64_t(y) << 40) ^ (std::uint64_t(x) << 16) ^ s;
    return {hash(2 * key), hash(2 * key + 1)};
  }

  // Marches a primary, reflected or refracted ray; returns its radiance.
  V3 Trace(Ctx& c, const V3& o, const V3& d, RayKind kind, int parent, std::uint32_t spawn,
           std::uint32_t depth, std::optional<CellId> start, std::uint64_t* missed) const {
    const int slot = c.rec.Open(kind, parent, spawn);
    Path& path = c.paths[depth];
    path.Build(*job_.cells, nonempty_, job_.all_cells, ToVec(o), ToVec(d), CellDDA::kInfinity,
               start);
    if (path.empty()) {       // only a primary ray can miss every non-empty cell
      if (path.size() > 0) {  // a regroupable capture keeps it: it crosses empty cells
        c.rec.Close(slot, path);
      } else {
        c.rec.DropLast();
        if (missed) ++*missed;
      }
      return BackgroundOf(d);
    }
    const std::optional<Hit<Real>> hit =
        FindSurface(c, depth, o, d, path.chord_lo(), path.chord_hi());
    const double t_fog_end = hit ? double(hit->t) : path.chord_hi();
    V3 lumi(Real(0)), trans(Real(1));
    std::optional<Real> t_term =
        MarchFog(c, slot, depth, o, d, path.chord_lo(), t_fog_end, &lumi, &trans);
    if (!t_term) {
      lumi += trans * (hit ? Shade(c, slot, depth, o, d, *hit) : BackgroundOf(d));
    }
    Finish(c, slot, depth, t_term ? double(*t_term) : t_fog_end, !t_term && !hit);
    return lumi;
  }

  // Attributes the surface search's samples up to t_end, cuts the path there, records it.
  void Finish(Ctx& c, int slot, std::uint32_t depth, double t_end, bool ran_out) const {
    Path& path = c.paths[depth];
    for (Real t : c.surface_samples[depth]) {
      if (t <= t_end) path.AddSamples(t, 1);
    }
    path.Truncate(t_end, ran_out);
    c.rec.Close(slot, path);
  }

  V3 BackgroundOf(const V3& d) const { return FromRgb<Real>(job_.scene->background(ToVec(d))); }

  // Spans of active fog along the ray within [ta, tb], merged over fog grids, in world t.
  const std::vector<TimeSpan>& FogSpans(Ctx& c, std::uint32_t depth, const V3& o, const V3& d,
                                        double ta, double tb) const {
    auto& merged = c.merged[depth];
    merged.clear();
    for (std::size_t i = 0; i < c.fogs.size(); ++i) {
      GridCtx<Real>& g = c.fogs[i];
      c.fog_rays[depth][i] = g.ToIndex(o, d);
      g.Spans(o, d, ta, tb, &c.spans[depth]);
      merged.insert(merged.end(), c.spans[depth].begin(), c.spans[depth].end());
    }
    if (c.fogs.size() > 1) MergeSpans(merged);
    return merged;
  }

  static void MergeSpans(std::vector<TimeSpan>& s) {
    std::sort(s.begin(), s.end(), [](const TimeSpan& a, const TimeSpan& b) { return a.t0 < b.t0; });
    std::size_t n = 0;
    for (const TimeSpan& span : s) {
      if (n > 0 && span.t0 <= s[n - 1].t1) {
        s[n - 1].t1 = std::max(s[n - 1].t1, span.t1);
      } else {
        s[n++] = span;
      }
    }
    s.resize(n);
  }

  void Probe(const Ctx& c, RayKind kind, int slot, std::uint32_t depth, Real t, const V3& tau,
             const V3& trans) const {
    if (!job_.sample_probe) return;
    job_.sample_probe(MarchSample{c.px,
                                  c.py,
                                  std::uint32_t(slot),
                                  kind,
                                  depth,
                                  double(t),
                                  {double(tau.x()), double(tau.y()), double(tau.z())},
                                  {double(trans.x()), double(trans.y()), double(trans.z())}});
  }

  // a / b per channel: 0 where b is 0 or not finite, so finite whatever the coefficients.
  static V3 Ratio(const V3& a, const V3& b) {
    V3 r(Real(0));
    for (int ch = 0; ch < 3; ++ch) {
      if (b[ch] > 0 && std::isfinite(b[ch])) r[ch] = a[ch] / b[ch];
    }
    return r;
  }

  // One fog sample: the densities of every grid at world t, the optical depth of one step of
  // `step` world units (coefficients are per voxel of each grid, as in vdb_render) and the
  // largest density. Densities below 0 (or NaN) count as 0, so depth is never negative and
  // transmittance never grows along a ray; an infinite depth is fine (the step is opaque).
  struct FogSample {
    Real max_density = 0;
    V3 tau{Real(0)}, extinction{Real(0)};  // extinction: density-weighted, per world unit
  };
  FogSample FogAt(Ctx& c, std::uint32_t depth, Real t, Real step) const {
    FogSample s;
    for (std::size_t i = 0; i < c.fogs.size(); ++i) {
      const Real dens = Density(c.fogs[i].Sample(c.fog_rays[depth][i], t));
      c.densities[i] = dens;
      if (dens == 0) continue;  // adds nothing (and 0 * an overflowed coefficient is NaN)
      s.max_density = std::max(s.max_density, dens);
      s.extinction += fog_mats_[i].extinction * (dens * c.fogs[i].inv_vs);
    }
    s.tau = s.extinction * step;
    return s;
  }

  // The single-scattering albedo of the sample FogAt took last: the material's own with one
  // fog grid (as vdb_render), else the ratio of the density-weighted coefficients.
  V3 AlbedoOf(const Ctx& c, const FogSample& s) const {
    if (c.fogs.size() == 1) return fog_mats_[0].albedo;
    V3 scattering(Real(0));
    for (std::size_t i = 0; i < c.fogs.size(); ++i) {
      if (c.densities[i] != 0)
        scattering += fog_mats_[i].scattering * (c.densities[i] * c.fogs[i].inv_vs);
    }
    return Ratio(scattering, s.extinction);
  }

  // The first of vdb_render's step positions k * step at or after t, with k >= 1: a ray
  // never samples its own origin, since vdb_render's rays start just after it (a shadow ray
  // at t0 = math::Delta, a camera ray at the near plane). Shadow rays sampling their origin,
  // the lit sample itself, shadowed every sample by its own density: linear images were 29%
  // (mj_smoke) and 63% (the fluid cache's density) darker than vdb_render's. k is an integer
  // so that the march ends even where t is too large for Real to tell k from k + 1 (a
  // distant camera in single precision): the positions then repeat, the count of steps stays
  // right.
  static std::int64_t FirstStep(Real t, Real step) {
    const Real k = std::max(Real(1), std::ceil(t / step));
    RAYCELL_CHECK(k < Real(0x1p62));  // more steps than any run could take
    return std::int64_t(k);
  }

  static Real Density(float sampled) { return sampled > 0 ? Real(sampled) : Real(0); }

  // Front-to-back fog integration over [ta, tb]; every lit sample casts shadow rays.
  // Returns the parameter of early termination, if it happened.
  std::optional<Real> MarchFog(Ctx& c, int slot, std::uint32_t depth, const V3& o, const V3& d,
                               double ta, double tb, V3* lumi, V3* trans) const {
    if (c.fogs.empty()) return std::nullopt;
    const Real step = primary_step_;
    const RayKind kind = c.rec.kind(slot);
    for (const TimeSpan& span : FogSpans(c, depth, o, d, ta, tb)) {
      const Real t1 = Real(span.t1);
      for (std::int64_t k = FirstStep(Real(span.t0), step); Real(k) * step <= t1; ++k) {
        const Real t = Real(k) * step;
        const std::uint32_t visit = c.paths[depth].AddSampleInOrder(t);
        const FogSample fog = FogAt(c, depth, t, step);
        if (fog.max_density < cutoff_ || fog.max_density == 0) continue;
        const V3& tau = fog.tau;
        const V3 albedo = AlbedoOf(c, fog);
        const V3 dT = ExpOf(-tau);
        const V3 pos = o + d * t;
        const CellId cell = c.paths[depth].cell(visit);
        for (const LightR& l : lights_) {
          const V3 s_trans = TraceShadow(c, slot, visit, depth + 1, pos, l, cell);
          *lumi += albedo * l.color * s_trans * *trans * (V3(Real(1)) - dT);
        }
        *trans *= dT;
        Probe(c, kind, slot, depth, t, tau, *trans);
        if (trans->lengthSqr() < cutoff_) return t;
      }
    }
    return std::nullopt;
  }

  // A shadow ray from pos towards light l: its transmittance through fog and surfaces.
  V3 TraceShadow(Ctx& c, int parent, std::uint32_t spawn, std::uint32_t depth, const V3& pos,
                 const LightR& l, CellId start) const {
    V3 dir = l.v;
    double tmax = CellDDA::kInfinity;
    if (l.point) {
      dir -= pos;
      const Real len = dir.length();
      if (!(len > 0)) return V3(Real(1));
      dir /= len;
      tmax = len;
    }
    const int slot = c.rec.Open(RayKind::kShadow, parent, spawn);
    Path& path = c.paths[depth];
    path.Build(*job_.cells, nonempty_, job_.all_cells, ToVec(pos), ToVec(dir), tmax, start);
    const std::optional<Hit<Real>> hit =
        FindSurface(c, depth, pos, dir, path.chord_lo(), path.chord_hi());
    const double t_stop = hit ? double(hit->t) : path.chord_hi();
    V3 trans(Real(1));
    std::optional<Real> t_term =
        Attenuate(c, slot, depth, pos, dir, path.chord_lo(), t_stop, &trans);
    if (hit && !t_term) trans *= surface_mats_[hit->surface].transparency;
    Finish(c, slot, depth, t_term ? double(*t_term) : t_stop, !t_term && !hit);
    return trans;
  }

  // Shadow-ray transmittance through fog over [ta, tb], vdb_render's rule with gain.
  std::optional<Real> Attenuate(Ctx& c, int slot, std::uint32_t depth, const V3& o, const V3& d,
                                double ta, double tb, V3* trans) const {
    if (c.fogs.empty()) return std::nullopt;
    const Real step = shadow_step_;
    for (const TimeSpan& span : FogSpans(c, depth, o, d, ta, tb)) {
      const Real t1 = Real(span.t1);
      for (std::int64_t k = FirstStep(Real(span.t0), step); Real(k) * step <= t1; ++k) {
        const Real t = Real(k) * step;
        c.paths[depth].AddSampleInOrder(t);
        V3 tau(Real(0));
        Real max_density = 0;
        for (std::size_t i = 0; i < c.fogs.size(); ++i) {
          const Real dens = Density(c.fogs[i].Sample(c.fog_rays[depth][i], t));
          if (dens == 0) continue;  // as in FogAt
          max_density = std::max(max_density, dens);
          const FogCoeffs& m = fog_mats_[i];
          const Real voxel_t = t * c.fogs[i].inv_vs;
          tau +=
              m.extinction * (dens * step * c.fogs[i].inv_vs / (Real(1) + voxel_t * m.shadow_gain));
        }
        if (max_density < cutoff_) continue;
        *trans *= ExpOf(-tau);
        Probe(c, RayKind::kShadow, slot, depth, t, tau, *trans);
        if (trans->lengthSqr() < cutoff_) return t;
      }
    }
    return std::nullopt;
  }

  // The nearest level-set crossing along the ray in [ta, tb]. Every level-set evaluation's t
  // is kept in surface_samples[depth] so that it can be counted where the ray really goes.
  std::optional<Hit<Real>> FindSurface(Ctx& c, std::uint32_t depth, const V3& o, const V3& d,
                                       double ta, double tb) const {
    auto& samples = c.surface_samples[depth];
    samples.clear();
    std::optional<Hit<Real>> best;
    for (std::size_t i = 0; i < c.surfaces.size(); ++i) {
      const double limit = best ? double(best->t) : tb;
      if (auto t = Crossing(c.surfaces[i], c.spans[depth], samples, o, d, ta, limit)) {
        best = Hit<Real>{*t, int(i)};
      }
    }
    return best;
  }

  static std::optional<Real> Crossing(GridCtx<Real>& g, std::vector<TimeSpan>& spans,
                                      std::vector<Real>& samples, const V3& o, const V3& d,
                                      double ta, double tb) {
    const typename GridCtx<Real>::IndexRay ray = g.ToIndex(o, d);
    g.Spans(o, d, ta, tb, &spans);
    bool have_prev = false, inside = false;
    Real prev_t = 0;
    for (const TimeSpan& span : spans) {
      const Real t1 = Real(span.t1);
      for (Real t = Real(span.t0);;) {
        const Real phi = g.Sample(ray, t);
        samples.push_back(t);
        const bool in = phi < 0;
        if (have_prev && in != inside) return Refine(g, ray, samples, prev_t, t, inside);
        have_prev = true, inside = in, prev_t = t;
        if (t >= t1 || t > tb) break;
        const Real next = std::min(t1, t + std::max(Real(0.9) * std::abs(phi), Real(0.25) * g.vs));
        // Where the step is below t's resolution (a distant camera in single precision), the
        // next representable t: the search still moves on.
        t = next > t ? next : std::nextafter(t, t1);
      }
    }
    return std::nullopt;
  }

  // Bisection of a sign change of the level set between a (side `inside_a`) and b.
  static Real Refine(GridCtx<Real>& g, const typename GridCtx<Real>::IndexRay& ray,
                     std::vector<Real>& samples, Real a, Real b, bool inside_a) {
    for (int i = 0; i < kBisections; ++i) {
      const Real m = Real(0.5) * (a + b);
      samples.push_back(m);
      ((g.Sample(ray, m) < 0) == inside_a ? a : b) = m;
    }
    return Real(0.5) * (a + b);
  }

  V3 Normal(GridCtx<Real>& g, const V3& p) const {
    const Real h = Real(0.5) * g.vs;
    V3 n(g.SampleAt(p + V3(h, 0, 0)) - g.SampleAt(p - V3(h, 0, 0)),
         g.SampleAt(p + V3(0, h, 0)) - g.SampleAt(p - V3(0, h, 0)),
         g.SampleAt(p + V3(0, 0, h)) - g.SampleAt(p - V3(0, 0, h)));
    const Real len = n.length();
    return len > 0 ? n / len : V3(0, 1, 0);
  }

  // Radiance leaving a surface hit towards -d: diffuse light through shadow rays, mirror
  // reflection and refraction, each spawned in the hit's cell.
  V3 Shade(Ctx& c, int slot, std::uint32_t depth, const V3& o, const V3& d,
           const Hit<Real>& hit) const {
    GridCtx<Real>& g = c.surfaces[hit.surface];
    const SurfaceCoeffs& m = surface_mats_[hit.surface];
    const V3 p = o + d * hit.t;
    Path& path = c.paths[depth];
    path.AddSamples(hit.t, 6);  // the normal's central differences
    const std::uint32_t visit = path.VisitAt(hit.t);
    const CellId cell = path.cell(visit);
    const V3 n = Normal(g, p);
    const bool entering = d.dot(n) < 0;
    const V3 nf = entering ? n : -n;  // faces the incoming ray
    const Real offset = Real(kSpawnOffset) * g.vs;
    const V3 p_out = p + nf * offset, p_in = p - nf * offset;
    V3 out(Real(0));
    const Real diffuse = Real(1) - m.reflectivity - m.transparency;
    if (diffuse > 0) {
      out += m.color * (diffuse * Real(kAmbient));
      for (const LightR& l : lights_) {
        const V3 ldir = l.point ? (l.v - p).unit() : l.v;
        const Real ndl = nf.dot(ldir);
        if (ndl <= 0) continue;
        const V3 tr = TraceShadow(c, slot, visit, depth + 1, p_out, l, cell);
        out += m.color * l.color * tr * (diffuse * ndl);
      }
    }
    if (depth >= set_.max_depth) return out;
    const V3 r = d - nf * (Real(2) * d.dot(nf));
    if (m.reflectivity > 0) {
      out += m.color * m.reflectivity *
             Trace(c, p_out, r.unit(), RayKind::kReflection, slot, visit, depth + 1, cell, nullptr);
    }
    if (m.transparency > 0) {
      const Real eta = entering ? Real(1) / m.ior : m.ior;
      const Real cosi = -d.dot(nf);
      const Real k = Real(1) - eta * eta * (Real(1) - cosi * cosi);
      if (k < 0) {  // total internal reflection
        out +=
            m.color * m.transparency *
            Trace(c, p_out, r.unit(), RayKind::kReflection, slot, visit, depth + 1, cell, nullptr);
      } else {
        const V3 t = (d * eta + nf * (eta * cosi - std::sqrt(k))).unit();
        out += m.color * m.transparency *
               Trace(c, p_in, t, RayKind::kRefraction, slot, visit, depth + 1, cell, nullptr);
      }
    }
    return out;
  }

  const RenderJob& job_;
  const Scene::Impl& s_;
  const RenderSettings& set_;
  std::vector<bool> nonempty_;  // [cell]: footprint > 0
  std::vector<Intersector> fog_masters_, surface_masters_;
  Real primary_step_ = 0, shadow_step_ = 0, cutoff_ = 0;  // steps in world units
  std::vector<FogCoeffs> fog_mats_;
  std::vector<SurfaceCoeffs> surface_mats_;
  std::vector<LightR> lights_;
};

void Tally(const RayBatch& b, FrameStats* st) {
  st->rays += b.size();
  st->visits += b.visit_count();
  for (RayKind k : b.kinds()) ++st->rays_by_kind[int(k)];
  for (std::uint32_t s : b.samples()) st->samples += s;
}

// One image row in flight: its rays (ids relative to the row until numbered in order).
struct Row {
  explicit Row(bool store_t) : rays(store_t) {}
  std::uint32_t y = 0;
  RayBatch rays;
  std::uint64_t missed = 0;
};

// The rows of a frame: at most `limit` exist; each is free, traced, or numbered and waiting
// for the sink. Reused rows keep their buffers' capacity.
class RowPool {
 public:
  RowPool(std::size_t limit, bool store_t) : limit_(limit), store_t_(store_t) {}
  // A free row; waits while all `limit` rows are in use.
  Row* Take() {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [&] { return !free_.empty() || all_.size() < limit_; });
    if (free_.empty()) return all_.emplace_back(std::make_unique<Row>(store_t_)).get();
    Row* row = free_.back();
    free_.pop_back();
    return row;
  }
  void Give(Row* row) {
    std::lock_guard<std::mutex> lock(mutex_);
    free_.push_back(row);
    changed_.notify_all();
  }
  // Numbered rows, in order, for the sink; nullptr ends the frame.
  void Push(Row* row) {
    std::lock_guard<std::mutex> lock(mutex_);
    ready_.push_back(row);
    changed_.notify_all();
  }
  Row* Pop() {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [&] { return !ready_.empty(); });
    Row* row = ready_.front();
    ready_.pop_front();
    return row;
  }

 private:
  const std::size_t limit_;
  const bool store_t_;
  std::vector<std::unique_ptr<Row>> all_;
  std::vector<Row*> free_;
  std::deque<Row*> ready_;
  std::mutex mutex_;
  std::condition_variable changed_;
};

// Rows flow through a TBB pipeline: handed out in order, traced in parallel, then numbered
// in row order; a thread of its own gives them to the sink (encoding and compressing them)
// while later rows are traced. No tracing thread waits at a barrier between rows, and the
// sink's work overlaps tracing even with one tracing thread.
template <class Real>
bool RenderFrameIn(const RenderJob& job, Image* image, FrameStats* stats) {
  const RenderSettings& set = job.settings;
  *stats = FrameStats{};
  FrameTracer<Real> tracer(job);
  tbb::enumerable_thread_specific<ThreadCtx<Real>> contexts([&] { return tracer.MakeContext(); });
  tbb::task_arena arena(job.threads > 0 ? job.threads : tbb::task_arena::automatic);
  const std::size_t tokens = 4 * std::size_t(arena.max_concurrency());
  RowPool pool(2 * tokens, set.store_t);
  std::exception_ptr sink_error;  // the sink's first exception (e.g. a full disk)
  std::atomic<bool> sink_failed{false};
  Background writer([&] {
    while (Row* row = pool.Pop()) {
      if (!sink_failed.load()) {
        try {
          job.sink(row->rays);
        } catch (...) {
          sink_error = std::current_exception();
          sink_failed.store(true);
        }
      }
      pool.Give(row);
    }
  });
  std::uint32_t next_y = 0;
  bool cancelled = false;
  auto hand_out = [&](tbb::flow_control& fc) -> Row* {
    if (next_y == set.height || sink_failed.load() || (job.cancel && job.cancel->load())) {
      cancelled = next_y < set.height;
      fc.stop();
      return nullptr;
    }
    Row* row = pool.Take();
    row->y = next_y++;
    return row;
  };
  auto trace = [&](Row* row) {
    row->rays.Clear();
    row->rays.set_first_id(0);
    row->missed = tracer.RenderRow(contexts.local(), row->y, row->rays, *image);
    return row;
  };
  auto number = [&](Row* row) {
    row->rays.Rebase(stats->rays);  // in row order: ids continue
    Tally(row->rays, stats);
    stats->primary_missed += row->missed;
    if (job.progress) job.progress(double(row->y + 1) / set.height);
    pool.Push(row);
  };
  std::exception_ptr trace_error;
  try {
    arena.execute([&] {
      tbb::parallel_pipeline(
          tokens, tbb::make_filter<void, Row*>(tbb::filter_mode::serial_in_order, hand_out) &
                      tbb::make_filter<Row*, Row*>(tbb::filter_mode::parallel, trace) &
                      tbb::make_filter<Row*, void>(tbb::filter_mode::serial_in_order, number));
    });
  } catch (...) {
    trace_error = std::current_exception();
  }
  pool.Push(nullptr);
  writer.Join();
  if (trace_error) std::rethrow_exception(trace_error);
  if (sink_error) std::rethrow_exception(sink_error);
  return !cancelled;
}

}  // namespace

bool RenderFrame(const RenderJob& job, Image* image, FrameStats* stats) {
  RAYCELL_CHECK(job.scene && job.cells && job.sink);
  RAYCELL_CHECK(job.footprints);
  RAYCELL_CHECK_EQ(job.footprints->size(), std::size_t(job.cells->cell_count()));
  return job.settings.single_precision ? RenderFrameIn<float>(job, image, stats)
                                       : RenderFrameIn<double>(job, image, stats);
}

}  // namespace raycell
