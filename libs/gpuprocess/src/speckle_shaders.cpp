#include "operator_shaders.h"

namespace relief::gpuprocess {
namespace {

// The window's count, mean and unbiased variance of the valid samples, summed
// as window_stats.cpp does: each column top to bottom, then the columns left
// to right. `precise` forbids fused multiply-adds the CPU does not use.
constexpr const char* kWindowStats = R"(
const double kEpsilon = 1e-10LF;
void window_stats(ivec2 p, out double n, out double mean, out double var) {
  precise double s = 0.0LF, q = 0.0LF, c = 0.0LF;
  for (int dx = -r; dx <= r; ++dx) {
    precise double vs = 0.0LF, vq = 0.0LF, vc = 0.0LF;
    for (int dy = -r; dy <= r; ++dy) {
      float v = at(p + ivec2(dx, dy));
      if (nodata(v)) continue;
      double d = double(v);
      vs += d;
      vq += d * d;
      vc += 1.0LF;
    }
    s += vs;
    q += vq;
    c += vc;
  }
  n = c;
  mean = s / n;
  precise double v = n > 1.0LF ? (q - s * mean) / (n - 1.0LF) : 0.0LF;
  var = max(0.0LF, v);
}
)";
constexpr const char* kLocalStats = R"(
// A local-statistics filter (speckle.cpp local_stats_filter): filter(i, mean, var).
double local_filter(double i, double m, double var);
float apply(ivec2 p) {
  float centre = at(p);
  if (nodata(centre)) return centre;
  double n, m, var;
  window_stats(p, n, m, var);
  return float(local_filter(double(centre), m, var));
}
)";

// Lee and Kuan (speckle.cpp mmse_filter); k[0] = Cu^2 = 1 / looks.
std::string mmse(const std::string& weight) {
  return std::string(kWindowStats) + kLocalStats + R"(
double local_filter(double i, double m, double var) {
  double cu2 = k[0];
  if (abs(m) < kEpsilon) return 0.0LF;
  if (abs(var) < kEpsilon) return m;
  double ci2 = var / (m * m);
  if (ci2 < cu2) return m;
  double wt = )" +
         weight + R"(;
  return i * wt + m * (1.0LF - wt);
}
)";
}

constexpr const char* kGammaMap = R"(
double local_filter(double i, double m, double var) {
  double looks = k[0], cu2 = k[1], cmax = k[2];
  if (abs(m) < kEpsilon) return 0.0LF;
  if (abs(var) < kEpsilon) return m;
  double ci2 = var / (m * m);
  if (ci2 <= cu2) return m;
  if (sqrt(ci2) >= cmax) return i;
  double alpha = (1.0LF + cu2) / (ci2 - cu2);
  double b = alpha - looks - 1.0LF;
  double d = m * m * b * b + 4.0LF * alpha * looks * m * i;
  return (b * m + sqrt(d)) / (2.0LF * alpha);
}
)";

// Frost (speckle.cpp frost_filter): exp(-alpha distance) weights, k[0] = deramp.
constexpr const char* kFrost = R"(
float apply(ivec2 p) {
  float centre = at(p);
  if (nodata(centre)) return centre;
  double n, m, var;
  window_stats(p, n, m, var);
  if (abs(m) < kEpsilon) return 0.0;
  if (abs(var) < kEpsilon) return float(m);
  double alpha = k[0] * var / (m * m);
  precise double norm = 0.0LF, acc = 0.0LF;
  for (int dy = -r; dy <= r; ++dy) {
    for (int dx = -r; dx <= r; ++dx) {
      float v = at(p + ivec2(dx, dy));
      if (nodata(v)) continue;
      double c = dexp(-alpha * sqrt(double(dx * dx + dy * dy)));
      norm += c;
      acc += c * double(v);
    }
  }
  return float(acc / norm);
}
)";

// Gauss (speckle.cpp gauss_filter): weights w[0..2r], columns first.
constexpr const char* kGauss = R"(
float apply(ivec2 p) {
  float centre = at(p);
  if (nodata(centre)) return centre;
  precise double s = 0.0LF, ws = 0.0LF;
  for (int kx = 0; kx <= 2 * r; ++kx) {
    precise double vs = 0.0LF, vw = 0.0LF;
    for (int ky = 0; ky <= 2 * r; ++ky) {
      float v = at(p + ivec2(kx - r, ky - r));
      if (nodata(v)) continue;
      vs += w[ky] * double(v);
      vw += w[ky];
    }
    s += w[kx] * vs;
    ws += w[kx] * vw;
  }
  return float(s / ws);
}
)";

// Median (speckle.cpp median_filter): the upper median of the valid samples,
// exact up to radius 3, above it the median of the column medians.
constexpr const char* kMedian = R"(
float values[49];
float sorted_median(int n) {  // insertion sort of values[0, n), then the middle one
  for (int i = 1; i < n; ++i) {
    float v = values[i];
    int j = i - 1;
    while (j >= 0 && values[j] > v) {
      values[j + 1] = values[j];
      --j;
    }
    values[j + 1] = v;
  }
  return values[n / 2];
}
float apply(ivec2 p) {
  float centre = at(p);
  if (nodata(centre)) return centre;
  if (r <= 3) {
    int n = 0;
    for (int dy = -r; dy <= r; ++dy) {
      for (int dx = -r; dx <= r; ++dx) {
        float v = at(p + ivec2(dx, dy));
        if (!nodata(v)) values[n++] = v;
      }
    }
    return sorted_median(n);
  }
  float columns[19];
  for (int dx = -r; dx <= r; ++dx) {
    int n = 0;
    for (int dy = -r; dy <= r; ++dy) {
      float v = at(p + ivec2(dx, dy));
      if (!nodata(v)) values[n++] = v;
    }
    columns[dx + r] = n == 0 ? nan_f() : sorted_median(n);
  }
  int n = 0;
  for (int i = 0; i <= 2 * r; ++i) {
    if (!nodata(columns[i])) values[n++] = columns[i];
  }
  return sorted_median(n);
}
)";

}  // namespace

// The speckle filters of speckle.cpp (the wavelet: wavelet_passes.h).
void add_speckle_shaders(ShaderBodies& bodies) {
  bodies.insert({
      // Speckle filters.
      {"mean", std::string(kWindowStats) + kLocalStats +
                   "double local_filter(double i, double m, double v) {\n"
                   "  return m;\n}\n"},
      {"lee", mmse("1.0LF - cu2 / ci2")},
      {"kuan", mmse("(1.0LF - cu2 / ci2) / (1.0LF + cu2)")},
      {"gamma-map", std::string(kWindowStats) + kLocalStats + kGammaMap},
      {"frost", std::string(kWindowStats) + kFrost},
      {"gauss", kGauss},
      {"median", kMedian},
  });
}

}  // namespace relief::gpuprocess
