#pragma once
// Dynamic-range reduction of SAR amplitudes (seed 003 §2.2). Every operator
// maps linear amplitudes to grey levels in [0, 1]; NaN stays NaN. Global
// operators are a function of the sample and of the dataset's global
// statistics (from the store's manifest or a scan of the whole raster, never
// from what happens to be on screen); local ones also of a neighbourhood.
// docs/process.md gives every formula and parameter.

namespace relief::process {

struct GlobalStats {
  double min = 0, max = 0, mean = 0, stddev = 0;
};

// E[a^gamma] estimated from the mean and standard deviation alone (second-order
// Taylor expansion around the mean). The RAT variant needs the mean of the
// gamma-mapped amplitudes; a store's manifest holds only these four numbers.
// For Rayleigh-distributed amplitudes and gamma = 0.7 the estimate is 0.14 %
// above the exact value.
double estimated_power_mean(const GlobalStats& stats, double gamma);

}  // namespace relief::process
