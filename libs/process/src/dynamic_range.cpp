#include "relief/process/dynamic_range.h"

#include <algorithm>
#include <cmath>

namespace relief::process {
namespace {

template <class F>
void point_map(ConstView in, MutView out, int y0, int y1, F f) {
  for (int y = y0; y < y1; ++y) {
    const float* src = in.row(y);
    float* dst = out.row(y);
    for (int x = 0; x < out.width; ++x) {
      const float a = src[x];
      dst[x] =
          std::isnan(a) ? a : static_cast<float>(std::clamp(f(static_cast<double>(a)), 0.0, 1.0));
    }
  }
}

}  // namespace

void linear_map(ConstView in, MutView out, double t, int y0, int y1) {
  point_map(in, out, y0, y1, [t](double a) { return a / t; });
}

void log_map(ConstView in, MutView out, double c, double t_min, double t_max, int y0, int y1) {
  const double span = t_max - t_min, norm = std::log1p(c);
  point_map(in, out, y0, y1, [=](double a) {
    const double x = std::clamp((a - t_min) / span, 0.0, 1.0);
    return std::log1p(c * x) / norm;
  });
}

void gamma_map(ConstView in, MutView out, double gamma, double a_max, int y0, int y1) {
  point_map(in, out, y0, y1, [=](double a) { return std::pow(std::max(0.0, a) / a_max, gamma); });
}

}  // namespace relief::process
