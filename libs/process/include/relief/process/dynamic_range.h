#pragma once
// Global dynamic-range reduction of SAR amplitudes (seed 003 §2.2.3): each
// output sample is a function of its input sample and of global statistics of
// the whole dataset (from the store's manifest or a scan of the raster, never
// from what happens to be on screen). Input: linear amplitude. Output: grey
// levels in [0, 1]; NaN stays NaN.
#include "relief/process/view.h"

namespace relief::process {

struct GlobalStats {
  double min = 0, max = 0, mean = 0, stddev = 0;
};

// g = a / t clipped to [0, 1], t = mean + k * stddev (k = 3 in the seed).
void linear_map(ConstView in, MutView out, double t, int y0, int y1);
// a' = (a - t_min) / (t_max - t_min) clipped to [0, 1]; g = log(1 + c a') / log(1 + c).
void log_map(ConstView in, MutView out, double c, double t_min, double t_max, int y0, int y1);
// g = (a / a_max)^gamma clipped to [0, 1], gamma in (0, 1].
void gamma_map(ConstView in, MutView out, double gamma, double a_max, int y0, int y1);

}  // namespace relief::process
