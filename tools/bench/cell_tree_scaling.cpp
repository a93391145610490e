// Linear time of Cell Tree building and Peel: synthetic frames whose trees grow from 10^4
// to 10^7 nodes; prints time and nodes per second per size and the exponent of a
// least-squares fit of log(time) against log(nodes) (1.0 is linear).
//
// Usage: bench_cell_tree_scaling [MAX_NODES=10000000] [CELLS=27] [SEED=1]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <utility>
#include <vector>

#include "graph/cell_tree.h"
#include "graph/peel.h"

namespace raycell {
namespace {

// Random ray trees (a primary ray and a few spawned rays), each ray a random walk over
// `cells` cells, streamed to the builder in batches of 1024 ray trees, until the tree has at
// least `target` nodes.
std::pair<CellTree, double> Build(std::size_t target, std::uint32_t cells, std::mt19937_64& rng) {
  CellTreeBuilder builder;
  std::uniform_int_distribution<std::uint32_t> cell_number(0, cells - 1);
  const auto cell = [&](auto& r) { return CellId(cell_number(r)); };
  std::uniform_int_distribution<int> length(1, 8), children(0, 4);
  RayBatch batch(false);
  RayId next = 0;
  double seconds = 0;
  auto add_ray = [&](RayKind kind, RayId parent, std::uint32_t spawn, CellId first) {
    batch.BeginRay(kind, parent, spawn, 0, 0);
    CellId prev = first;
    batch.AddVisit(prev, 1, 0, 0);
    for (int v = length(rng); v > 1; --v) {
      CellId c;
      do c = cell(rng);
      while (c == prev);
      batch.AddVisit(prev = c, 1, 0, 0);
    }
    return next++;
  };
  for (std::size_t nodes = 0; nodes < target;) {
    batch.Clear();
    batch.set_first_id(next);
    for (int i = 0; i < 1024; ++i) {
      const RayId p = add_ray(RayKind::kPrimary, kNoParent, 0, cell(rng));
      const std::size_t pv =
          batch.visit_end(p - batch.first_id()) - batch.visit_begin(p - batch.first_id());
      for (int k = children(rng); k > 0; --k) {
        const auto spawn = std::uint32_t(rng() % pv);
        add_ray(RayKind::kShadow, p, spawn,
                batch.cells()[batch.visit_begin(p - batch.first_id()) + spawn]);
      }
    }
    const auto t0 = std::chrono::steady_clock::now();
    builder.AddBatch(batch);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    nodes = builder.node_count();
  }
  const auto t0 = std::chrono::steady_clock::now();
  CellTree tree = builder.Finish();
  return {std::move(tree),
          seconds + std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()};
}

double Slope(const std::vector<double>& x, const std::vector<double>& y) {
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < x.size(); ++i) mx += x[i], my += y[i];
  mx /= x.size(), my /= y.size();
  double num = 0, den = 0;
  for (std::size_t i = 0; i < x.size(); ++i)
    num += (x[i] - mx) * (y[i] - my), den += (x[i] - mx) * (x[i] - mx);
  return num / den;
}

int Main(int argc, char** argv) {
  const std::size_t max_nodes = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 10'000'000;
  const std::uint32_t cells = argc > 2 ? std::uint32_t(std::atoi(argv[2])) : 27;
  std::mt19937_64 rng(argc > 3 ? std::strtoull(argv[3], nullptr, 10) : 1);
  std::printf("%12s %12s %10s %12s %10s %12s %9s\n", "nodes", "rays", "build s", "build n/s",
              "peel s", "peel n/s", "splits");
  std::vector<double> lx, lb, lp;
  for (std::size_t target = 10'000; target <= max_nodes; target *= 10) {
    for (std::size_t t : {target, target * 3}) {
      if (t > max_nodes) break;
      const auto [tree, build] = Build(t, cells, rng);
      const auto t0 = std::chrono::steady_clock::now();
      const PeelResult peel = Peel(tree);
      const double p = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const double n = double(tree.node_count());
      std::printf("%12.0f %12llu %10.3f %12.3g %10.3f %12.3g %9zu\n", n,
                  (unsigned long long)tree.rays(), build, n / build, p, n / p, peel.split_peels);
      lx.push_back(std::log(n)), lb.push_back(std::log(build)), lp.push_back(std::log(p));
    }
  }
  std::printf("fitted exponent (time ~ nodes^k): build k = %.3f, peel k = %.3f\n", Slope(lx, lb),
              Slope(lx, lp));
  return 0;
}

}  // namespace
}  // namespace raycell

int main(int argc, char** argv) { return raycell::Main(argc, argv); }
