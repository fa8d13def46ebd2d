#include "operator_shaders.h"

namespace relief::gpuprocess {
namespace {

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

}  // namespace

// Conversions and global mappings: one sample in, one out.
void add_point_shaders(ShaderBodies& bodies) {
  bodies.insert({
      // Conversions.
      {"intensity-to-amplitude", point("return a >= 0.0LF ? sqrt(a) : double(nan_f());")},
      {"amplitude-to-intensity", point("return a * a;")},
      {"db-to-amplitude", point("return dexp(a / 20.0LF * kLn10);")},
      {"amplitude-to-db", point("return a > 0.0LF ? 20.0LF * dlog10(a) : double(nan_f());")},
      // Global mappings; k as step_uniforms() sets it.
      // Single precision: a / t is correctly rounded in float too (t rounded
      // to float first: within 2 ulp of the CPU's double quotient rounded).
      {"linear",
       "float apply(ivec2 p) {\n"
       "  float a = at(p);\n"
       "  return nodata(a) ? a : clamp(a / float(k[0]), 0.0, 1.0);\n"
       "}\n"},
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
      // Not an operator: the wavelet's step at levels where no scale is left.
      {"identity", point("return a;")},
  });
}

}  // namespace relief::gpuprocess
