#include "operator_shaders.h"

namespace relief::gpuprocess {
namespace {

// The window's count, mean and unbiased variance of the valid samples, summed
// as window_stats.cpp does: each column top to bottom, then the columns left
// to right. `precise` forbids fused multiply-adds the CPU does not use.
// Frost's statistics (its exp weights cost far more than these sums) and
// Gamma-MAP's (which amplifies their rounding, below).
constexpr const char* kWindowStats = R"(
const double kEpsilon = 1e-10LF;
void window_stats(ivec2 p, out double n, out double mean, out double var) {
  precise double s = 0.0LF, q = 0.0LF, c = 0.0LF;
  for (int dx = -r; dx <= r; ++dx) {
    precise double vs = 0.0LF, vq = 0.0LF, vc = 0.0LF;
    for (int dy = -r; dy <= r; ++dy) {
      // A select, not `continue`: llvmpipe runs a loop with a divergent
      // branch 3-4x slower. Adding 0 changes no sum.
      float v = at(p + ivec2(dx, dy));
      bool valid = !nodata(v);
      double d = valid ? double(v) : 0.0LF;
      vs += d;
      vq += d * d;
      vc += valid ? 1.0LF : 0.0LF;
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

// The same statistics in single precision and two passes (the seed's cost on
// a GPU, and 4-10x less on llvmpipe, which emulates doubles per lane): the
// rows pass (window_rows_shader) leaves, per texel, the sums over the row
// segment of 2r + 1 samples of d = v - shift and d^2, their count, and the
// shift (the segment's centre); this pass adds the 2r + 1 segments of a
// column, moved to the output sample's own value. Sums around a local value
// keep mean-of-squares-minus-square-of-mean from cancelling: for the 8-bit
// amplitudes of SAR stores (and their 2x2 means on coarser levels) every sum
// is exact in float, and the variance is finished in double.
constexpr const char* kWindowStatsRows = R"(
const double kEpsilon = 1e-10LF;
layout(binding = 1) uniform sampler2D rows;  // window_rows_shader's output
void window_stats(ivec2 p, out double n, out double mean, out double var) {
  float centre = at(p);  // valid: the callers checked
  precise float s = 0.0, q = 0.0, c = 0.0;
  for (int dy = -r; dy <= r; ++dy) {
    vec4 t = texelFetch(rows, p + ivec2(0, dy), 0);
    float delta = t.w - centre;  // (v - t.w) + delta = v - centre
    s += t.x + t.z * delta;
    q += t.y + 2.0 * delta * t.x + t.z * delta * delta;
    c += t.z;
  }
  n = double(c);
  const double ds = double(s);
  mean = double(centre) + ds / n;
  precise double v = n > 1.0LF ? (double(q) - ds * ds / n) / (n - 1.0LF) : 0.0LF;
  var = max(0.0LF, v);
}
)";

constexpr const char* kWindowRows = R"(#version 450 core
layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 0) uniform sampler2D src;
layout(rgba32f, binding = 1) writeonly uniform image2D rows;
uniform ivec2 origin;
uniform ivec2 extent;
uniform int r;
bool nodata(float v) { return (floatBitsToUint(v) & 0x7fffffffu) > 0x7f800000u; }
void main() {
  uvec2 id = gl_GlobalInvocationID.xy;
  if (id.x >= uint(extent.x) || id.y >= uint(extent.y)) return;
  ivec2 p = origin + ivec2(id);
  float shift = texelFetch(src, p, 0).r;
  if (nodata(shift)) shift = 0.0;
  precise float s = 0.0, q = 0.0, c = 0.0;
  for (int dx = -r; dx <= r; ++dx) {  // selects, not branches (see kWindowStats)
    float v = texelFetch(src, p + ivec2(dx, 0), 0).r;
    bool valid = !nodata(v);
    float d = valid ? v - shift : 0.0;
    s += d;
    q += d * d;
    c += valid ? 1.0 : 0.0;
  }
  imageStore(rows, p, vec4(s, q, c, shift));
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
  return std::string(kWindowStatsRows) + kLocalStats + R"(
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
      float v = at(p + ivec2(dx, dy));  // selects, not branches (kWindowStats)
      double c = nodata(v) ? 0.0LF : dexp(-alpha * sqrt(double(dx * dx + dy * dy)));
      norm += c;
      acc += c * (nodata(v) ? 0.0LF : double(v));
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
      float v = at(p + ivec2(kx - r, ky - r));  // selects, not branches (kWindowStats)
      double wv = nodata(v) ? 0.0LF : w[ky];
      vs += wv * (nodata(v) ? 0.0LF : double(v));
      vw += wv;
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

bool uses_window_rows(const std::string& name) {
  return name == "mean" || name == "lee" || name == "kuan";
}
std::string window_rows_shader(int radius) {
  std::string t = kWindowRows;
  with_radius(t, radius);
  return t;
}
bool constant_radius(const std::string& name) {
  return uses_window_rows(name);
}

// The speckle filters of speckle.cpp (the wavelet: wavelet_passes.h).
void add_speckle_shaders(ShaderBodies& bodies) {
  bodies.insert({
      // Speckle filters.
      {"mean", std::string(kWindowStatsRows) + kLocalStats +
                   "double local_filter(double i, double m, double v) {\n"
                   "  return m;\n}\n"},
      {"lee", mmse("1.0LF - cu2 / ci2")},
      {"kuan", mmse("(1.0LF - cu2 / ci2) / (1.0LF + cu2)")},
      // Double: 1 / (Ci^2 - Cu^2) amplifies the variance's float rounding
      // (3e-3 relative on the SAR store's tiles in single precision).
      {"gamma-map", std::string(kWindowStats) + kLocalStats + kGammaMap},
      {"frost", std::string(kWindowStats) + kFrost},
      {"gauss", kGauss},
      {"median", kMedian},
  });
}

}  // namespace relief::gpuprocess
