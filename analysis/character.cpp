#include "analysis/character.h"

#include <algorithm>
#include <iomanip>

#include "base/parallel.h"
#include "graph/frame_tree.h"

namespace raycell {
namespace {

double Ratio(std::uint64_t a, std::uint64_t b) { return b ? double(a) / double(b) : 0.0; }

}  // namespace

double CaptureCharacter::rays_per_pixel() const { return Ratio(rays, pixels * frames); }
double CaptureCharacter::secondary_share() const {
  return Ratio(rays - rays_by_kind[int(RayKind::kPrimary)], rays);
}
double CaptureCharacter::visits_per_ray() const { return Ratio(visits, rays); }
double CaptureCharacter::mean_max_gen() const { return Ratio(max_gen_sum, busy_cells); }

CaptureCharacter Characterize(const TraceReader& reader, unsigned threads) {
  const auto& frames = reader.frames();
  CaptureCharacter c;
  c.frames = frames.size();
  c.pixels = std::uint64_t(reader.header().settings.width) * reader.header().settings.height;
  for (const FrameSummary& s : frames) {
    c.rays += s.rays;
    c.visits += s.visits;
    c.samples += s.samples;
    for (int k = 0; k < kRayKindCount; ++k) c.rays_by_kind[k] += s.rays_by_kind[k];
  }
  // Per frame its own slot, summed in frame order: the same for any thread count.
  struct Gens {
    std::uint64_t busy = 0, sum = 0;
    std::uint32_t largest = 0;
  };
  std::vector<Gens> per_frame(frames.size());
  ParallelFor(frames.size(), threads, [&](std::size_t f) {
    const CellTree tree = BuildFrameTree(reader, f);
    Gens& g = per_frame[f];
    for (std::uint32_t m : MaxGenerations(tree)) {
      if (m == 0) continue;
      ++g.busy;
      g.sum += m;
      g.largest = std::max(g.largest, m);
    }
  });
  for (const Gens& g : per_frame) {
    c.busy_cells += g.busy;
    c.max_gen_sum += g.sum;
    c.max_gen_largest = std::max(c.max_gen_largest, g.largest);
  }
  return c;
}

void PrintCharacter(const CaptureCharacter& c, std::ostream& out) {
  out << std::fixed << std::setprecision(3) << "character:      " << c.rays_per_pixel()
      << " rays per pixel, " << c.secondary_share()
      << " of them secondary (reflection, refraction, shadow), " << c.visits_per_ray()
      << " visits per ray\n"
      << "maxGen:         mean " << c.mean_max_gen() << ", largest " << c.max_gen_largest
      << " over " << c.busy_cells
      << " (frame, cell) pairs with work (the fewest fetches of each, one-cell cache)\n";
  out.unsetf(std::ios::floatfield);
  out << std::setprecision(6);
}

}  // namespace raycell
