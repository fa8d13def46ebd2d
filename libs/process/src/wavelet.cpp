// Wavelet soft thresholding (seed 003 §2.3.3, Donoho 1995) on log amplitudes,
// where speckle is additive with a standard deviation known from the number
// of looks. The transform is the undecimated "a trous" B3-spline wavelet:
// shift-invariant, so a quad with its border gives exactly the whole image's
// result. Each level j smooths with [1 4 6 4 1] / 16 dilated by 2^(j-1);
// w_j = c_(j-1) - c_j; the result is exp(c_J + sum soft(w_j, k sigma e_j) + bias),
// the bias restoring the mean amplitude that the log shifts.
#include <cmath>
#include <vector>

#include "kernels.h"
#include "relief/process/speckle.h"

namespace relief::process {
namespace {

// Standard deviation of white noise of unit deviation in a trous B3 bands 1..3
// (Starck and Murtagh).
constexpr double kBandNoise[] = {0.889, 0.200, 0.086};

double digamma(double x) {
  double r = 0;
  for (; x < 6; x += 1) r -= 1 / x;
  const double f = 1 / (x * x);
  return r + std::log(x) - 0.5 / x - f * (1.0 / 12 - f * (1.0 / 120 - f / 252));
}

double trigamma(double x) {
  double r = 0;
  for (; x < 6; x += 1) r += 1 / (x * x);
  const double f = 1 / (x * x);
  return r + 1 / x + f / 2 + f / x * (1.0 / 6 - f * (1.0 / 30 - f / 42));
}

// Rows of a 2-D float64 plane with NaN as nodata.
struct Plane {
  int width = 0, height = 0;
  std::vector<double> v;
  double& at(int x, int y) { return v[static_cast<size_t>(y) * width + x]; }
  double at(int x, int y) const { return v[static_cast<size_t>(y) * width + x]; }
};

// One a trous smoothing with hole size `step`; the result is 2 * 2 * step
// samples smaller in each direction. Nodata is left out, weights renormalised.
Plane smooth(const Plane& in, int step) {
  static constexpr double kTaps[] = {1.0 / 16, 4.0 / 16, 6.0 / 16, 4.0 / 16, 1.0 / 16};
  const int m = 2 * step;
  Plane rows{in.width - 2 * m, in.height, {}}, out{in.width - 2 * m, in.height - 2 * m, {}};
  std::vector<double> rows_w;
  rows.v.resize(static_cast<size_t>(rows.width) * rows.height);
  rows_w.resize(rows.v.size());
  for (int y = 0; y < rows.height; ++y) {
    for (int x = 0; x < rows.width; ++x) {
      double s = 0, w = 0;
      for (int k = 0; k < 5; ++k) {
        const double v = in.at(x + k * step, y);
        if (std::isnan(v)) continue;
        s += kTaps[k] * v;
        w += kTaps[k];
      }
      rows.at(x, y) = s;
      rows_w[static_cast<size_t>(y) * rows.width + x] = w;
    }
  }
  out.v.resize(static_cast<size_t>(out.width) * out.height);
  for (int y = 0; y < out.height; ++y) {
    for (int x = 0; x < out.width; ++x) {
      double s = 0, w = 0;
      for (int k = 0; k < 5; ++k) {
        s += kTaps[k] * rows.at(x, y + k * step);
        w += kTaps[k] * rows_w[static_cast<size_t>(y + k * step) * rows.width + x];
      }
      out.at(x, y) = w > 0 ? s / w : NAN;
    }
  }
  return out;
}

double soft(double w, double t) {
  return w > t ? w - t : (w < -t ? w + t : 0.0);
}

}  // namespace

int wavelet_margin(int levels) {
  return 2 * ((1 << levels) - 1);
}

WaveletShrinkage wavelet_shrinkage(double looks, double k) {
  // ln A of an L-look amplitude: standard deviation sqrt(psi'(L)) / 2, and
  // ln(mean A) - E[ln A] = ln(Gamma(L + 1/2) / (Gamma(L) sqrt(L))) - (psi(L) - ln L) / 2.
  const double sigma = std::sqrt(trigamma(looks)) / 2;
  WaveletShrinkage s;
  for (int j = 0; j < 3; ++j) s.threshold[j] = k * sigma * kBandNoise[j];
  s.bias = std::lgamma(looks + 0.5) - std::lgamma(looks) - 0.5 * std::log(looks) -
           0.5 * (digamma(looks) - std::log(looks));
  return s;
}

void wavelet_kernel(ConstView in, MutView out, const KernelContext& c, int y0, int y1) {
  const int levels = c.ip("levels"), margin = wavelet_margin(levels);
  const WaveletShrinkage shrink = wavelet_shrinkage(c.p("looks"), c.p("k"));
  // Amplitudes <= 0 have no logarithm: they are left out and returned as 0.
  std::vector<Plane> c_levels(1);
  Plane& c0 = c_levels[0];
  c0 = {in.width, y1 - y0 + 2 * margin, {}};
  c0.v.resize(static_cast<size_t>(c0.width) * c0.height);
  for (int y = 0; y < c0.height; ++y) {
    const float* src = in.row(y0 + y);
    for (int x = 0; x < c0.width; ++x) c0.at(x, y) = src[x] > 0 ? std::log(src[x]) : NAN;
  }
  for (int j = 1; j <= levels; ++j) c_levels.push_back(smooth(c_levels.back(), 1 << (j - 1)));
  for (int y = y0; y < y1; ++y) {
    for (int x = 0; x < out.width; ++x) {
      const float a = in.at(x + margin, y + margin);
      if (!(a > 0)) {
        out.at(x, y) = std::isnan(a) ? a : 0.0f;
        continue;
      }
      // Every level is centred: level j lost 2 * (2^j - 1) samples per side.
      auto value = [&](int j) {
        const int lost = 2 * ((1 << j) - 1), off = margin - lost;
        return c_levels[j].at(x + off, y - y0 + off);
      };
      double result = value(levels);
      for (int j = 1; j <= levels; ++j) {
        result += soft(value(j - 1) - value(j), shrink.threshold[j - 1]);
      }
      out.at(x, y) = static_cast<float>(std::exp(result + shrink.bias));
    }
  }
}

}  // namespace relief::process
