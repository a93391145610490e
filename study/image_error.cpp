#include "study/image_error.h"

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "base/check.h"

namespace raycell {
namespace {

static_assert(FLT_EVAL_METHOD == 0, "float arithmetic must round to float, as numpy's");

constexpr std::size_t kNumpyBufferSize = 8192;  // np.getbufsize()

// numpy's pairwise_sum (numpy/core/src/umath/loops_utils.h.src) on a contiguous array.
double PairwiseSum(const double* a, std::size_t n) {
  if (n < 8) {
    double res = 0.;
    for (std::size_t i = 0; i < n; ++i) res += a[i];
    return res;
  }
  if (n <= 128) {
    double r[8];
    for (int j = 0; j < 8; ++j) r[j] = a[j];
    std::size_t i = 8;
    for (; i < n - n % 8; i += 8) {
      for (int j = 0; j < 8; ++j) r[j] += a[i + j];
    }
    double res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
    for (; i < n; ++i) res += a[i];
    return res;
  }
  std::size_t n2 = n / 2;
  n2 -= n2 % 8;
  return PairwiseSum(a, n2) + PairwiseSum(a + n2, n - n2);
}

// matplotlib's imread of an 8-bit PNG: np.divide(values, 255, dtype=np.float32), a float
// division (FLT_EVAL_METHOD 0: no wider intermediate), as a table of the 256 values.
const std::array<float, 256>& Units() {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int v = 0; v < 256; ++v) t[v] = float(v) / 255.0f;
    return t;
  }();
  return table;
}

// np.mean((x - y) ** 2) of one frame, x and y as float64 copies of the float32 values.
double MeanSquaredError(const Rgb8Image& x, const Rgb8Image& y) {
  const std::array<float, 256>& unit = Units();
  std::vector<double> squares(x.rgb.size());
  for (std::size_t i = 0; i < squares.size(); ++i) {
    const double d = double(unit[x.rgb[i]]) - double(unit[y.rgb[i]]);
    squares[i] = d * d;
  }
  return NumpyMean(squares);
}

}  // namespace

double NumpySum(const double* values, std::size_t n) {
  double sum = 0.;
  for (std::size_t i = 0; i < n; i += kNumpyBufferSize) {
    sum += PairwiseSum(values + i, std::min(kNumpyBufferSize, n - i));
  }
  return sum;
}

double NumpyMean(const std::vector<double>& values) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  return NumpySum(values.data(), values.size()) / double(values.size());
}

double ImageRmse(const std::vector<Rgb8Image>& a, const std::vector<Rgb8Image>& b) {
  if (a.size() != b.size()) {
    throw InputError("image RMSE: " + std::to_string(a.size()) + " frames against " +
                     std::to_string(b.size()));
  }
  std::vector<double> means;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].width != b[i].width || a[i].height != b[i].height) {
      throw InputError("image RMSE: frame " + std::to_string(i) + " is " +
                       std::to_string(a[i].width) + "x" + std::to_string(a[i].height) +
                       " against " + std::to_string(b[i].width) + "x" +
                       std::to_string(b[i].height));
    }
    means.push_back(MeanSquaredError(a[i], b[i]));
  }
  return std::sqrt(NumpyMean(means));
}

}  // namespace raycell
