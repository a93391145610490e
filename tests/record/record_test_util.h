// Helpers shared by the recorder's tests: small recordings (temporary folders: TempDir in
// tests/test_util.h).
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "record/image.h"
#include "record/recorder.h"
#include "tests/test_util.h"

namespace raycell::testing {

inline std::string ReadBytes(const std::filesystem::path& p) {
  return raycell::testing::ReadBytes(p.string());
}

// A small, quick recording of the built-in scene.
inline RecordOptions SmallBuiltin(const std::filesystem::path& dir, int res = 48) {
  RecordOptions o;
  o.settings.width = o.settings.height = std::uint32_t(res);
  o.out = (dir / "builtin.rct").string();
  o.images_dir.clear();
  o.progress = false;
  return o;
}

inline std::string SharedData() { return RAYCELL_SHARED_DATA; }

// The root mean square and the largest difference of two linear images' channels, and the
// mean channel of each.
struct ImageDiff {
  double rmse = 0, max_abs = 0, mean = 0, mean_other = 0;
};

inline ImageDiff Compare(const Image& a, const Image& b) {
  EXPECT_EQ(a.width(), b.width());
  EXPECT_EQ(a.height(), b.height());
  double sq = 0, sum = 0, sum_other = 0;
  ImageDiff d;
  for (std::size_t i = 0; i < a.pixels().size() && i < b.pixels().size(); ++i) {
    const Rgb &p = a.pixels()[i], &q = b.pixels()[i];
    for (double e : {p.r - q.r, p.g - q.g, p.b - q.b}) {
      sq += e * e;
      d.max_abs = std::max(d.max_abs, std::abs(e));
    }
    sum += p.r + p.g + p.b;
    sum_other += q.r + q.g + q.b;
  }
  const double n = 3.0 * a.pixels().size();
  d.rmse = std::sqrt(sq / n);
  d.mean = sum / n;
  d.mean_other = sum_other / n;
  return d;
}

}  // namespace raycell::testing
