#pragma once
// Speckle filters (seed 003 §2.3) on amplitude images. Each takes an input view
// that extends `radius` samples beyond the output on every side; windows are
// square, (2r+1)^2 samples; NaN samples are left out of every statistic and a
// NaN centre gives a NaN output.
//
// The local-statistics filters follow the definitions of OTB's Despeckle
// (mean m and unbiased variance s^2 of the window, Ci^2 = s^2/m^2, Cu^2 = 1/L
// for L looks), so the two agree where windows are complete; see docs/process.md.
#include "relief/process/view.h"

namespace relief::process {

struct SpeckleParams {
  int radius = 1;
  double looks = 1;     // Lee, Kuan, Gamma-MAP
  double deramp = 0.1;  // Frost: damping of the exponential kernel
  double sigma = 0;     // Gauss: standard deviation in samples (0 = radius / 2.5)
  // Set by run_operator from the input (all_small_integers): enables O(1)
  // running window sums. Leave false when unsure: results are the same.
  bool integral_input = false;
};

// Each processes output rows [y0, y1).
void mean_filter(ConstView in, MutView out, const SpeckleParams& p, int y0, int y1);
void lee_filter(ConstView in, MutView out, const SpeckleParams& p, int y0, int y1);
void kuan_filter(ConstView in, MutView out, const SpeckleParams& p, int y0, int y1);
void gamma_map_filter(ConstView in, MutView out, const SpeckleParams& p, int y0, int y1);
void frost_filter(ConstView in, MutView out, const SpeckleParams& p, int y0, int y1);
void gauss_filter(ConstView in, MutView out, const SpeckleParams& p, int y0, int y1);
// Exact median for radius <= 3; above, the separable approximation (median of
// the column medians, Narendra 1981) that keeps large masks affordable.
void median_filter(ConstView in, MutView out, const SpeckleParams& p, int y0, int y1);

// The wavelet filter's shrinkage for `looks`-look amplitudes and threshold
// factor k (seed 003 §2.3.3): the soft thresholds of a trous bands 1..3 on
// log amplitudes, and the bias restoring the mean amplitude the log shifts.
// Shared with the GPU operators (libs/gpuprocess), which must agree.
struct WaveletShrinkage {
  double threshold[3] = {};
  double bias = 0;
};
WaveletShrinkage wavelet_shrinkage(double looks, double k);

}  // namespace relief::process
