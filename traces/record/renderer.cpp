// The recording renderer. One of the two translation units that include OpenVDB (with
// scene.cpp).
//
// Every ray is first cut into its visits: the non-empty cells its chord through the scene
// box crosses (CellDDA). All work is then confined to [first visit, last visit]: empty space
// costs nothing, twice over (empty cells are never marched, and inside non-empty cells
// VolumeRayIntersector skips to allocated leaves). Each volume sample is counted in the
// visit holding it. A ray's visits end where it ends: early termination, a surface hit, or
// the box exit.
//
// Fog volumes are integrated front to back exactly as OpenVDB's vdb_render does (same step
// positions, transmittance, cutoff and shadow-ray gain), every lit sample casting one shadow
// ray per light. Level sets are surfaces: sphere-traced within their narrow band, refined by
// bisection, and shaded with diffuse light (shadow rays), mirror reflection and Snell
// refraction with total internal reflection, up to the maximum depth.
#include "traces/record/renderer.h"

#include <openvdb/math/Ray.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/RayIntersector.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <future>
#include <optional>

#include "traces/check.h"
#include "traces/record/camera.h"
#include "traces/record/scene_vdb.h"
#include "traces/record/vec3.h"

namespace raycell {
namespace {

using V3 = openvdb::Vec3d;
using RayT = openvdb::math::Ray<double>;
using TimeSpan = RayT::TimeSpan;
using Intersector = openvdb::tools::VolumeRayIntersector<openvdb::FloatGrid>;
using Accessor = openvdb::FloatGrid::ConstAccessor;
using Sampler = openvdb::tools::BoxSampler;

constexpr double kAmbient = 0.04;     // surfaces' unshadowed ambient term
constexpr int kBisections = 6;        // refinement of a level-set crossing
constexpr double kSpawnOffset = 0.5;  // in voxels: spawned rays start off the surface

Vec3d ToVec(const V3& v) { return {v.x(), v.y(), v.z()}; }
V3 ToV3(const Vec3d& v) { return {v.x, v.y, v.z}; }
V3 ToV3(const Rgb& c) { return {c.r, c.g, c.b}; }
V3 Exp(const V3& v) { return {std::exp(v.x()), std::exp(v.y()), std::exp(v.z())}; }

// The visits of one ray while it is traced: the non-empty cells of its chord, with samples.
class Path {
 public:
  void Build(const CellGrid& grid, const std::vector<std::uint64_t>& fp, const V3& o, const V3& d,
             double tmax, std::optional<CellId> start) {
    cells_.clear(), t0_.clear(), t1_.clear(), samples_.clear();
    cursor_ = 0;
    CellDDA dda(grid, ToVec(o), ToVec(d), 0.0, tmax, start);
    for (CellSegment s; dda.Next(&s);) {
      if (fp[s.cell] == 0) continue;
      cells_.push_back(s.cell), t0_.push_back(s.t0), t1_.push_back(s.t1);
      samples_.push_back(0);
    }
  }
  bool empty() const { return cells_.empty(); }
  std::size_t size() const { return cells_.size(); }
  double t_lo() const { return t0_.front(); }
  double t_hi() const { return t1_.back(); }
  CellId cell(std::size_t i) const { return cells_[i]; }
  // Index of the visit holding t (t inside [t_lo, t_hi]; a t in a gap between visits, which
  // only rounding produces, goes to the visit before it).
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
  // The ray ends at t_end: later visits are dropped, the last one ends at t_end.
  void Truncate(double t_end) {
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
struct GridCtx {
  GridCtx(const Intersector& master, const openvdb::FloatGrid& g)
      : grid(&g),
        inter(master),
        acc(g.getConstAccessor()),
        vs(g.voxelSize()[0]),
        inv_vs(1.0 / vs) {}
  const openvdb::FloatGrid* grid;
  Intersector inter;
  Accessor acc;
  double vs, inv_vs;
  // A world ray in this grid's index space: the position at world t is eye + dir * t.
  struct IndexRay {
    V3 eye, dir;
  };
  IndexRay ToIndex(const V3& o, const V3& d) const {
    const V3 eye = grid->worldToIndex(o);
    return {eye, grid->worldToIndex(o + d) - eye};
  }
  float Sample(const IndexRay& r, double t) { return Sampler::sample(acc, r.eye + r.dir * t); }
  float SampleAt(const V3& world) { return Sampler::sample(acc, grid->worldToIndex(world)); }
  // World-t spans of active leaves along the current ray within [ta, tb].
  void Spans(const V3& o, const V3& d, double ta, double tb, std::vector<TimeSpan>* out) {
    out->clear();
    if (!inter.setWorldRay(RayT(o, d, ta, tb))) return;
    inter.hits(*out);
    for (auto& s : *out) s.t0 *= vs, s.t1 *= vs;  // index t -> world t (uniform scale)
  }
};

struct Hit {
  double t = 0;
  int surface = -1;
};

// Everything a thread needs; scratch is kept per ray depth so that a parent's state
// survives while its children are traced.
struct ThreadCtx {
  std::vector<GridCtx> fogs, surfaces;
  std::vector<Path> paths;
  std::vector<std::vector<TimeSpan>> spans, merged;
  std::vector<std::vector<double>> surface_samples;
  std::vector<std::vector<GridCtx::IndexRay>> fog_rays;  // [depth][fog grid]
  PixelRecord rec;
};

class FrameTracer {
 public:
  explicit FrameTracer(const RenderJob& job)
      : job_(job), s_(job.scene->impl()), set_(job.settings) {
    // Reserved first: a copied intersector is shallow, only the master owns its tree.
    fog_masters_.reserve(s_.fogs.size());
    surface_masters_.reserve(s_.surfaces.size());
    for (const auto& f : s_.fogs) fog_masters_.emplace_back(*f.grid);
    for (const auto& f : s_.surfaces) surface_masters_.emplace_back(*f.grid);
    min_fog_vs_ = 0;
    for (const auto& f : s_.fogs) {
      const double vs = f.grid->voxelSize()[0];
      min_fog_vs_ = min_fog_vs_ == 0 ? vs : std::min(min_fog_vs_, vs);
    }
  }

  ThreadCtx MakeContext() const {
    ThreadCtx c;
    for (std::size_t i = 0; i < s_.fogs.size(); ++i)
      c.fogs.emplace_back(fog_masters_[i], *s_.fogs[i].grid);
    for (std::size_t i = 0; i < s_.surfaces.size(); ++i)
      c.surfaces.emplace_back(surface_masters_[i], *s_.surfaces[i].grid);
    const std::size_t levels = set_.max_depth + 2;
    c.paths.resize(levels);
    c.spans.resize(levels);
    c.merged.resize(levels);
    c.surface_samples.resize(levels);
    c.fog_rays.assign(levels, std::vector<GridCtx::IndexRay>(c.fogs.size()));
    return c;
  }

  // Traces all rays of row y into `out` (ids relative to the row) and the image row.
  std::uint64_t RenderRow(ThreadCtx& c, std::uint32_t y, RayBatch& out, Image& img) const {
    const PinholeCamera cam = PinholeCamera::Create(job_.camera, set_.width, set_.height);
    std::uint64_t missed = 0;
    for (std::uint32_t x = 0; x < set_.width; ++x) {
      V3 sum(0.0);
      for (std::uint32_t s = 0; s < set_.spp; ++s) {
        const auto [jx, jy] = Jitter(x, y, s);
        const V3 o = ToV3(cam.eye()), d = ToV3(cam.Direction(x + jx, y + jy));
        sum += Trace(c, o, d, RayKind::kPrimary, -1, 0, 0, std::nullopt, &missed);
      }
      c.rec.FlushTo(out, x, y);
      sum *= 1.0 / set_.spp;
      RAYCELL_CHECK(std::isfinite(sum.x()) && std::isfinite(sum.y()) && std::isfinite(sum.z()));
      img.at(x, y) = {sum.x(), sum.y(), sum.z()};
    }
    return missed;
  }

 private:
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
  V3 Trace(ThreadCtx& c, const V3& o, const V3& d, RayKind kind, int parent, std::uint32_t spawn,
           std::uint32_t depth, std::optional<CellId> start, std::uint64_t* missed) const {
    const int slot = c.rec.Open(kind, parent, spawn);
    Path& path = c.paths[depth];
    path.Build(*job_.cells, job_.footprints, o, d, CellDDA::kInfinity, start);
    if (path.empty()) {  // only a primary ray can miss every non-empty cell
      c.rec.DropLast();
      if (missed) ++*missed;
      return BackgroundOf(d);
    }
    const std::optional<Hit> hit = FindSurface(c, depth, o, d, path.t_lo(), path.t_hi());
    const double t_fog_end = hit ? hit->t : path.t_hi();
    V3 lumi(0.0), trans(1.0);
    std::optional<double> t_term =
        MarchFog(c, slot, depth, o, d, path.t_lo(), t_fog_end, &lumi, &trans);
    if (!t_term) {
      lumi += trans * (hit ? Shade(c, slot, depth, o, d, *hit) : BackgroundOf(d));
    }
    Finish(c, slot, depth, t_term ? *t_term : t_fog_end);
    return lumi;
  }

  // Attributes the surface search's samples up to t_end, cuts the path there, records it.
  void Finish(ThreadCtx& c, int slot, std::uint32_t depth, double t_end) const {
    Path& path = c.paths[depth];
    for (double t : c.surface_samples[depth]) {
      if (t <= t_end) path.AddSamples(t, 1);
    }
    path.Truncate(t_end);
    c.rec.Close(slot, path);
  }

  V3 BackgroundOf(const V3& d) const {
    const Rgb b = job_.scene->background(ToVec(d));
    return {b.r, b.g, b.b};
  }

  // Spans of active fog along the ray within [ta, tb], merged over fog grids, in world t.
  const std::vector<TimeSpan>& FogSpans(ThreadCtx& c, std::uint32_t depth, const V3& o, const V3& d,
                                        double ta, double tb) const {
    auto& merged = c.merged[depth];
    merged.clear();
    for (std::size_t i = 0; i < c.fogs.size(); ++i) {
      GridCtx& g = c.fogs[i];
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

  // The optical depth of one step of `step` world units at world t (coefficients are per
  // voxel of each grid, as in vdb_render) and the single-scattering albedo there; returns the
  // largest density. Densities below 0 (or NaN) count as 0, so depth is never negative and
  // transmittance never grows along a ray; an infinite depth is fine (the step is opaque).
  double FogAt(ThreadCtx& c, std::uint32_t depth, double t, double step, V3* tau,
               V3* albedo) const {
    double max_density = 0;
    V3 extinction(0.0), scattering(0.0);  // density-weighted coefficients per world unit
    for (std::size_t i = 0; i < c.fogs.size(); ++i) {
      const double dens = Density(c.fogs[i].Sample(c.fog_rays[depth][i], t));
      max_density = std::max(max_density, dens);
      const FogMaterial& m = s_.fogs[i].material;
      const double k = dens * c.fogs[i].inv_vs;
      extinction += (ToV3(m.absorption) + ToV3(m.scattering)) * k;
      scattering += ToV3(m.scattering) * k;
    }
    *tau = extinction * step;
    for (int ch = 0; ch < 3; ++ch) {  // a ratio of coefficients: finite whatever the density
      (*albedo)[ch] = extinction[ch] > 0 && std::isfinite(extinction[ch])
                          ? scattering[ch] / extinction[ch]
                          : 0.0;
    }
    return max_density;
  }

  static double Density(double sampled) { return sampled > 0 ? sampled : 0.0; }

  // Front-to-back fog integration over [ta, tb]; every lit sample casts shadow rays.
  // Returns the parameter of early termination, if it happened.
  std::optional<double> MarchFog(ThreadCtx& c, int slot, std::uint32_t depth, const V3& o,
                                 const V3& d, double ta, double tb, V3* lumi, V3* trans) const {
    if (c.fogs.empty()) return std::nullopt;
    const double step = set_.primary_step * min_fog_vs_;
    for (const TimeSpan& span : FogSpans(c, depth, o, d, ta, tb)) {
      for (double k = std::ceil(span.t0 / step); k * step <= span.t1; k += 1) {
        const double t = k * step;
        const std::uint32_t visit = c.paths[depth].AddSampleInOrder(t);
        V3 tau, albedo;
        const double density = FogAt(c, depth, t, step, &tau, &albedo);
        if (density < set_.cutoff || density == 0) continue;
        const V3 dT = Exp(-tau);
        const V3 pos = o + d * t;
        const CellId cell = c.paths[depth].cell(visit);
        for (const Light& l : s_.lights) {
          const V3 s_trans = TraceShadow(c, slot, visit, depth + 1, pos, l, cell);
          *lumi += albedo * ToV3(l.color) * s_trans * *trans * (V3(1.0) - dT);
        }
        *trans *= dT;
        if (trans->lengthSqr() < set_.cutoff) return t;
      }
    }
    return std::nullopt;
  }

  // A shadow ray from pos towards light l: its transmittance through fog and surfaces.
  V3 TraceShadow(ThreadCtx& c, int parent, std::uint32_t spawn, std::uint32_t depth, const V3& pos,
                 const Light& l, CellId start) const {
    V3 dir = ToV3(l.v);
    double tmax = CellDDA::kInfinity;
    if (l.type == Light::Type::kPoint) {
      dir -= pos;
      tmax = dir.length();
      if (!(tmax > 0)) return V3(1.0);
      dir /= tmax;
    }
    const int slot = c.rec.Open(RayKind::kShadow, parent, spawn);
    Path& path = c.paths[depth];
    path.Build(*job_.cells, job_.footprints, pos, dir, tmax, start);
    const std::optional<Hit> hit = FindSurface(c, depth, pos, dir, path.t_lo(), path.t_hi());
    const double t_stop = hit ? hit->t : path.t_hi();
    V3 trans(1.0);
    std::optional<double> t_term = Attenuate(c, depth, pos, dir, path.t_lo(), t_stop, &trans);
    if (hit && !t_term) trans *= s_.surfaces[hit->surface].material.transparency;
    Finish(c, slot, depth, t_term ? *t_term : t_stop);
    return trans;
  }

  // Shadow-ray transmittance through fog over [ta, tb], vdb_render's rule with gain.
  std::optional<double> Attenuate(ThreadCtx& c, std::uint32_t depth, const V3& o, const V3& d,
                                  double ta, double tb, V3* trans) const {
    if (c.fogs.empty()) return std::nullopt;
    const double step = set_.shadow_step * min_fog_vs_;
    for (const TimeSpan& span : FogSpans(c, depth, o, d, ta, tb)) {
      for (double k = std::ceil(span.t0 / step); k * step <= span.t1; k += 1) {
        const double t = k * step;
        c.paths[depth].AddSampleInOrder(t);
        V3 tau(0.0);
        double max_density = 0;
        for (std::size_t i = 0; i < c.fogs.size(); ++i) {
          const double dens = Density(c.fogs[i].Sample(c.fog_rays[depth][i], t));
          max_density = std::max(max_density, dens);
          const FogMaterial& m = s_.fogs[i].material;
          const double voxel_t = t * c.fogs[i].inv_vs;
          tau += (ToV3(m.absorption) + ToV3(m.scattering)) *
                 (dens * step * c.fogs[i].inv_vs / (1.0 + voxel_t * m.shadow_gain));
        }
        if (max_density < set_.cutoff) continue;
        *trans *= Exp(-tau);
        if (trans->lengthSqr() < set_.cutoff) return t;
      }
    }
    return std::nullopt;
  }

  // The nearest level-set crossing along the ray in [ta, tb]. Every level-set evaluation's t
  // is kept in surface_samples[depth] so that it can be counted where the ray really goes.
  std::optional<Hit> FindSurface(ThreadCtx& c, std::uint32_t depth, const V3& o, const V3& d,
                                 double ta, double tb) const {
    auto& samples = c.surface_samples[depth];
    samples.clear();
    std::optional<Hit> best;
    for (std::size_t i = 0; i < c.surfaces.size(); ++i) {
      const double limit = best ? best->t : tb;
      if (auto t = Crossing(c.surfaces[i], c.spans[depth], samples, o, d, ta, limit)) {
        best = Hit{*t, int(i)};
      }
    }
    return best;
  }

  static std::optional<double> Crossing(GridCtx& g, std::vector<TimeSpan>& spans,
                                        std::vector<double>& samples, const V3& o, const V3& d,
                                        double ta, double tb) {
    const GridCtx::IndexRay ray = g.ToIndex(o, d);
    g.Spans(o, d, ta, tb, &spans);
    bool have_prev = false, inside = false;
    double prev_t = 0;
    for (const TimeSpan& span : spans) {
      for (double t = span.t0;;) {
        const double phi = g.Sample(ray, t);
        samples.push_back(t);
        const bool in = phi < 0;
        if (have_prev && in != inside) return Refine(g, ray, samples, prev_t, t, inside);
        have_prev = true, inside = in, prev_t = t;
        if (t >= span.t1 || t > tb) break;
        t = std::min(span.t1, t + std::max(0.9 * std::abs(phi), 0.25 * g.vs));
      }
    }
    return std::nullopt;
  }

  // Bisection of a sign change of the level set between a (side `inside_a`) and b.
  static double Refine(GridCtx& g, const GridCtx::IndexRay& ray, std::vector<double>& samples,
                       double a, double b, bool inside_a) {
    for (int i = 0; i < kBisections; ++i) {
      const double m = 0.5 * (a + b);
      samples.push_back(m);
      ((g.Sample(ray, m) < 0) == inside_a ? a : b) = m;
    }
    return 0.5 * (a + b);
  }

  V3 Normal(GridCtx& g, const V3& p) const {
    const double h = 0.5 * g.vs;
    V3 n(g.SampleAt(p + V3(h, 0, 0)) - g.SampleAt(p - V3(h, 0, 0)),
         g.SampleAt(p + V3(0, h, 0)) - g.SampleAt(p - V3(0, h, 0)),
         g.SampleAt(p + V3(0, 0, h)) - g.SampleAt(p - V3(0, 0, h)));
    const double len = n.length();
    return len > 0 ? n / len : V3(0, 1, 0);
  }

  // Radiance leaving a surface hit towards -d: diffuse light through shadow rays, mirror
  // reflection and refraction, each spawned in the hit's cell.
  V3 Shade(ThreadCtx& c, int slot, std::uint32_t depth, const V3& o, const V3& d,
           const Hit& hit) const {
    GridCtx& g = c.surfaces[hit.surface];
    const SurfaceMaterial& m = s_.surfaces[hit.surface].material;
    const V3 p = o + d * hit.t;
    Path& path = c.paths[depth];
    path.AddSamples(hit.t, 6);  // the normal's central differences
    const std::uint32_t visit = path.VisitAt(hit.t);
    const CellId cell = path.cell(visit);
    const V3 n = Normal(g, p);
    const bool entering = d.dot(n) < 0;
    const V3 nf = entering ? n : -n;  // faces the incoming ray
    const V3 p_out = p + nf * (kSpawnOffset * g.vs), p_in = p - nf * (kSpawnOffset * g.vs);
    const V3 color = ToV3(m.color);
    V3 out(0.0);
    const double diffuse = 1.0 - m.reflectivity - m.transparency;
    if (diffuse > 0) {
      out += color * (diffuse * kAmbient);
      for (const Light& l : s_.lights) {
        V3 ldir = l.type == Light::Type::kPoint ? (ToV3(l.v) - p).unit() : ToV3(l.v);
        const double ndl = nf.dot(ldir);
        if (ndl <= 0) continue;
        const V3 tr = TraceShadow(c, slot, visit, depth + 1, p_out, l, cell);
        out += color * ToV3(l.color) * tr * (diffuse * ndl);
      }
    }
    if (depth >= set_.max_depth) return out;
    const V3 r = d - nf * (2.0 * d.dot(nf));
    if (m.reflectivity > 0) {
      out += color * m.reflectivity *
             Trace(c, p_out, r.unit(), RayKind::kReflection, slot, visit, depth + 1, cell, nullptr);
    }
    if (m.transparency > 0) {
      const double eta = entering ? 1.0 / m.ior : m.ior;
      const double cosi = -d.dot(nf);
      const double k = 1.0 - eta * eta * (1.0 - cosi * cosi);
      if (k < 0) {  // total internal reflection
        out +=
            color * m.transparency *
            Trace(c, p_out, r.unit(), RayKind::kReflection, slot, visit, depth + 1, cell, nullptr);
      } else {
        const V3 t = (d * eta + nf * (eta * cosi - std::sqrt(k))).unit();
        out += color * m.transparency *
               Trace(c, p_in, t, RayKind::kRefraction, slot, visit, depth + 1, cell, nullptr);
      }
    }
    return out;
  }

  const RenderJob& job_;
  const Scene::Impl& s_;
  const RenderSettings& set_;
  std::vector<Intersector> fog_masters_, surface_masters_;
  double min_fog_vs_ = 0;
};

void Tally(const RayBatch& b, FrameStats* st) {
  st->rays += b.size();
  st->visits += b.visit_count();
  for (RayKind k : b.kinds()) ++st->rays_by_kind[int(k)];
  for (std::uint32_t s : b.samples()) st->samples += s;
}

}  // namespace

namespace {

// The rows of one band: traced in parallel, then numbered and handed on in row order.
struct Band {
  std::vector<RayBatch> rows;
  std::vector<std::uint64_t> missed;
  std::uint32_t count = 0;
};

}  // namespace

// Bands of rows are traced in parallel while the previous band is handed to the sink on
// another thread (encoding and compressing it), so neither waits for the other.
bool RenderFrame(const RenderJob& job, Image* image, FrameStats* stats) {
  RAYCELL_CHECK(job.scene && job.cells && job.sink);
  RAYCELL_CHECK_EQ(job.footprints.size(), std::size_t(job.cells->cell_count()));
  const RenderSettings& set = job.settings;
  *stats = FrameStats{};
  FrameTracer tracer(job);
  tbb::enumerable_thread_specific<ThreadCtx> contexts([&] { return tracer.MakeContext(); });
  tbb::task_arena arena(job.threads > 0 ? job.threads : tbb::task_arena::automatic);
  constexpr std::uint32_t kBand = 16;
  Band bands[2];
  for (Band& b : bands) {
    b.rows.assign(kBand, RayBatch(set.store_t));
    b.missed.assign(kBand, 0);
  }
  std::future<void> writing;
  bool cancelled = false;
  for (std::uint32_t y0 = 0, k = 0; y0 < set.height; y0 += kBand, k ^= 1) {
    if (job.cancel && job.cancel->load()) {
      cancelled = true;
      break;
    }
    Band& band = bands[k];
    band.count = std::min(kBand, set.height - y0);
    arena.execute([&] {
      tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, band.count, 1), [&](const auto& r) {
        ThreadCtx& c = contexts.local();
        for (std::uint32_t i = r.begin(); i < r.end(); ++i) {
          band.rows[i].Clear();  // ids relative to the row until Rebase
          band.rows[i].set_first_id(0);
          band.missed[i] = tracer.RenderRow(c, y0 + i, band.rows[i], *image);
        }
      });
    });
    if (writing.valid()) writing.get();               // the other band is free again
    for (std::uint32_t i = 0; i < band.count; ++i) {  // in row order: ids continue
      band.rows[i].Rebase(stats->rays);
      Tally(band.rows[i], stats);
      stats->primary_missed += band.missed[i];
    }
    writing = std::async(std::launch::async, [&job, &band] {
      for (std::uint32_t i = 0; i < band.count; ++i) job.sink(band.rows[i]);
    });
    if (job.progress) job.progress(double(y0 + band.count) / set.height);
  }
  if (writing.valid()) writing.get();
  return !cancelled;
}

}  // namespace raycell
