// The commonly used global mappings (seed 003 §2.2.3) and the explicit
// conversions between amplitude, intensity and decibels.
#include <cmath>

#include "kernels.h"

namespace relief::process {

double estimated_power_mean(const GlobalStats& g, double gamma) {
  const double m = g.mean, var = g.stddev * g.stddev;
  if (!(m > 0)) return 0;
  return std::pow(m, gamma) + 0.5 * gamma * (gamma - 1) * std::pow(m, gamma - 2) * var;
}

// g = a / t clipped, t = mean + k std (k = 3 in the seed).
void linear_kernel(ConstView in, MutView out, const KernelContext& c, int y0, int y1) {
  const double t = c.stats.mean + c.p("sigmas") * c.stats.stddev;
  point_map(in, out, y0, y1, [t](double a) { return a / t; });
}

// a' = (a - t_min) / (t_max - t_min) clipped; g = log(1 + c a') / log(1 + c).
void log_kernel(ConstView in, MutView out, const KernelContext& c, int y0, int y1) {
  const double t_min = std::isnan(c.p("t_min")) ? c.stats.min : c.p("t_min");
  const double t_max = std::isnan(c.p("t_max")) ? c.stats.mean + 3 * c.stats.stddev : c.p("t_max");
  const double span = t_max - t_min, k = c.p("c"), norm = std::log1p(k);
  point_map(in, out, y0, y1, [=](double a) {
    const double x = std::clamp((a - t_min) / span, 0.0, 1.0);
    return std::log1p(k * x) / norm;
  });
}

// g = (a / max)^gamma.
void gamma_kernel(ConstView in, MutView out, const KernelContext& c, int y0, int y1) {
  const double gamma = c.p("gamma"), a_max = c.stats.max;
  point_map(in, out, y0, y1, [=](double a) { return std::pow(std::max(0.0, a) / a_max, gamma); });
}

// The RAT radar tools' variant: a^gamma, then [0, scale * mean(a^gamma)] to [0, 1].
void rat_kernel(ConstView in, MutView out, const KernelContext& c, int y0, int y1) {
  const double gamma = c.p("gamma");
  const double white = c.p("scale") * estimated_power_mean(c.stats, gamma);
  point_map(in, out, y0, y1, [=](double a) { return std::pow(std::max(0.0, a), gamma) / white; });
}

void intensity_to_amplitude_kernel(ConstView in, MutView out, const KernelContext&, int y0,
                                   int y1) {
  point_apply(in, out, y0, y1, [](double i) { return i >= 0 ? std::sqrt(i) : NAN; });
}

void amplitude_to_intensity_kernel(ConstView in, MutView out, const KernelContext&, int y0,
                                   int y1) {
  point_apply(in, out, y0, y1, [](double a) { return a * a; });
}

// 20 log10(A) equals 10 log10(I): one decibel scale serves both.
void db_to_amplitude_kernel(ConstView in, MutView out, const KernelContext&, int y0, int y1) {
  point_apply(in, out, y0, y1, [](double db) { return std::pow(10.0, db / 20); });
}

void amplitude_to_db_kernel(ConstView in, MutView out, const KernelContext&, int y0, int y1) {
  point_apply(in, out, y0, y1, [](double a) { return a > 0 ? 20 * std::log10(a) : NAN; });
}

}  // namespace relief::process
