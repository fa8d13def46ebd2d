#include "operator_shaders.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace relief::gpuprocess {
namespace {

// What every operator shader shares: bindings, uniforms, nodata, and double
// precision log/exp (GLSL has them for float only, whose ~1e-7 relative error
// would not meet the 1e-4 bound after log1p's cancellation; these are
// accurate to a few units in the last place of a double).
constexpr const char* kPrelude = R"(#version 450 core
layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 0) uniform sampler2D src;
layout(r32f, binding = 0) writeonly uniform image2D dst;
uniform ivec2 origin;  // first output texel
uniform ivec2 extent;  // output texels
uniform int r;
uniform double k[8];
uniform double w[361];

float at(ivec2 p) { return texelFetch(src, p, 0).r; }
)";

constexpr const char* kMath = R"(
// Bit tests: nodata survives whatever the compiler assumes about NaN.
bool nodata(float v) { return (floatBitsToUint(v) & 0x7fffffffu) > 0x7f800000u; }
float nan_f() { return uintBitsToFloat(0x7fc00000u); }
double inf_d() { return double(uintBitsToFloat(0x7f800000u)); }
double clamp01(double x) { return x < 0.0LF ? 0.0LF : (1.0LF < x ? 1.0LF : x); }

const double kLn2 = 0.693147180559945309417LF;
const double kLn2Hi = 6.93147180369123816490e-01LF;
const double kLn2Lo = 1.90821492927058770002e-10LF;
const double kLn10 = 2.30258509299404568402LF;

double dlog(double x) {
  if (x == 0.0LF) return -inf_d();
  if (!(x > 0.0LF)) return double(nan_f());
  if (x == inf_d()) return x;
  int e;
  double m = frexp(x, e);  // x = m 2^e, m in [0.5, 1)
  if (m < 0.70710678118654752440LF) {
    m *= 2.0LF;
    e -= 1;
  }
  // log m = 2 atanh(s), |s| <= 0.172: 13 terms of s^(2n+1) / (2n+1).
  double s = (m - 1.0LF) / (m + 1.0LF), s2 = s * s;
  double t = 1.0LF / 25.0LF;
  for (int n = 11; n >= 0; --n) t = 1.0LF / double(2 * n + 1) + s2 * t;
  return 2.0LF * s * t + double(e) * kLn2;
}
// log(1 + y) without the cancellation of 1 + y (the classic u - 1 correction).
double dlog1p(double y) {
  double u = 1.0LF + y;
  if (u == 1.0LF) return y;
  return dlog(u) * (y / (u - 1.0LF));
}
double dlog10(double x) { return dlog(x) / kLn10; }
double dexp(double x) {
  if (x > 709.0LF) return inf_d();
  if (x < -708.0LF) return 0.0LF;
  double n = floor(x / kLn2 + 0.5LF);
  double f = (x - n * kLn2Hi) - n * kLn2Lo;  // |f| <= ln2 / 2
  double t = 1.0LF;
  for (int i = 16; i >= 1; --i) t = 1.0LF + f * t / double(i);
  return ldexp(t, int(n));
}
double dpow(double a, double b) {
  if (a == 0.0LF) return b > 0.0LF ? 0.0LF : (b == 0.0LF ? 1.0LF : inf_d());
  return dexp(b * dlog(a));
}

)";

constexpr const char* kMain = R"(
float apply(ivec2 p);
void main() {
  uvec2 id = gl_GlobalInvocationID.xy;
  if (id.x >= uint(extent.x) || id.y >= uint(extent.y)) return;
  ivec2 p = origin + ivec2(id);
  imageStore(dst, p, vec4(apply(p), 0.0, 0.0, 0.0));
}
)";

// A sample-wise operator: f(a) in double, NaN stays NaN (kernels.h point_apply).
std::string point(const std::string& f) {
  return "double f(double a) {" + f +
         "}\n"
         "float apply(ivec2 p) {\n"
         "  float a = at(p);\n"
         "  return nodata(a) ? a : float(f(double(a)));\n"
         "}\n";
}
// A grey-level mapping: the result clipped to [0, 1] (kernels.h point_map).
std::string mapping(const std::string& f) {
  return point("return clamp01(g(a));").insert(0, "double g(double a) {" + f + "}\n");
}

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

// The Gauss stack G_1 .. G_r (gauss_stack.cpp) and what the local mappings
// of tone_mapping_local.cpp build on it; the weights of radius q start at
// w[q * q - 1]. Every local mapping defines local_map(p, a), a the input.
constexpr const char* kGaussStack = R"(
double gauss_level(ivec2 p, int q) {
  int o = q * q - 1;
  precise double s = 0.0LF, ws = 0.0LF;
  for (int dx = -q; dx <= q; ++dx) {
    precise double cs = 0.0LF, cw = 0.0LF;
    for (int dy = -q; dy <= q; ++dy) {
      float v = at(p + ivec2(dx, dy));
      if (nodata(v)) continue;
      cs += w[o + dy + q] * double(v);
      cw += w[o + dy + q];
    }
    s += w[o + dx + q] * cs;
    ws += w[o + dx + q] * cw;
  }
  return ws > 0.0LF ? s / ws : double(nan_f());
}
// |G_r - G_r+1| / G_r, infinite where G_r is zero but G_r+1 is not.
double quotient(double g_r, double g_next) {
  if (g_r > 0.0LF) return abs(g_r - g_next) / g_r;
  return g_next > 0.0LF ? inf_d() : 0.0LF;
}
// The SAR adaptation value for normalised a, threshold t and scale 1 / max.
double sar_adaptation(ivec2 p, double a, double t, double scale) {
  double adapted = a;
  if (r < 2) return adapted;
  double prev = gauss_level(p, 1) * scale;
  for (int q = 2; q <= r; ++q) {
    double next = gauss_level(p, q) * scale;
    if (quotient(prev, next) > t) adapted = next;
    prev = next;
  }
  return adapted;
}
double local_map(ivec2 p, double a);
float apply(ivec2 p) {
  float v = at(p);
  if (nodata(v)) return v;
  return float(clamp01(local_map(p, double(v))));
}
)";

// Ashikhmin's perceptual capacity (tone_mapping_local.cpp capacity).
constexpr const char* kCapacity = R"(
double capacity(double l) {
  if (l < 0.0034LF) return l / 0.0014LF;
  if (l < 1.0LF) return 2.4483LF + dlog10(l / 0.0034LF) / 0.4027LF;
  if (l < 7.2444LF) return 16.5630LF + (l - 1.0LF) / 0.4027LF;
  return 32.0693LF + dlog10(l / 7.2444LF) / 0.0556LF;
}
)";

// Durand-Dorsey (durand.cpp): a bilateral filter of log10 amplitudes. The
// CPU tabulates the range weight at 4096 steps of |d| < 4 sigma_r; the shader
// computes the same tabulated value (same index, same formula) on the fly.
// w[] holds the (2r+1)^2 spatial weights row by row; k[0] = k, k[1] = 1 / max,
// k[2] = sigma_r, k[3] = the table's step.
constexpr const char* kDurand = R"(
double log_amplitude(float v) { return dlog10(max(1e-6LF, double(v) * k[1])); }
double range_weight(double d) {
  double i = abs(d) / k[3] + 0.5LF;
  if (!(i < 4096.0LF)) return 0.0LF;
  double x = double(int(i)) * k[3];
  return dexp(-0.5LF * x * x / (k[2] * k[2]));
}
float apply(ivec2 p) {
  float v = at(p);
  if (nodata(v)) return v;
  double centre = log_amplitude(v);
  precise double sum = 0.0LF, weight = 0.0LF;
  int s = 0;
  for (int dy = -r; dy <= r; ++dy) {
    for (int dx = -r; dx <= r; ++dx, ++s) {
      float u = at(p + ivec2(dx, dy));
      if (nodata(u)) continue;
      double l = log_amplitude(u);
      double wt = w[s] * range_weight(l - centre);
      sum += wt * l;
      weight += wt;
    }
  }
  double base = sum / weight;
  return float(clamp01(dexp((k[0] * base + centre - base) * kLn10)));
}
)";

const std::map<std::string, std::string>& bodies() {
  static const std::map<std::string, std::string> map = {
      // Conversions.
      {"intensity-to-amplitude", point("return a >= 0.0LF ? sqrt(a) : double(nan_f());")},
      {"amplitude-to-intensity", point("return a * a;")},
      {"db-to-amplitude", point("return dexp(a / 20.0LF * kLn10);")},
      {"amplitude-to-db", point("return a > 0.0LF ? 20.0LF * dlog10(a) : double(nan_f());")},
      // Global mappings; k as step_uniforms() sets it.
      {"linear", mapping("return a / k[0];")},
      {"log", mapping("double x = clamp01((a - k[0]) / k[1]);\n"
                      "return dlog1p(k[2] * x) / k[3];")},
      {"gamma", mapping("return dpow(max(0.0LF, a) / k[1], k[0]);")},
      {"rat", mapping("return dpow(max(0.0LF, a), k[0]) / k[1];")},
      {"drago", mapping("double x = max(0.0LF, a) * k[3];\n"
                        "return k[1] * dlog1p(k[0] * x) / dlog(2.0LF + 8.0LF * dpow(x, k[2]));")},
      {"tumblin", mapping("return k[0] * dpow(k[1] * max(0.0LF, a) * k[2] / k[3], k[4]);")},
      {"schlick", mapping("double x = max(0.0LF, a) * k[1];\n"
                          "return k[0] * x / ((k[0] - 1.0LF) * x + 1.0LF);")},
      {"reinhard-devlin", mapping("double x = max(0.0LF, a) * k[4];\n"
                                  "double l = (1.0LF - k[2]) * x + k[2] * k[3];\n"
                                  "double sigma = dpow(k[1] * l, k[0]);\n"
                                  "return x + sigma > 0.0LF ? x / (x + sigma) : 0.0LF;")},
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
      // Local mappings with the SAR adaptation value.
      {"ext-schlick", std::string(kGaussStack) + R"(
double local_map(ivec2 p, double v) {
  double b = k[0], d = k[1], t = k[2], scale = k[3];
  double a = max(0.0LF, v) * scale;
  double a_prime = (1.0LF - d) * a + d * sar_adaptation(p, a, t, scale);
  return b * a / ((b - 1.0LF) * a_prime + 1.0LF);
}
)"},
      {"ext-reinhard-devlin", std::string(kGaussStack) + R"(
double local_map(ivec2 p, double v) {
  double m = k[0], f = k[1], c = k[2], avg = k[3], d = k[4], t = k[5], scale = k[6];
  double a = max(0.0LF, v) * scale;
  double a_prime = (1.0LF - d) * a + d * sar_adaptation(p, a, t, scale);
  double l = (1.0LF - c) * a_prime + c * avg;
  double sigma = dpow(f * l, m);
  return a + sigma > 0.0LF ? a / (a + sigma) : 0.0LF;
}
)"},
      {"chiu", std::string(kGaussStack) + R"(
double local_map(ivec2 p, double v) {
  double c = k[0], scale = k[1];
  double a = max(0.0LF, v) * scale;
  double local = r == 0 ? a : gauss_level(p, r) * scale;
  return local > 0.0LF ? a / (c * local) : 0.0LF;
}
)"},
      {"retinex", std::string(kGaussStack) + R"(
double local_map(ivec2 p, double v) {
  double pre = k[0], wt = k[1], range = k[2], scale = k[6];
  double a = max(0.0LF, v) * scale;
  if (r == 0) return 0.5LF;
  double weights[3] = double[3](1.0LF, wt, wt * wt);
  double total = 1.0LF + wt + wt * wt;
  double sum = 0.0LF;
  for (int i = 0; i < 3; ++i) {
    double g = gauss_level(p, int(k[3 + i])) * scale;
    sum += weights[i] * (dlog1p(pre * a) - dlog1p(pre * g));
  }
  return 0.5LF + sum / total / (2.0LF * range);
}
)"},
      {"ashikhmin", std::string(kGaussStack) + kCapacity + R"(
double local_map(ivec2 p, double v) {
  double c = k[0], t = k[1], c_lo = k[2], c_hi = k[3], scale = k[4];
  double a = max(0.0LF, v) * scale;
  double adapted = a;
  if (r >= 1) {
    double prev = gauss_level(p, 1) * scale;
    adapted = prev;
    for (int q = 2; q <= r; ++q) {
      double next = gauss_level(p, q) * scale;
      if (!(quotient(prev, next) < t)) break;
      adapted = next;
      prev = next;
    }
  }
  if (!(adapted > 0.0LF)) return 0.0LF;
  return (capacity(c * adapted) - c_lo) / (c_hi - c_lo) * a / adapted;
}
)"},
      {"reinhard", std::string(kGaussStack) + R"(
double local_map(ivec2 p, double v) {
  double key = k[0], white = k[1], sharpen = k[2], t = k[3], scale = k[4];
  double a = max(0.0LF, v) * scale;
  double adapted = a;
  if (r >= 1) {
    double prev = gauss_level(p, 1) * scale;
    adapted = prev;
    for (int q = 2; q <= r; ++q) {
      double next = gauss_level(p, q) * scale;
      double s = double(q - 1);
      double u = key * (prev - next) / (sharpen * key / (s * s) + key * prev);
      if (abs(u) >= t) break;
      adapted = next;
      prev = next;
    }
  }
  double l = key * a;
  return l * (1.0LF + l / (white * white)) / (1.0LF + key * adapted);
}
)"},
      {"durand", kDurand},
      // Not an operator: the wavelet's step at levels where no scale is left.
      {"identity", point("return a;")},
  };
  return map;
}

std::vector<double> gauss_weights(int radius, double sigma) {
  std::vector<double> kernel;
  for (int d = -radius; d <= radius; ++d)
    kernel.push_back(std::exp(-0.5 * d * d / (sigma * sigma)));
  return kernel;
}

// These mirror libs/process/src/tone_mapping_global.cpp (private there); the
// GPU = CPU tests catch any drift.
double auto_schlick_b(const process::GlobalStats& g) {
  const double m = g.mean / g.max;
  return std::max(1.0, (1 - m) / m);
}
double reinhard_devlin_exponent(const process::GlobalStats& g) {
  const double avg = g.mean / g.max, lo = std::max(0.0, g.min) / g.max;
  return 0.3 + 0.7 * std::pow((1 - avg) / (1 - lo), 1.4);
}
double capacity(double l) {
  if (l < 0.0034) return l / 0.0014;
  if (l < 1) return 2.4483 + std::log10(l / 0.0034) / 0.4027;
  if (l < 7.2444) return 16.5630 + (l - 1) / 0.4027;
  return 32.0693 + std::log10(l / 7.2444) / 0.0556;
}
double tumblin_gamma(double luminance) {
  return luminance > 100 ? 2.655 : 1.855 + 0.4 * std::log10(luminance + 2.3e-5);
}

}  // namespace

std::string shader_math() {
  return kMath;
}

std::string operator_shader(const std::string& name) {
  auto it = bodies().find(name);
  if (it == bodies().end()) return {};
  return std::string(kPrelude) + kMath + kMain + it->second;
}

StepUniforms step_uniforms(const ChainStep& step, const process::GlobalStats& g) {
  StepUniforms u;
  const auto p = [&](const char* key) { return step.params.at(key); };
  const auto has = [&](const char* key) { return step.params.contains(key); };
  const std::string& name = step.op->name;
  if (has("radius")) u.r = static_cast<int>(p("radius"));
  if (has("max_radius")) u.r = static_cast<int>(p("max_radius"));
  auto& k = u.k;
  if (name == "lee" || name == "kuan") {
    k[0] = 1.0 / p("looks");
  } else if (name == "gamma-map") {
    k[0] = p("looks"), k[1] = 1.0 / k[0], k[2] = std::sqrt(2.0) * std::sqrt(k[1]);
  } else if (name == "frost") {
    k[0] = p("deramp");
  } else if (name == "gauss") {
    const double sigma = p("sigma") > 0 ? p("sigma") : (u.r > 0 ? u.r / 2.5 : 1.0);
    u.w = gauss_weights(u.r, sigma);
  } else if (name == "linear") {
    k[0] = g.mean + p("sigmas") * g.stddev;
  } else if (name == "log") {
    const double t_min = std::isnan(p("t_min")) ? g.min : p("t_min");
    const double t_max = std::isnan(p("t_max")) ? g.mean + 3 * g.stddev : p("t_max");
    k[0] = t_min, k[1] = t_max - t_min, k[2] = p("c"), k[3] = std::log1p(p("c"));
  } else if (name == "gamma") {
    k[0] = p("gamma"), k[1] = g.max;
  } else if (name == "rat") {
    k[0] = p("gamma"), k[1] = p("scale") * process::estimated_power_mean(g, p("gamma"));
  } else if (name == "drago") {
    k[0] = p("c"), k[1] = p("m") / std::log1p(p("c")), k[2] = p("b"), k[3] = 1 / g.max;
  } else if (name == "tumblin") {
    const double scale = 1 / g.max;
    const double aa = std::isnan(p("aa")) ? std::max(1e-6, p("c") * g.mean * scale) : p("aa");
    k[0] = p("ad") / 100, k[1] = p("c"), k[2] = scale, k[3] = aa;
    k[4] = tumblin_gamma(aa) / tumblin_gamma(p("ad"));
  } else if (name == "schlick" || name == "ext-schlick") {
    k[0] = std::isnan(p("b")) ? auto_schlick_b(g) : p("b"), k[1] = 1 / g.max;
    if (name == "ext-schlick") k[1] = p("d"), k[2] = p("t"), k[3] = 1 / g.max;
  } else if (name == "reinhard-devlin" || name == "ext-reinhard-devlin") {
    k[0] = reinhard_devlin_exponent(g), k[1] = std::exp(-p("b")), k[2] = p("c");
    k[3] = g.mean / g.max;
    if (name == "reinhard-devlin") {
      k[4] = 1 / g.max;
    } else {
      k[4] = p("d"), k[5] = p("t"), k[6] = 1 / g.max;
    }
  } else if (name == "durand") {
    const double sigma_s = u.r > 0 ? u.r / 2.5 : 1.0, sigma_r = p("sigma_r");
    k[0] = p("k"), k[1] = 1 / g.max, k[2] = sigma_r, k[3] = 4 * sigma_r / (4096 - 1);
    for (int dy = -u.r; dy <= u.r; ++dy) {
      for (int dx = -u.r; dx <= u.r; ++dx) {
        u.w.push_back(std::exp(-0.5 * (dx * dx + dy * dy) / (sigma_s * sigma_s)));
      }
    }
  } else if (name == "chiu") {
    k[0] = p("c"), k[1] = 1 / g.max;
  } else if (name == "retinex") {
    const int big = u.r;
    k[0] = p("p"), k[1] = p("w"), k[2] = p("range");
    k[3] = std::max(1, big / 5), k[4] = std::max(1, big / 2), k[5] = big, k[6] = 1 / g.max;
  } else if (name == "ashikhmin") {
    k[0] = p("c"), k[1] = p("t");
    k[2] = capacity(p("c") * std::max(0.0, g.min) / g.max), k[3] = capacity(p("c"));
    k[4] = 1 / g.max;
  } else if (name == "reinhard") {
    const double mean = g.mean / g.max;
    k[0] = std::isnan(p("c")) ? 0.18 / mean : p("c");
    k[1] = std::isnan(p("w")) ? k[0] : p("w");
    k[2] = std::pow(2.0, p("s")), k[3] = p("t"), k[4] = 1 / g.max;
  }
  if (name == "ext-schlick" || name == "ext-reinhard-devlin" || name == "chiu" ||
      name == "retinex" || name == "ashikhmin" || name == "reinhard") {
    for (int q = 1; q <= u.r; ++q) {
      const auto kernel = gauss_weights(q, q / 2.5);
      u.w.insert(u.w.end(), kernel.begin(), kernel.end());
    }
  }
  assert(u.w.size() <= static_cast<size_t>(kWeights));
  return u;
}

}  // namespace relief::gpuprocess
