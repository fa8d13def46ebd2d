#pragma once
// Sum, sum of squares and count of the valid (non-NaN) samples in the square
// window of radius r around every output sample, computed separably (column
// sums over 2r+1 rows, then sums of those over 2r+1 columns) and streamed one
// output row at a time, so memory is O(width) whatever the image.
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

// True when every valid value is an integer of magnitude <= 2^20: window sums
// of such values and their squares (at most 19 x 19) stay below 2^53, where
// doubles are exact.
bool all_small_integers(ConstView in);

class WindowSums {
 public:
  // `in` extends `radius` beyond the output on every side. `integral` says
  // whether every valid input value is an integer of magnitude <= 2^20
  // (see all_small_integers); it selects the running sums.
  WindowSums(ConstView in, int radius, bool integral);
  int width() const { return width_; }
  // Output row y; rows must be requested in increasing order. The arrays hold
  // width() values each and stay valid until the next call.
  void next_row(int y);
  const double* sum() const { return sum_.data(); }
  const double* sum_sq() const { return sum_sq_.data(); }
  const double* count() const { return count_.data(); }

 private:
  ConstView in_;
  int radius_, width_;
  bool running_;
  int last_row_ = -1;
  std::vector<double> vs_, vq_, vc_;          // per input column
  std::vector<double> sum_, sum_sq_, count_;  // per output column
};

}  // namespace relief::process
