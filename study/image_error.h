// The error between two renderings of the same frames as numpy measures it, to the last bit:
// the study prints these errors at full precision, and they must equal what matplotlib and
// numpy give on the same PNGs (`np.sqrt(np.mean([np.mean((x - y) ** 2) ...]))`).
#pragma once

#include <cstddef>
#include <vector>

#include "record/image.h"

namespace raycell {

// np.add.reduce over a contiguous float64 array of n values, in numpy's order: blocks of
// 8192 values (its buffer size) added in turn to a sum starting at 0, each block summed
// pairwise (numpy's pairwise_sum: fewer than 8 values in a loop; up to 128 in eight running
// sums, combined as ((0+1)+(2+3))+((4+5)+(6+7)), then the rest; more split in two halves, the
// first a multiple of 8).
double NumpySum(const double* values, std::size_t n);
// np.mean of the values: NumpySum / n. NaN for no values, as numpy.
double NumpyMean(const std::vector<double>& values);

// The RMSE between frames a[i] and b[i] of 8-bit RGB values, as numpy computes it from
// matplotlib's imread: each value v read as float32(v) / 255 in float32, the squared
// differences in float64, their NumpyMean per frame, the NumpyMean of the frames' means, its
// square root. InputError if the frame counts or a frame's sizes differ.
double ImageRmse(const std::vector<Rgb8Image>& a, const std::vector<Rgb8Image>& b);

}  // namespace raycell
