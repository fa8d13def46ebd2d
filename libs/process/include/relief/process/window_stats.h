#pragma once
// Sum, sum of squared deviations from the mean and count of the valid
// (non-NaN) samples in the square window of radius r around every output
// sample, computed separably (column sums over 2r+1 rows, then sums of those
// over 2r+1 columns) and streamed one output row at a time, so memory is
// O(width) whatever the image.
//
// The statistics of a sample must depend only on the input around it, so that
// a quad processed with its border gives bit for bit the values of the whole
// image (see view.h). Three ways keep that:
// - Exact (mean, Lee, Kuan): every valid value is an integer multiple of a
//   power of two 2^k (k from the smallest magnitude in the rows at hand), so
//   window sums of those integers and of their squares are exact in 64- and
//   128-bit integers and running sums cost O(1) per sample whatever the
//   radius; the results are the exact sums rounded once, whatever k. The
//   squared deviations come from the exact n sum(v^2) - sum(v)^2: no
//   cancellation. Where the values' magnitudes span too many bits (more
//   than 2^29 between the smallest and largest nonzero magnitude, or an
//   infinity), each window decides alone: exact when its own values fit,
//   else the direct sums below.
// - Integer-valued inputs (8- and 16-bit SAR amplitudes) without `exact`:
//   running sums in double, exact for such values, so the order of additions
//   cannot matter.
// - Other inputs sum every window afresh in a fixed order, O(r) per sample.
#include <cstdint>
#include <vector>

#include "relief/process/view.h"

namespace relief::process {

// True when every valid value is an integer of magnitude <= 2^20: window sums
// of such values and their squares (at most 19 x 19) stay below 2^53, where
// doubles are exact.
bool all_small_integers(ConstView in);

class WindowSums {
 public:
  enum class Mode {
    exact,   // exact integer sums (mean, Lee, Kuan)
    double_  // running double sums when `integral`, else direct double sums
  };
  // `in` extends `radius` beyond the output on every side. `integral` says
  // whether every valid input value is an integer of magnitude <= 2^20
  // (see all_small_integers); it selects the running double sums.
  WindowSums(ConstView in, int radius, bool integral, Mode mode = Mode::double_);
  int width() const { return width_; }
  // Output row y; rows must be requested in increasing order. The arrays hold
  // width() values each and stay valid until the next call.
  void next_row(int y);
  const double* sum() const { return sum_.data(); }
  // Sum of (v - mean)^2 over the valid samples (0 for none).
  const double* dev_sq() const { return dev_sq_.data(); }
  const double* count() const { return count_.data(); }

 private:
  void next_row_double(int y);
  void next_row_exact(int y);
  void window_alone(int x, int y);  // exact mode, values spanning too many bits

  ConstView in_;
  int radius_, width_;
  bool running_;
  bool exact_ = false, exact_running_ = false;
  int scale_exp_ = 0;  // exact: values are integers times 2^scale_exp_
  int last_row_ = -1;
  std::vector<double> vs_, vq_, vc_;  // per input column (double sums)
  std::vector<int64_t> xs_;           // per input column (exact sums)
  std::vector<unsigned __int128> xq_;
  std::vector<int32_t> xc_;
  std::vector<double> sum_, dev_sq_, count_;  // per output column
};

}  // namespace relief::process
