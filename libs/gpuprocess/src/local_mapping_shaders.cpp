#include "operator_shaders.h"

namespace relief::gpuprocess {
namespace {

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
      float v = at(p + ivec2(dx, dy));  // selects, not branches (kWindowStats)
      double wv = nodata(v) ? 0.0LF : w[o + dy + q];
      cs += wv * (nodata(v) ? 0.0LF : double(v));
      cw += wv;
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
      float u = at(p + ivec2(dx, dy));  // selects, not branches (kWindowStats)
      double l = nodata(u) ? centre : log_amplitude(u);
      double wt = nodata(u) ? 0.0LF : w[s] * range_weight(l - centre);
      sum += wt * l;
      weight += wt;
    }
  }
  double base = sum / weight;
  return float(clamp01(dexp((k[0] * base + centre - base) * kLn10)));
}
)";

}  // namespace

// The local mappings of tone_mapping_local.cpp and durand.cpp.
void add_local_mapping_shaders(ShaderBodies& bodies) {
  bodies.insert({
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
      {"durand", kDurand},
  });
}

}  // namespace relief::gpuprocess
