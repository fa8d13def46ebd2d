// Local dynamic-range reduction (seed 003 §2.2.4-2.2.5): each sample is mapped
// with a local adaptation value A computed from Gauss-filtered averages G_r
// of its neighbourhood. Amplitudes are normalised to [0, 1] by the dataset's
// maximum first. The window radius parameters are in samples of the finest
// level; coarser pyramid levels scale them (operators.h, scale_params).
#include <cmath>
#include <span>

#include "gauss_stack.h"
#include "kernels.h"
#include "tone_mapping.h"

namespace relief::process {
namespace {

// Calls f(a, G) for every valid sample of rows [y0, y1), a and G normalised;
// G[k] is the average for radii[k]. Results are clipped to [0, 1].
template <class F>
void adaptive_map(ConstView in, MutView out, const std::vector<int>& radii, double scale, int y0,
                  int y1, F f) {
  const int m = (in.width - out.width) / 2;
  GaussStack stack(in.window(0, y0, in.width, y1 - y0 + 2 * m), radii);
  std::vector<double> g(radii.size());
  for (int y = y0; y < y1; ++y) {
    stack.compute_row(y - y0);
    const float* src = in.row(y + m) + m;
    float* dst = out.row(y);
    for (int x = 0; x < out.width; ++x) {
      if (std::isnan(src[x])) {
        dst[x] = src[x];
        continue;
      }
      for (size_t k = 0; k < radii.size(); ++k) g[k] = stack.level(k)[x] * scale;
      const double a = std::max(0.0, static_cast<double>(src[x])) * scale;
      dst[x] = static_cast<float>(std::clamp(f(a, std::span<const double>(g)), 0.0, 1.0));
    }
  }
}

// |G_r - G_{r+1}| / G_r, infinite where G_r is zero but G_{r+1} is not.
double quotient(double g_r, double g_next) {
  if (g_r > 0) return std::abs(g_r - g_next) / g_r;
  return g_next > 0 ? INFINITY : 0.0;
}

// The SAR adaptation value (seed 003 §2.2.5): the largest G_r whose quotient
// exceeds t, so peaks adapt to a wide neighbourhood; a itself where none does.
double sar_adaptation(double a, std::span<const double> g, double t) {
  double adapted = a;
  for (size_t r = 0; r + 1 < g.size(); ++r) {
    if (quotient(g[r], g[r + 1]) > t) adapted = g[r + 1];
  }
  return adapted;
}

// Ashikhmin's perceptual capacity C(L) of a luminance in cd/m^2.
double capacity(double l) {
  if (l < 0.0034) return l / 0.0014;
  if (l < 1) return 2.4483 + std::log10(l / 0.0034) / 0.4027;
  if (l < 7.2444) return 16.5630 + (l - 1) / 0.4027;
  return 32.0693 + std::log10(l / 7.2444) / 0.0556;
}

}  // namespace

// Chiu: g = a / (c G_r).
void chiu_kernel(ConstView in, MutView out, const KernelContext& c, int y0, int y1) {
  const double k = c.p("c");
  const int r = c.ip("radius");
  const std::vector<int> radii = r > 0 ? std::vector<int>{r} : std::vector<int>{};
  adaptive_map(in, out, radii, 1 / c.stats.max, y0, y1, [k](double a, std::span<const double> g) {
    const double local = g.empty() ? a : g[0];  // coarser than the mask: the sample itself
    return local > 0 ? a / (k * local) : 0.0;
  });
}

// Rahman-Jobson-Woodell multiscale retinex: the weighted mean over three
// scales of log(1 + p a) - log(1 + p G_r), mapped from [-range, range] to
// [0, 1]. Weights w^0, w^1, w^2 from the smallest scale up.
void retinex_kernel(ConstView in, MutView out, const KernelContext& c, int y0, int y1) {
  const int big = c.ip("max_radius");
  const double p = c.p("p"), w = c.p("w"), range = c.p("range");
  std::vector<int> radii;
  for (int r : {std::max(1, big / 5), std::max(1, big / 2), big}) {
    if (big > 0) radii.push_back(r);
  }
  const double weights[] = {1, w, w * w}, total = radii.empty() ? 1 : 1 + w + w * w;
  adaptive_map(in, out, radii, 1 / c.stats.max, y0, y1, [&](double a, std::span<const double> g) {
    double sum = 0;
    for (size_t k = 0; k < g.size(); ++k) {
      sum += weights[k] * (std::log1p(p * a) - std::log1p(p * g[k]));
    }
    return 0.5 + sum / total / (2 * range);
  });
}

// Ashikhmin: A is the largest G_r reached before a quotient exceeds t;
// g = F(c A) a / A with F the capacity scaled to the dataset's range.
void ashikhmin_kernel(ConstView in, MutView out, const KernelContext& c, int y0, int y1) {
  const double k = c.p("c"), t = c.p("t");
  const double c_lo = capacity(k * std::max(0.0, c.stats.min) / c.stats.max), c_hi = capacity(k);
  adaptive_map(in, out, radii_up_to(c.ip("max_radius")), 1 / c.stats.max, y0, y1,
               [=](double a, std::span<const double> g) {
                 double adapted = g.empty() ? a : g[0];
                 for (size_t r = 0; r + 1 < g.size() && quotient(g[r], g[r + 1]) < t; ++r) {
                   adapted = g[r + 1];
                 }
                 if (!(adapted > 0)) return 0.0;
                 return (capacity(k * adapted) - c_lo) / (c_hi - c_lo) * a / adapted;
               });
}

// Reinhard et al. photographic: L = key a, V = key A, g = L (1 + L / w^2) / (1 + V),
// with A the largest G_r (scale s = r) before |G_r - G_{r+1}| / (2^phi key / r^2 + G_r)
// (in key units) exceeds t.
void reinhard_kernel(ConstView in, MutView out, const KernelContext& c, int y0, int y1) {
  const double mean = c.stats.mean / c.stats.max;
  const double key = std::isnan(c.p("c")) ? 0.18 / mean : c.p("c");
  const double white = std::isnan(c.p("w")) ? key : c.p("w");
  const double sharpen = std::pow(2.0, c.p("s")), t = c.p("t");
  adaptive_map(in, out, radii_up_to(c.ip("max_radius")), 1 / c.stats.max, y0, y1,
               [=](double a, std::span<const double> g) {
                 double adapted = g.empty() ? a : g[0];
                 for (size_t r = 0; r + 1 < g.size(); ++r) {
                   const double s = static_cast<double>(r + 1);
                   const double v =
                       key * (g[r] - g[r + 1]) / (sharpen * key / (s * s) + key * g[r]);
                   if (std::abs(v) >= t) break;
                   adapted = g[r + 1];
                 }
                 const double l = key * a;
                 return l * (1 + l / (white * white)) / (1 + key * adapted);
               });
}

// Extended Schlick (Eq. 2.15, 2.17) with the SAR adaptation value.
void ext_schlick_kernel(ConstView in, MutView out, const KernelContext& c, int y0, int y1) {
  const double b = std::isnan(c.p("b")) ? auto_schlick_b(c.stats) : c.p("b");
  const double d = c.p("d"), t = c.p("t");
  adaptive_map(in, out, radii_up_to(c.ip("max_radius")), 1 / c.stats.max, y0, y1,
               [=](double a, std::span<const double> g) {
                 const double a_prime = (1 - d) * a + d * sar_adaptation(a, g, t);
                 return schlick(a, a_prime, b);
               });
}

// Extended Reinhard-Devlin (Eq. 2.16, 2.17) with the SAR adaptation value.
void ext_reinhard_devlin_kernel(ConstView in, MutView out, const KernelContext& c, int y0, int y1) {
  const ReinhardDevlin rd(c.stats, c.p("b"), c.p("c"));
  const double d = c.p("d"), t = c.p("t");
  adaptive_map(in, out, radii_up_to(c.ip("max_radius")), 1 / c.stats.max, y0, y1,
               [&](double a, std::span<const double> g) {
                 return rd(a, (1 - d) * a + d * sar_adaptation(a, g, t));
               });
}

}  // namespace relief::process
