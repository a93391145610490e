#include "traces/auto_cells.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>
#include <utility>

#include "base/check.h"

namespace raycell {

void CellPaths::Add(const RayBatch& coarse) {
  RAYCELL_CHECK_EQ(coarse.first_id(), RayId(rays()));
  for (std::size_t r = 0; r < coarse.size(); ++r) {
    const RayId parent = coarse.parents()[r];
    RAYCELL_CHECK(parent == kNoParent || parent < RayId(rays()));
    RAYCELL_CHECK_LT(rays(), std::size_t{kNone});  // ray numbers fit 32 bits
    parent_.push_back(parent == kNoParent ? kNone : std::uint32_t(parent));
    spawn_.push_back(coarse.spawns()[r]);
    for (std::size_t v = coarse.visit_begin(r); v < coarse.visit_end(r); ++v) {
      const std::uint32_t c = coarse.cells()[v].value();
      cell_.push_back(c);
      cells_ = std::max(cells_, c + 1);
    }
    begin_.push_back(cell_.size());
  }
}

double CellPaths::MaxWorkBytes(const std::vector<std::uint64_t>& fp, std::uint64_t capacity) const {
  RAYCELL_CHECK(fp.size() >= cells_);
  const std::size_t n = rays();
  // Each ray's children, ordered by their spawn visit (then id).
  std::vector<std::uint64_t> child_begin(n + 1, 0);
  for (std::size_t r = 0; r < n; ++r) {
    if (parent_[r] != kNone) ++child_begin[parent_[r] + 1];
  }
  for (std::size_t r = 0; r < n; ++r) child_begin[r + 1] += child_begin[r];
  std::vector<std::uint32_t> child(child_begin[n]);
  {
    std::vector<std::uint64_t> at(child_begin.begin(), child_begin.end() - 1);
    for (std::size_t r = 0; r < n; ++r) {
      if (parent_[r] != kNone) child[at[parent_[r]]++] = std::uint32_t(r);
    }
  }
  for (std::size_t r = 0; r < n; ++r) {
    std::stable_sort(child.begin() + std::ptrdiff_t(child_begin[r]),
                     child.begin() + std::ptrdiff_t(child_begin[r + 1]),
                     [&](std::uint32_t a, std::uint32_t b) { return spawn_[a] < spawn_[b]; });
  }
  std::vector<std::uint64_t> next_child(child_begin.begin(), child_begin.end() - 1);
  // Per cell, the rays queued to enter it: (ray, visit).
  std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> queue(cells_);
  for (std::size_t r = 0; r < n; ++r) {
    if (parent_[r] == kNone && begin_[r] < begin_[r + 1]) {
      queue[cell_[begin_[r]]].push_back({std::uint32_t(r), 0});
    }
  }
  // The LRU cache: per cell whether held and when last used.
  std::vector<std::uint8_t> held(cells_, 0);
  std::vector<std::uint64_t> used(cells_, 0);
  std::uint64_t held_bytes = 0, clock = 0;
  double bytes = 0;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> work;
  for (;;) {
    std::uint32_t c = 0;
    for (std::uint32_t k = 1; k < cells_; ++k) {
      if (queue[k].size() > queue[c].size()) c = k;
    }
    if (cells_ == 0 || queue[c].empty()) break;
    if (!held[c]) {
      bytes += double(fp[c]);
      if (fp[c] <= capacity) {
        while (held_bytes + fp[c] > capacity) {
          std::uint32_t victim = cells_;
          for (std::uint32_t k = 0; k < cells_; ++k) {
            if (held[k] && (victim == cells_ || used[k] < used[victim])) victim = k;
          }
          held[victim] = 0;
          held_bytes -= fp[victim];
        }
        held[c] = 1;
        held_bytes += fp[c];
      }
    }
    used[c] = ++clock;
    work.swap(queue[c]);
    while (!work.empty()) {
      const auto [r, v] = work.back();
      work.pop_back();
      while (next_child[r] < child_begin[r + 1] && spawn_[child[next_child[r]]] <= v) {
        work.push_back({child[next_child[r]++], 0});
      }
      if (begin_[r] + v + 1 < begin_[r + 1]) {
        queue[cell_[begin_[r] + v + 1]].push_back({r, v + 1});
      }
    }
  }
  return bytes;
}

double CellPaths::TreeBytes(const std::vector<std::uint64_t>& fp) const {
  RAYCELL_CHECK(fp.size() >= cells_);
  std::vector<std::uint32_t> max_gen(cells_, 0), count(cells_, 0);
  std::vector<std::uint32_t> touched;
  // (ray, last visit walked) from the ray up to its primary ray.
  std::vector<std::pair<std::size_t, std::uint64_t>> chain;
  for (std::size_t r = 0; r < rays(); ++r) {
    if (begin_[r] == begin_[r + 1]) continue;
    chain.clear();
    std::size_t at = r;
    std::uint64_t last = begin_[r + 1] - begin_[r] - 1;
    for (;;) {
      chain.push_back({at, last});
      if (parent_[at] == kNone) break;
      last = spawn_[at];
      at = std::size_t(parent_[at]);
    }
    // From the primary ray down: a node per visit, but a spawned ray's first visit, which is
    // its parent's node of the spawn visit.
    for (std::size_t k = chain.size(); k-- > 0;) {
      const auto [ray, upto] = chain[k];
      for (std::uint64_t v = parent_[ray] == kNone ? 0 : 1; v <= upto; ++v) {
        const std::uint32_t c = cell_[begin_[ray] + v];
        if (count[c]++ == 0) touched.push_back(c);
        if (k == 0) max_gen[c] = std::max(max_gen[c], count[c]);
      }
    }
    for (std::uint32_t c : touched) count[c] = 0;
    touched.clear();
  }
  double bytes = 0;
  for (std::uint32_t c = 0; c < cells_; ++c) bytes += double(max_gen[c]) * double(fp[c]);
  return bytes;
}

namespace {

// Per fine cell, its cell in `sub`, kNoCell where that cell is empty (fp 0): the map a
// RayRegrouper takes, as the regrouped view's.
std::vector<CellId> NonEmptyMap(const Subdivision& sub, const std::vector<std::uint64_t>& fp) {
  std::vector<CellId> m(sub.coarse_of_fine.size());
  for (std::size_t f = 0; f < m.size(); ++f) {
    const CellId c = sub.coarse_of_fine[f];
    m[f] = fp[c.value()] == 0 ? kNoCell : c;
  }
  return m;
}

}  // namespace

struct AutoCells::Rule {
  // What a rule's cells are made from: nothing but the footprints, frame 0's samples, or the
  // samples of every frame seen.
  enum class Data { kNone, kFirst, kSeen };
  std::string name;  // "uniform", or the SPEC and its data ("kd:27:sqrt@seen")
  std::string spec;
  Data data = Data::kNone;
  bool has = false;  // whether it has cells for the next frame
  Subdivision sub;
  std::vector<std::uint64_t> fp;
  std::unique_ptr<RayRegrouper> regrouper;
  CellPaths paths;
  // Per frame given: its ratio to the baseline's estimate, NaN where it had no cells, and
  // the ratio of its Max Work estimate alone.
  std::vector<double> ratio;
  std::vector<double> mw_ratio;
};

AutoCells::AutoCells(std::uint32_t cells, FineCells fine, const std::string& what)
    : cells_(cells), fine_(std::move(fine)), what_(what) {
  RAYCELL_CHECK(fine_.union_footprint != nullptr);
  if (cells_ > fine_.count()) {
    throw InputError(what_ + ": " + std::to_string(cells_) + " cells from " +
                     std::to_string(fine_.count()) + " fine cells");
  }
  const std::array<std::uint32_t, 3> g = CubicGrid(cells_, fine_.grid, what_);
  const std::string n = std::to_string(cells_);
  using Data = Rule::Data;
  std::vector<std::tuple<std::string, std::string, Data>> rules = {
      {"uniform",
       "grid:" + std::to_string(g[0]) + "x" + std::to_string(g[1]) + "x" + std::to_string(g[2]),
       Data::kNone},
      {"kd:" + n + ":footprint", "kd:" + n + ":footprint", Data::kNone},
      {"kd:" + n + ":sqrt@0", "kd:" + n + ":sqrt", Data::kFirst},
      {"kd:" + n + ":sqrt@seen", "kd:" + n + ":sqrt", Data::kSeen},
  };
  // The grids one prime factor away from the baseline: a factor p of one axis's count moved to
  // another axis (3x3x3 -> the six 1x3x9, 8x8x8 -> the six 4x8x16), within the fine grid;
  // static. (grid:N:crossings picks among grids by a proxy; the estimates compare them here.)
  std::vector<std::array<std::uint32_t, 3>> near;
  for (int from = 0; from < 3; ++from) {
    for (int to = 0; to < 3; ++to) {
      if (from == to) continue;
      for (std::uint32_t p = 2; p <= g[from]; ++p) {
        bool prime = g[from] % p == 0;
        for (std::uint32_t d = 2; prime && d * d <= p; ++d) prime = p % d != 0;
        if (!prime) continue;
        std::array<std::uint32_t, 3> other = g;
        other[from] /= p;
        other[to] *= p;
        if (other[to] > fine_.grid[to]) continue;
        if (std::find(near.begin(), near.end(), other) != near.end()) continue;
        near.push_back(other);
        const std::string grid = "grid:" + std::to_string(other[0]) + "x" +
                                 std::to_string(other[1]) + "x" + std::to_string(other[2]);
        rules.push_back({grid, grid, Data::kNone});
      }
    }
  }
  for (const auto& [name, spec, data] : rules) {
    rules_.push_back(std::make_unique<Rule>());
    rules_.back()->name = name;
    rules_.back()->spec = spec;
    rules_.back()->data = data;
  }
  Prepare();
  std::vector<std::uint64_t> full;
  for (std::uint64_t b : rules_[0]->fp) {
    if (b != 0) full.push_back(b);
  }
  std::sort(full.begin(), full.end());
  capacity_ = full.empty() ? 0 : full[(full.size() - 1) / 2];
}

std::size_t ChooseAutoRule(const std::vector<std::vector<double>>& ratio,
                           const std::vector<double>& switch_cost, std::size_t current) {
  RAYCELL_CHECK_EQ(ratio.size(), switch_cost.size());
  RAYCELL_CHECK_LT(current, ratio.size());
  const std::size_t frames = ratio[0].size();
  const auto r = [&](std::size_t i, std::size_t t) { return i == 0 ? 1.0 : ratio[i][t]; };
  std::size_t chosen = current;
  for (std::size_t j = 0; j < ratio.size(); ++j) {
    if (j == current) continue;
    RAYCELL_CHECK_EQ(ratio[j].size(), frames);
    // The run of the latest frames on which j was cheaper than current, and what it saved.
    double saved = 0;
    std::size_t run = 0;
    for (std::size_t t = frames; t-- > 0;) {
      const double now = r(current, t), other = r(j, t);
      if (!(other < now)) break;  // NaN included
      saved += now - other;
      ++run;
    }
    if (run < 2 || saved < switch_cost[j]) continue;
    if (chosen == current || r(j, frames - 1) < r(chosen, frames - 1)) chosen = j;
  }
  return chosen;
}

AutoCells::~AutoCells() = default;

const Subdivision& AutoCells::next() const { return rules_[chosen_]->sub; }

void AutoCells::Prepare() {
  using Data = Rule::Data;
  const std::size_t k = samples_.size();  // the next frame
  for (auto& rule : rules_) {
    rule->has = rule->data == Data::kNone || k > 0;
    if (!rule->has) continue;
    const bool remake = rule->data == Data::kNone    ? k == 0
                        : rule->data == Data::kFirst ? k == 1
                                                     : true;
    if (remake) {
      FineCells f;
      f.grid = fine_.grid;
      f.union_footprint = fine_.union_footprint;
      if (rule->data == Data::kFirst) {
        f.samples = samples_[0];
      } else if (rule->data == Data::kSeen) {
        f.samples.assign(fine_.count(), 0);
        for (const auto& frame : samples_) {
          for (std::size_t c = 0; c < frame.size(); ++c) f.samples[c] += frame[c];
        }
      }
      rule->sub = Subdivide(ParseSubdivisionSpec(rule->spec, what_), f);
      rule->fp.assign(rule->sub.cells(), 0);
      for (std::uint32_t c = 0; c < rule->sub.cells(); ++c) {
        rule->fp[c] = fine_.union_footprint(FineCellsOf(rule->sub.boxes[c], fine_.grid));
      }
    }
    rule->regrouper = std::make_unique<RayRegrouper>(NonEmptyMap(rule->sub, rule->fp));
    rule->paths = CellPaths();
  }
  // The rule for frame k (ChooseAutoRule): the baseline before two frames are seen.
  if (k < 2) {
    chosen_ = 0;
    return;
  }
  // What changing the cells to a rule costs, in frames of the baseline (design §1 "auto:N"):
  // the changed frame is scheduled with no earlier tree, estimated halfway between Max Work's
  // bytes and the tree's (the baseline's mw/tree from the last two frames, the larger), less
  // the frame the rule would cost with a tree to follow (the lesser of its last two ratios).
  const double no_tree = (1 + std::max(base_mw_over_tree_[k - 2], base_mw_over_tree_[k - 1])) / 2;
  std::vector<std::vector<double>> ratio;
  std::vector<double> switch_cost;
  for (const auto& rule : rules_) {
    ratio.push_back(rule->ratio);
    double cost = std::numeric_limits<double>::infinity();
    if (!std::isnan(rule->ratio[k - 2]) && !std::isnan(rule->ratio[k - 1])) {
      const double mw = std::max(rule->mw_ratio[k - 2], rule->mw_ratio[k - 1]);
      cost = std::max(0.0, mw * no_tree - std::min(rule->ratio[k - 2], rule->ratio[k - 1]));
    }
    switch_cost.push_back(cost);
  }
  chosen_ = ChooseAutoRule(ratio, switch_cost, chosen_);
}

void AutoCells::AddBatch(const RayBatch& fine) {
  if (frame_samples_.empty()) frame_samples_.assign(fine_.count(), 0);
  for (std::size_t v = 0; v < fine.visit_count(); ++v) {
    const std::uint32_t c = fine.cells()[v].value();
    RAYCELL_CHECK_LT(c, fine_.count());
    frame_samples_[c] += fine.samples()[v];
  }
  for (auto& rule : rules_) {
    if (rule->has) rule->paths.Add(rule->regrouper->Regroup(fine));
  }
}

void AutoCells::EndFrame() {
  Frame out;
  out.rule = rules_[chosen_]->name;
  const Rule& base = *rules_[0];
  const double base_mw = base.paths.MaxWorkBytes(base.fp, capacity_);
  const double base_tree = base.paths.TreeBytes(base.fp);
  for (auto& rule : rules_) {
    double q = std::numeric_limits<double>::quiet_NaN(), q_mw = q;
    if (rule->has) {
      const double mw = rule->paths.MaxWorkBytes(rule->fp, capacity_);
      const double tree = rule->paths.TreeBytes(rule->fp);
      q_mw = base_mw > 0 ? mw / base_mw : 1.0;
      q = std::max(q_mw, base_tree > 0 ? tree / base_tree : 1.0);
      out.ratios.push_back({rule->name, q});
    }
    rule->ratio.push_back(q);
    rule->mw_ratio.push_back(q_mw);
  }
  base_mw_over_tree_.push_back(base_tree > 0 ? base_mw / base_tree : 1.0);
  frames_.push_back(std::move(out));
  if (frame_samples_.empty()) frame_samples_.assign(fine_.count(), 0);
  samples_.push_back(std::move(frame_samples_));
  frame_samples_.clear();
  Prepare();
}

}  // namespace raycell
