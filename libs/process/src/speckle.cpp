#include "relief/process/speckle.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "kernels.h"
#include "relief/process/window_stats.h"

namespace relief::process {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr double kEpsilon = 1e-10;  // as OTB: "zero" mean or variance

// Streams window sums over output rows [y0, y1).
WindowSums sums_for_rows(ConstView in, MutView out, int r, int y0, int y1, bool integral,
                         WindowSums::Mode mode = WindowSums::Mode::double_) {
  return WindowSums(in.window(0, y0, out.width + 2 * r, y1 - y0 + 2 * r), r, integral, mode);
}

// Shared skeleton of the local-statistics filters: f(centre, mean, variance, n).
// Mean, Lee and Kuan take the exact window sums (window_stats.h); Gamma-MAP
// keeps the double sums its GPU shader reproduces bit for bit (its weight
// amplifies their rounding near the threshold).
template <class F>
void local_stats_filter(ConstView in, MutView out, const SpeckleParams& p, int y0, int y1,
                        WindowSums::Mode mode, F f) {
  const int r = p.radius;
  WindowSums sums = sums_for_rows(in, out, r, y0, y1, p.integral_input, mode);
  for (int y = y0; y < y1; ++y) {
    sums.next_row(y - y0);
    const double *s = sums.sum(), *d = sums.dev_sq(), *c = sums.count();
    const float* src = in.row(y + r) + r;
    float* dst = out.row(y);
    for (int x = 0; x < out.width; ++x) {
      const float centre = src[x];
      if (std::isnan(centre)) {
        dst[x] = kNaN;
        continue;
      }
      const double n = c[x];
      const double mean = s[x] / n;
      const double var = n > 1 ? d[x] / (n - 1) : 0.0;
      dst[x] = static_cast<float>(f(static_cast<double>(centre), mean, std::max(0.0, var), n));
    }
  }
}

}  // namespace

void mean_filter(ConstView in, MutView out, const SpeckleParams& p, int y0, int y1) {
  local_stats_filter(in, out, p, y0, y1, WindowSums::Mode::exact,
                     [](double, double m, double, double) { return m; });
}

// Lee and Kuan share everything but the weight of the centre sample.
template <class Weight>
void mmse_filter(ConstView in, MutView out, const SpeckleParams& p, int y0, int y1, Weight weight) {
  const double cu2 = 1.0 / p.looks;
  local_stats_filter(in, out, p, y0, y1, WindowSums::Mode::exact,
                     [=](double i, double m, double var, double) {
                       if (std::abs(m) < kEpsilon) return 0.0;
                       if (std::abs(var) < kEpsilon) return m;
                       const double ci2 = var / (m * m);
                       if (ci2 < cu2) return m;
                       const double w = weight(ci2, cu2);
                       return i * w + m * (1.0 - w);
                     });
}

void lee_filter(ConstView in, MutView out, const SpeckleParams& p, int y0, int y1) {
  mmse_filter(in, out, p, y0, y1, [](double ci2, double cu2) { return 1.0 - cu2 / ci2; });
}

void kuan_filter(ConstView in, MutView out, const SpeckleParams& p, int y0, int y1) {
  mmse_filter(in, out, p, y0, y1,
              [](double ci2, double cu2) { return (1.0 - cu2 / ci2) / (1.0 + cu2); });
}

void gamma_map_filter(ConstView in, MutView out, const SpeckleParams& p, int y0, int y1) {
  const double looks = p.looks, cu2 = 1.0 / looks, cmax = std::sqrt(2.0) * std::sqrt(cu2);
  local_stats_filter(in, out, p, y0, y1, WindowSums::Mode::double_,
                     [=](double i, double m, double var, double) {
                       if (std::abs(m) < kEpsilon) return 0.0;
                       if (std::abs(var) < kEpsilon) return m;
                       const double ci2 = var / (m * m);
                       // At ci2 == cu2 alpha is infinite and the MAP estimate tends to the mean;
                       // OTB evaluates the formula there and returns NaN (see docs/process.md).
                       if (ci2 <= cu2) return m;
                       if (std::sqrt(ci2) >= cmax) return i;  // a point target or an edge: keep it
                       const double alpha = (1.0 + cu2) / (ci2 - cu2);
                       const double b = alpha - looks - 1.0;
                       const double d = m * m * b * b + 4.0 * alpha * looks * m * i;
                       return (b * m + std::sqrt(d)) / (2.0 * alpha);
                     });
}

void frost_filter(ConstView in, MutView out, const SpeckleParams& p, int y0, int y1) {
  const int r = p.radius;
  // The kernel exp(-alpha * distance) takes few distinct distances: compute
  // exp once per distinct distance, not once per neighbour.
  std::vector<double> distances;
  std::vector<int> distance_index;  // per (dx, dy), row-major over the window
  for (int dy = -r; dy <= r; ++dy) {
    for (int dx = -r; dx <= r; ++dx) {
      const double d = std::sqrt(static_cast<double>(dx * dx + dy * dy));
      auto it = std::find(distances.begin(), distances.end(), d);
      if (it == distances.end()) it = distances.insert(distances.end(), d);
      distance_index.push_back(static_cast<int>(it - distances.begin()));
    }
  }
  std::vector<double> weight(distances.size());
  WindowSums sums = sums_for_rows(in, out, r, y0, y1, p.integral_input);
  for (int y = y0; y < y1; ++y) {
    sums.next_row(y - y0);
    for (int x = 0; x < out.width; ++x) {
      const float centre = in.at(x + r, y + r);
      if (std::isnan(centre)) {
        out.at(x, y) = kNaN;
        continue;
      }
      const double n = sums.count()[x], mean = sums.sum()[x] / n;
      const double var = n > 1 ? std::max(0.0, sums.dev_sq()[x] / (n - 1)) : 0.0;
      if (std::abs(mean) < kEpsilon) {
        out.at(x, y) = 0.0f;
        continue;
      }
      if (std::abs(var) < kEpsilon) {
        out.at(x, y) = static_cast<float>(mean);
        continue;
      }
      const double alpha = p.deramp * var / (mean * mean);
      for (size_t d = 0; d < distances.size(); ++d) weight[d] = std::exp(-alpha * distances[d]);
      double norm = 0, acc = 0;
      size_t w = 0;
      for (int dy = -r; dy <= r; ++dy) {
        const float* row = in.row(y + r + dy) + x + r;
        for (int dx = -r; dx <= r; ++dx, ++w) {
          const float v = row[dx];
          if (std::isnan(v)) continue;
          const double c = weight[static_cast<size_t>(distance_index[w])];
          norm += c;
          acc += c * v;
        }
      }
      out.at(x, y) = static_cast<float>(acc / norm);
    }
  }
}

void gauss_filter(ConstView in, MutView out, const SpeckleParams& p, int y0, int y1) {
  const int r = p.radius;
  // sigma = r / 2.5 puts almost all of the mass inside the mask (seed 003 §2.2.5);
  // r = 0 (a coarse level) is a one-sample mask whatever sigma.
  const double sigma = p.sigma > 0 ? p.sigma : (r > 0 ? r / 2.5 : 1.0);
  std::vector<double> kernel(static_cast<size_t>(2 * r + 1));
  for (int k = -r; k <= r; ++k) kernel[k + r] = std::exp(-0.5 * k * k / (sigma * sigma));
  // Separable: vertical weighted sums (values and weights of valid samples),
  // then horizontal, normalised by the valid weight so nodata does not darken.
  const int cols = out.width + 2 * r;
  std::vector<double> vs(static_cast<size_t>(cols)), vw(static_cast<size_t>(cols));
  for (int y = y0; y < y1; ++y) {
    std::fill(vs.begin(), vs.end(), 0.0);
    std::fill(vw.begin(), vw.end(), 0.0);
    for (int k = 0; k <= 2 * r; ++k) {
      const float* row = in.row(y + k);
      for (int x = 0; x < cols; ++x) {
        if (std::isnan(row[x])) continue;
        vs[x] += kernel[k] * row[x];
        vw[x] += kernel[k];
      }
    }
    for (int x = 0; x < out.width; ++x) {
      if (std::isnan(in.at(x + r, y + r))) {
        out.at(x, y) = kNaN;
        continue;
      }
      double s = 0, w = 0;
      for (int k = 0; k <= 2 * r; ++k) {
        s += kernel[k] * vs[x + k];
        w += kernel[k] * vw[x + k];
      }
      out.at(x, y) = static_cast<float>(s / w);
    }
  }
}

void median_filter(ConstView in, MutView out, const SpeckleParams& p, int y0, int y1) {
  const int r = p.radius;
  std::vector<float> values;
  values.reserve(static_cast<size_t>((2 * r + 1) * (2 * r + 1)));
  auto median_of = [](std::vector<float>& v) {
    const size_t mid = v.size() / 2;
    std::nth_element(v.begin(), v.begin() + static_cast<ptrdiff_t>(mid), v.end());
    return v[mid];
  };
  const bool exact = r <= 3;
  std::vector<float> column_medians(static_cast<size_t>(out.width + 2 * r));
  for (int y = y0; y < y1; ++y) {
    if (!exact) {
      // Separable approximation: the median of each column segment first.
      for (int x = 0; x < out.width + 2 * r; ++x) {
        values.clear();
        for (int dy = -r; dy <= r; ++dy) {
          const float v = in.at(x, y + r + dy);
          if (!std::isnan(v)) values.push_back(v);
        }
        column_medians[x] = values.empty() ? kNaN : median_of(values);
      }
    }
    for (int x = 0; x < out.width; ++x) {
      if (std::isnan(in.at(x + r, y + r))) {
        out.at(x, y) = kNaN;
        continue;
      }
      values.clear();
      if (exact) {
        for (int dy = -r; dy <= r; ++dy) {
          for (int dx = -r; dx <= r; ++dx) {
            const float v = in.at(x + r + dx, y + r + dy);
            if (!std::isnan(v)) values.push_back(v);
          }
        }
      } else {
        for (int dx = 0; dx <= 2 * r; ++dx) {
          if (!std::isnan(column_medians[x + dx])) values.push_back(column_medians[x + dx]);
        }
      }
      out.at(x, y) = median_of(values);
    }
  }
}

// --- registry adapters ------------------------------------------------------

namespace {

SpeckleParams speckle_params(const KernelContext& c) {
  SpeckleParams p;
  p.radius = c.ip("radius");
  if (auto it = c.params.find("looks"); it != c.params.end()) p.looks = it->second;
  if (auto it = c.params.find("deramp"); it != c.params.end()) p.deramp = it->second;
  if (auto it = c.params.find("sigma"); it != c.params.end()) p.sigma = it->second;
  p.integral_input = c.integral_input;
  return p;
}

}  // namespace

#define RELIEF_SPECKLE_KERNEL(kernel, filter)                                      \
  void kernel(ConstView in, MutView out, const KernelContext& c, int y0, int y1) { \
    filter(in, out, speckle_params(c), y0, y1);                                    \
  }
RELIEF_SPECKLE_KERNEL(mean_kernel, mean_filter)
RELIEF_SPECKLE_KERNEL(gauss_kernel, gauss_filter)
RELIEF_SPECKLE_KERNEL(median_kernel, median_filter)
RELIEF_SPECKLE_KERNEL(lee_kernel, lee_filter)
RELIEF_SPECKLE_KERNEL(kuan_kernel, kuan_filter)
RELIEF_SPECKLE_KERNEL(frost_kernel, frost_filter)
RELIEF_SPECKLE_KERNEL(gamma_map_filter_kernel, gamma_map_filter)
#undef RELIEF_SPECKLE_KERNEL

}  // namespace relief::process
