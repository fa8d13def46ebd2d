// Global tone-mapping operators applied to SAR amplitudes (seed 003 §2.2.4).
// Amplitudes are first normalised to [0, 1] by the dataset's maximum.
#include <cmath>

#include "kernels.h"
#include "tone_mapping.h"

namespace relief::process {

double auto_schlick_b(const GlobalStats& g) {
  const double m = g.mean / g.max;  // the mean maps to mid-grey: b m / ((b - 1) m + 1) = 1/2
  return std::max(1.0, (1 - m) / m);
}

double reinhard_devlin_exponent(const GlobalStats& g) {
  const double avg = g.mean / g.max, lo = std::max(0.0, g.min) / g.max;
  return 0.3 + 0.7 * std::pow((1 - avg) / (1 - lo), 1.4);
}

// Drago: g = m / log(1 + c) * log(1 + c a) / log(2 + 8 a^b).
void drago_kernel(ConstView in, MutView out, const KernelContext& c, int y0, int y1) {
  const double k = c.p("c"), m = c.p("m"), b = c.p("b"), scale = 1 / c.stats.max;
  const double norm = m / std::log1p(k);
  point_map(in, out, y0, y1, [=](double a) {
    const double x = std::max(0.0, a) * scale;
    return norm * std::log1p(k * x) / std::log(2 + 8 * std::pow(x, b));
  });
}

// Tumblin-Rushmeier's human contrast sensitivity (revised, 1999).
static double tumblin_gamma(double luminance) {
  return luminance > 100 ? 2.655 : 1.855 + 0.4 * std::log10(luminance + 2.3e-5);
}

// Tumblin-Rushmeier: g = ad (c a / aa)^(gamma(aa) / gamma(ad)), over a display
// whose white is 100 cd/m^2.
void tumblin_kernel(ConstView in, MutView out, const KernelContext& c, int y0, int y1) {
  const double k = c.p("c"), ad = c.p("ad"), scale = 1 / c.stats.max;
  const double aa = std::isnan(c.p("aa")) ? std::max(1e-6, k * c.stats.mean * scale) : c.p("aa");
  const double exponent = tumblin_gamma(aa) / tumblin_gamma(ad);
  constexpr double kDisplayWhite = 100;
  point_map(in, out, y0, y1, [=](double a) {
    return ad / kDisplayWhite * std::pow(k * std::max(0.0, a) * scale / aa, exponent);
  });
}

// Schlick: g = b a / ((b - 1) a + 1).
void schlick_kernel(ConstView in, MutView out, const KernelContext& c, int y0, int y1) {
  const double b = std::isnan(c.p("b")) ? auto_schlick_b(c.stats) : c.p("b");
  const double scale = 1 / c.stats.max;
  point_map(in, out, y0, y1, [=](double a) {
    const double x = std::max(0.0, a) * scale;
    return schlick(x, x, b);
  });
}

// Reinhard-Devlin photoreceptor, light adaptation only (one channel).
void reinhard_devlin_kernel(ConstView in, MutView out, const KernelContext& c, int y0, int y1) {
  const ReinhardDevlin rd(c.stats, c.p("b"), c.p("c"));
  const double scale = 1 / c.stats.max;
  point_map(in, out, y0, y1, [&rd, scale](double a) {
    const double x = std::max(0.0, a) * scale;
    return rd(x, x);
  });
}

}  // namespace relief::process
