#include "operator_shaders.h"

#include <fmt/format.h>

namespace relief::gpuprocess {
namespace {

constexpr int kRun = 8;  // outputs per invocation of the window-rows passes

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
// a GPU, and several times less on llvmpipe, which emulates doubles per
// lane): the rows pass (window_rows_shader) leaves, per texel, the sums over
// the row segment of 2r + 1 samples of v and of (v - shift)^2, their count,
// and the shift (the segment's centre); this pass adds the 2r + 1 segments of
// a column for a run of kRun outputs per invocation (each segment fetched
// once), the squares moved to each output sample's own value. Squares around
// a local value keep mean-of-squares-minus-square-of-mean from cancelling;
// the mean is the plain sum (non-negative amplitudes: no cancellation, and 0
// exactly where every sample is 0, as on the CPU); the statistics are
// finished in double. Defines main(), then local_filter(i, mean, var).
constexpr const char* kLocalStatsRuns = R"(
const double kEpsilon = 1e-10LF;
const int kRun = 8;
layout(binding = 1) uniform sampler2D rows;  // window_rows_shader's output
double local_filter(double i, double m, double var);
void finish(ivec2 o, float centre, float s, float sc, float qc, float c);
void main() {
  uvec2 id = gl_GlobalInvocationID.xy;
  int y0 = int(id.y) * kRun;
  if (id.x >= uint(extent.x) || y0 >= extent.y) return;
  ivec2 p = origin + ivec2(int(id.x), y0);
  int last = textureSize(rows, 0).y - 1;
  vec4 t[kRun + 2 * r];
  for (int i = 0; i < kRun + 2 * r; ++i) t[i] = texelFetch(rows, ivec2(p.x, min(p.y - r + i, last)), 0);
  float centre, delta, shifted;
  precise float s, sc, qc, c;
@RUNS@}
void finish(ivec2 o, float centre, float s, float sc, float qc, float c) {
  if (o.y >= origin.y + extent.y) return;
  double n = double(c), ds = double(sc);
  double mean = double(s) / n;
  precise double v = n > 1.0LF ? (double(qc) - ds * ds / n) / (n - 1.0LF) : 0.0LF;
  float result = nodata(centre) ? centre : float(local_filter(double(centre), mean, max(0.0LF, v)));
  imageStore(dst, o, vec4(result, 0.0, 0.0, 0.0));
}
)";

// The runs of the column pass, written out as rows_runs(). Per output: the
// segments' squares around their shifts, moved to the output's value
// ((v - t.w) + delta = v - centre), and the plain sum for the mean.
std::string column_runs(int r) {
  std::string code;
  for (int i = 0; i < kRun; ++i) {
    code += fmt::format(
        "  centre = at(p + ivec2(0, {}));\n  s = 0.0, sc = 0.0, qc = 0.0, c = 0.0;\n", i);
    for (int j = i; j <= i + 2 * r; ++j) {
      code += fmt::format(
          "  delta = t[{0}].w - centre; shifted = t[{0}].x - t[{0}].z * t[{0}].w;\n"
          "  s += t[{0}].x; sc += shifted + t[{0}].z * delta;\n"
          "  qc += t[{0}].y + 2.0 * delta * shifted + t[{0}].z * delta * delta; c += t[{0}].z;\n",
          j);
    }
    code += fmt::format("  finish(p + ivec2(0, {}), centre, s, sc, qc, c);\n", i);
  }
  return code;
}

// One invocation per kRun consecutive outputs of a row: the 2r + kRun
// samples they need are fetched once (fetches are what llvmpipe spends most
// on), then each output's sums are added anew from them (a sliding sum would
// keep the rounding of samples that left the window). Per output: the sum
// of the valid samples, the sum of squared deviations from the output's own
// sample (the shift), their count, and the shift.
constexpr const char* kWindowRows = R"(#version 450 core
layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 0) uniform sampler2D src;
layout(rgba32f, binding = 1) writeonly uniform image2D rows;
uniform ivec2 origin;
uniform ivec2 extent;
uniform int r;
const int kRun = 8;
bool nodata(float v) { return (floatBitsToUint(v) & 0x7fffffffu) > 0x7f800000u; }
void main() {
  uvec2 id = gl_GlobalInvocationID.xy;
  int x0 = int(id.x) * kRun;
  if (x0 >= extent.x || id.y >= uint(extent.y)) return;
  ivec2 p = origin + ivec2(x0, int(id.y));
  int last = textureSize(src, 0).x - 1;
  float v[kRun + 2 * r];
  bool ok[kRun + 2 * r];
  for (int i = 0; i < kRun + 2 * r; ++i) {
    v[i] = texelFetch(src, ivec2(min(p.x - r + i, last), p.y), 0).r;
    ok[i] = !nodata(v[i]);
  }
  float shift, d;
  precise float s, q, c;
@RUNS@}
)";

// The runs of the rows pass, written out (constant indices: the arrays stay
// in registers; llvmpipe keeps dynamically indexed ones in memory).
std::string rows_runs(int r) {
  std::string code;
  for (int i = 0; i < kRun; ++i) {
    code += fmt::format("  shift = ok[{0}] ? v[{0}] : 0.0;\n  s = 0.0, q = 0.0, c = 0.0;\n", i + r);
    for (int j = i; j <= i + 2 * r; ++j) {
      code += fmt::format(
          "  d = ok[{0}] ? v[{0}] - shift : 0.0; s += ok[{0}] ? v[{0}] : 0.0; q += d * d; "
          "c += ok[{0}] ? 1.0 : 0.0;\n",
          j);
    }
    code += fmt::format(
        "  if (x0 + {0} < extent.x) imageStore(rows, p + ivec2({0}, 0), vec4(s, q, c, shift));\n",
        i);
  }
  return code;
}

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
  return std::string(kLocalStatsRuns) + R"(
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
  t.replace(t.find("@RUNS@"), 6, rows_runs(radius));
  return t;
}
void with_runs(std::string& source, int radius) {
  if (const size_t at = source.find("@RUNS@"); at != std::string::npos) {
    source.replace(at, 6, column_runs(radius));
  }
}
bool constant_radius(const std::string& name) {
  return uses_window_rows(name);
}

// The speckle filters of speckle.cpp (the wavelet: wavelet_passes.h).
void add_speckle_shaders(ShaderBodies& bodies) {
  bodies.insert({
      // Speckle filters.
      {"mean", std::string(kLocalStatsRuns) +
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
