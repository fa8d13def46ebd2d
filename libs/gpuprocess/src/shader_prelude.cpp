#include "operator_shaders.h"

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

}  // namespace

std::string shader_math() {
  return kMath;
}
std::string shader_frame() {
  return kPrelude;
}
std::string shader_main() {
  return kMain;
}

}  // namespace relief::gpuprocess
