// Durand-Dorsey bilateral tone mapping (seed 003 §2.2.4): in log10 amplitude,
// a bilateral filter gives the base layer B, the rest is detail D = L - B;
// only the base is compressed: g = 10^(k B + D). The dataset's maximum (1
// after normalisation, B = 0) stays white.
#include <cmath>
#include <vector>

#include "kernels.h"

namespace relief::process {
namespace {

constexpr double kFloor = 1e-6;  // normalised amplitudes below map to log10 = -6

// exp(-d^2 / (2 sigma_r^2)) tabulated over |d| < 4 sigma_r (beyond: 0). The
// table depends only on the parameters, so results stay position-independent.
class RangeWeights {
 public:
  explicit RangeWeights(double sigma_r) : step_(4 * sigma_r / (kSize - 1)) {
    for (int i = 0; i < kSize; ++i) {
      const double d = i * step_;
      table_[i] = std::exp(-0.5 * d * d / (sigma_r * sigma_r));
    }
  }
  double operator()(double d) const {
    const double i = std::abs(d) / step_ + 0.5;
    return i < kSize ? table_[static_cast<int>(i)] : 0.0;
  }

 private:
  static constexpr int kSize = 4096;
  double step_;
  double table_[kSize];
};

}  // namespace

void durand_kernel(ConstView in, MutView out, const KernelContext& c, int y0, int y1) {
  const int r = c.ip("radius");
  const double k = c.p("k"), scale = 1 / c.stats.max;
  const double sigma_s = r > 0 ? r / 2.5 : 1.0;  // r = 0: the sample alone
  std::vector<double> spatial;
  for (int dy = -r; dy <= r; ++dy) {
    for (int dx = -r; dx <= r; ++dx) {
      spatial.push_back(std::exp(-0.5 * (dx * dx + dy * dy) / (sigma_s * sigma_s)));
    }
  }
  const RangeWeights range(c.p("sigma_r"));
  // Log amplitudes of the input rows this task reads.
  const int rows = y1 - y0 + 2 * r;
  std::vector<double> logs(static_cast<size_t>(rows) * in.width);
  for (int y = 0; y < rows; ++y) {
    const float* src = in.row(y0 + y);
    for (int x = 0; x < in.width; ++x) {
      logs[static_cast<size_t>(y) * in.width + x] =
          std::isnan(src[x]) ? NAN : std::log10(std::max(kFloor, src[x] * scale));
    }
  }
  for (int y = y0; y < y1; ++y) {
    for (int x = 0; x < out.width; ++x) {
      const double centre = logs[static_cast<size_t>(y - y0 + r) * in.width + x + r];
      if (std::isnan(centre)) {
        out.at(x, y) = NAN;
        continue;
      }
      double sum = 0, weight = 0;
      size_t s = 0;
      for (int dy = 0; dy <= 2 * r; ++dy) {
        const double* row = &logs[static_cast<size_t>(y - y0 + dy) * in.width + x];
        for (int dx = 0; dx <= 2 * r; ++dx, ++s) {
          if (std::isnan(row[dx])) continue;
          const double w = spatial[s] * range(row[dx] - centre);
          sum += w * row[dx];
          weight += w;
        }
      }
      const double base = sum / weight;  // weight >= 1: the centre itself
      out.at(x, y) =
          static_cast<float>(std::clamp(std::pow(10.0, k * base + centre - base), 0.0, 1.0));
    }
  }
}

}  // namespace relief::process
