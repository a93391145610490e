// Random frames of rays in raycell's order, their JSON Lines written here independently of
// traces/jsonl.cpp, and the same rays as another tool might write them: other ids, lines
// shuffled, keys in any order, optional keys left out.
#pragma once

#include <algorithm>
#include <cstdint>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "traces/ray_batch.h"

namespace raycell::testing {

// Ray trees one at a time (each ray's parent is an earlier ray of its tree), random kinds,
// pixels (a spawned ray mostly keeps its parent's), cells below `cells` without consecutive
// repeats, samples 0..999 (sometimes all 1), a few rays without visits.
inline RayBatch RandomFrame(std::mt19937& rng, std::uint32_t cells, int rays) {
  RayBatch b(false);
  std::uniform_int_distribution<std::uint32_t> cell_number(0, cells - 1);
  const auto cell = [&](auto& r) { return CellId(cell_number(r)); };
  std::size_t tree_start = 0;
  for (int i = 0; i < rays; ++i) {
    std::vector<std::size_t> parents;  // rays of this tree with visits
    for (std::size_t j = tree_start; j < b.size(); ++j) {
      if (b.visit_end(j) > b.visit_begin(j)) parents.push_back(j);
    }
    const bool primary = parents.empty() || rng() % 4 == 0;
    if (primary) tree_start = b.size();
    const std::size_t parent = primary ? 0 : parents[rng() % parents.size()];
    const auto spawn = static_cast<std::uint32_t>(
        primary ? 0 : rng() % (b.visit_end(parent) - b.visit_begin(parent)));
    std::uint32_t px = rng() % 300, py = rng() % 200;
    if (!primary && rng() % 5 != 0) px = b.pixel_xs()[parent], py = b.pixel_ys()[parent];
    const RayKind kind = primary ? RayKind::kPrimary : RayKind(1 + rng() % 3);
    b.BeginRay(kind, primary ? kNoParent : parent, spawn, px, py);
    const int visits = rng() % 12 == 0 ? 0 : 1 + rng() % 6;
    const bool ones = rng() % 3 == 0;
    CellId prev = primary ? cell(rng) : b.cells()[b.visit_begin(parent) + spawn];
    for (int v = 0; v < visits; ++v) {
      if (v > 0) {
        if (cells == 1) break;
        CellId next;
        do next = cell(rng);
        while (next == prev);
        prev = next;
      }
      b.AddVisit(prev, ones ? 1 : rng() % 1000, 0.f, 0.f);
    }
  }
  return b;
}

inline std::string List(const std::vector<std::uint32_t>& v, std::size_t begin, std::size_t end) {
  std::string s = "[";
  for (std::size_t i = begin; i < end; ++i) s += (i > begin ? "," : "") + std::to_string(v[i]);
  return s + "]";
}

inline std::string List(const std::vector<CellId>& v, std::size_t begin, std::size_t end) {
  std::vector<std::uint32_t> numbers;
  for (std::size_t i = begin; i < end; ++i) numbers.push_back(v[i].value());
  return List(numbers, 0, numbers.size());
}

// The line `raycell trace cat` writes for ray i.
inline std::string CanonicalLine(const RayBatch& b, std::size_t i, std::optional<int> frame) {
  const RayView r = b.ray(i);
  std::string s = "{";
  if (frame) s += "\"frame\":" + std::to_string(*frame) + ",";
  s += "\"id\":" + std::to_string(r.id);
  s += r.is_primary()
           ? ",\"parent\":null,\"spawn\":null"
           : ",\"parent\":" + std::to_string(r.parent) + ",\"spawn\":" + std::to_string(r.spawn);
  s += std::string(",\"kind\":\"") + ToString(r.kind) + "\",\"pixel\":[" +
       std::to_string(r.pixel_x) + "," + std::to_string(r.pixel_y) + "]";
  s += ",\"cells\":" + List(b.cells(), b.visit_begin(i), b.visit_end(i));
  s += ",\"samples\":" + List(b.samples(), b.visit_begin(i), b.visit_end(i));
  return s + "}\n";
}

inline std::string CanonicalJsonl(const RayBatch& b, std::optional<int> frame = std::nullopt) {
  std::string s;
  for (std::size_t i = 0; i < b.size(); ++i) s += CanonicalLine(b, i, frame);
  return s;
}

// How another tool might write a frame.
struct Disguise {
  bool shuffle = true;        // lines in random order
  bool sparse_ids = true;     // ids: a random increasing map, with gaps, up to ~2^63
  bool drop_defaults = true;  // leave out kind, pixel and samples where they are defaults
  bool minimal = false;       // leave out kind, pixel and samples always
  bool shuffle_keys = true;   // keys in random order, random spaces
};

// The rays of `b` as JSON lines disguised by `d`; `frame` adds the "frame" key.
inline std::vector<std::string> DisguisedLines(std::mt19937& rng, const RayBatch& b,
                                               std::optional<int> frame, const Disguise& d) {
  std::vector<std::uint64_t> id(b.size());
  std::uint64_t next = d.sparse_ids ? rng() % 1000000 : 0;
  for (std::size_t i = 0; i < b.size(); ++i) {
    id[i] = next;
    next += d.sparse_ids ? 1 + (rng() % 3 == 0 ? (std::uint64_t{rng()} << 22) : rng() % 50) : 1;
  }
  std::vector<std::string> lines;
  for (std::size_t i = 0; i < b.size(); ++i) {
    const RayView r = b.ray(i);
    std::vector<std::pair<std::string, std::string>> kv;
    if (frame) kv.push_back({"frame", std::to_string(*frame)});
    kv.push_back({"id", std::to_string(id[i])});
    kv.push_back({"parent", r.is_primary() ? "null" : std::to_string(id[r.parent])});
    kv.push_back({"spawn", r.is_primary() ? "null" : std::to_string(r.spawn)});
    const bool default_kind = r.kind == (r.is_primary() ? RayKind::kPrimary : RayKind::kReflection);
    if (!d.minimal && !(d.drop_defaults && default_kind && rng() % 2)) {
      kv.push_back({"kind", std::string("\"") + ToString(r.kind) + "\""});
    }
    const bool default_pixel =
        r.is_primary() ? r.pixel_x == 0 && r.pixel_y == 0
                       : r.pixel_x == b.pixel_xs()[r.parent] && r.pixel_y == b.pixel_ys()[r.parent];
    if (!d.minimal && !(d.drop_defaults && default_pixel && rng() % 2)) {
      kv.push_back(
          {"pixel", "[" + std::to_string(r.pixel_x) + "," + std::to_string(r.pixel_y) + "]"});
    }
    kv.push_back({"cells", List(b.cells(), b.visit_begin(i), b.visit_end(i))});
    const bool ones =
        std::all_of(b.samples().begin() + b.visit_begin(i), b.samples().begin() + b.visit_end(i),
                    [](std::uint32_t s) { return s == 1; });
    if (!d.minimal && !(d.drop_defaults && ones && rng() % 2)) {
      kv.push_back({"samples", List(b.samples(), b.visit_begin(i), b.visit_end(i))});
    }
    if (d.shuffle_keys) std::shuffle(kv.begin(), kv.end(), rng);
    std::string s = "{";
    for (std::size_t k = 0; k < kv.size(); ++k) {
      const char* space = d.shuffle_keys && rng() % 4 == 0 ? " " : "";
      s += (k ? "," : "") + std::string(space) + "\"" + kv[k].first + "\":" + space + kv[k].second;
    }
    lines.push_back(s + "}\n");
  }
  if (d.shuffle) std::shuffle(lines.begin(), lines.end(), rng);
  return lines;
}

inline std::string Join(const std::vector<std::string>& lines) {
  std::string s;
  for (const std::string& l : lines) s += l;
  return s;
}

}  // namespace raycell::testing
