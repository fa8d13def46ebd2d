#pragma once
// What the operator registry dispatches to: every operator is a kernel that
// fills output rows [y0, y1) from an input view extending the operator's
// margin beyond the output on every side.
#include <algorithm>
#include <cmath>

#include "relief/process/dynamic_range.h"
#include "relief/process/operators.h"

namespace relief::process {

struct KernelContext {
  const Params& params;
  GlobalStats stats;            // valid when the operator needs_global_stats
  bool integral_input = false;  // every valid input is a small integer (window_stats.h)
  double p(const char* name) const { return params.at(name); }
  int ip(const char* name) const { return static_cast<int>(params.at(name)); }
};

using Kernel = void (*)(ConstView in, MutView out, const KernelContext& context, int y0, int y1);

// Applies f to every sample of rows [y0, y1) (no neighbourhood: in and out
// have the same extent); NaN stays NaN.
template <class F>
void point_apply(ConstView in, MutView out, int y0, int y1, F f) {
  for (int y = y0; y < y1; ++y) {
    const float* src = in.row(y);
    float* dst = out.row(y);
    for (int x = 0; x < out.width; ++x) {
      const float a = src[x];
      dst[x] = std::isnan(a) ? a : static_cast<float>(f(static_cast<double>(a)));
    }
  }
}

// point_apply for grey-level results, clipped to [0, 1].
template <class F>
void point_map(ConstView in, MutView out, int y0, int y1, F f) {
  point_apply(in, out, y0, y1, [&f](double a) { return std::clamp(f(a), 0.0, 1.0); });
}

// Speckle filters (speckle.cpp), wrapped for the registry.
void mean_kernel(ConstView, MutView, const KernelContext&, int, int);
void gauss_kernel(ConstView, MutView, const KernelContext&, int, int);
void median_kernel(ConstView, MutView, const KernelContext&, int, int);
void lee_kernel(ConstView, MutView, const KernelContext&, int, int);
void kuan_kernel(ConstView, MutView, const KernelContext&, int, int);
void frost_kernel(ConstView, MutView, const KernelContext&, int, int);
void gamma_map_filter_kernel(ConstView, MutView, const KernelContext&, int, int);
void wavelet_kernel(ConstView, MutView, const KernelContext&, int, int);
int wavelet_margin(int levels);

// Global dynamic-range reduction (dynamic_range.cpp, tone_mapping_global.cpp).
void linear_kernel(ConstView, MutView, const KernelContext&, int, int);
void log_kernel(ConstView, MutView, const KernelContext&, int, int);
void gamma_kernel(ConstView, MutView, const KernelContext&, int, int);
void rat_kernel(ConstView, MutView, const KernelContext&, int, int);
void drago_kernel(ConstView, MutView, const KernelContext&, int, int);
void tumblin_kernel(ConstView, MutView, const KernelContext&, int, int);
void schlick_kernel(ConstView, MutView, const KernelContext&, int, int);
void reinhard_devlin_kernel(ConstView, MutView, const KernelContext&, int, int);

// Local dynamic-range reduction (tone_mapping_local.cpp).
void chiu_kernel(ConstView, MutView, const KernelContext&, int, int);
void retinex_kernel(ConstView, MutView, const KernelContext&, int, int);
void ashikhmin_kernel(ConstView, MutView, const KernelContext&, int, int);
void reinhard_kernel(ConstView, MutView, const KernelContext&, int, int);
void durand_kernel(ConstView, MutView, const KernelContext&, int, int);
void ext_schlick_kernel(ConstView, MutView, const KernelContext&, int, int);
void ext_reinhard_devlin_kernel(ConstView, MutView, const KernelContext&, int, int);

// Explicit conversions between amplitude, intensity and decibels.
void intensity_to_amplitude_kernel(ConstView, MutView, const KernelContext&, int, int);
void amplitude_to_intensity_kernel(ConstView, MutView, const KernelContext&, int, int);
void db_to_amplitude_kernel(ConstView, MutView, const KernelContext&, int, int);
void amplitude_to_db_kernel(ConstView, MutView, const KernelContext&, int, int);

}  // namespace relief::process
