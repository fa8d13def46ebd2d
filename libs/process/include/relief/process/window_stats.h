#pragma once
// Sum, sum of squares and count of the valid (non-NaN) samples in the square
// window of radius r around every output sample, computed separably: column
// sums over 2r+1 rows, then row sums of those over 2r+1 columns.
//
// The statistics of a sample must depend only on the input around it, so that
// a quad processed with its border gives bit for bit the values of the whole
// image (see view.h). Integer-valued inputs (8- and 16-bit SAR amplitudes, the
// common case) use running sums, O(1) per sample whatever the radius: their
// sums are exact in double, so the order of additions cannot matter. Other
// inputs sum every window afresh in a fixed order, O(r) per sample.
#include <vector>

#include "relief/process/view.h"

namespace relief::process {

struct WindowStats {
  int width = 0, height = 0;
  std::vector<double> sum, sum_sq, count;
  size_t index(int x, int y) const {
    return static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x);
  }
};

// Output covers the input view shrunk by `radius` on every side.
WindowStats window_stats(ConstView input, int radius);

}  // namespace relief::process
