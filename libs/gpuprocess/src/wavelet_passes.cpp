#include "wavelet_passes.h"

#include <cmath>

#include "operator_shaders.h"
#include "relief/process/speckle.h"

namespace relief::gpuprocess {
namespace {

constexpr const char* kHeader = R"(#version 450 core
layout(local_size_x = 8, local_size_y = 8) in;
uniform ivec2 origin;
uniform ivec2 extent;
bool outside() {
  return gl_GlobalInvocationID.x >= uint(extent.x) || gl_GlobalInvocationID.y >= uint(extent.y);
}
ivec2 here() { return origin + ivec2(gl_GlobalInvocationID.xy); }
double nan_d() { return packDouble2x32(uvec2(0u, 0x7ff80000u)); }
bool nodata(double v) { return isnan(v); }
)";

// c_0 = ln A where A > 0, nodata elsewhere (dlog, dexp: shader_math()).
const std::string kLogPass = std::string(kHeader) + R"(
layout(binding = 0) uniform sampler2D src;
layout(rg32ui, binding = 0) writeonly uniform uimage2D dst;
)" + R"(
double dlog(double x);
void main() {
  if (outside()) return;
  ivec2 p = here();
  float a = texelFetch(src, p, 0).r;
  // The CPU takes std::log of the float sample: a float logarithm.
  double c = a > 0.0 ? double(float(dlog(double(a)))) : nan_d();
  imageStore(dst, p, uvec4(unpackDouble2x32(c), 0u, 0u));
}
)";

// Rows of one smoothing with hole size `step` (wavelet.cpp smooth).
const std::string kRowsPass = std::string(kHeader) + R"(
layout(binding = 0) uniform usampler2D src;
layout(rgba32ui, binding = 0) writeonly uniform uimage2D dst;
uniform int step;
const double kTaps[5] = double[5](1.0LF / 16, 4.0LF / 16, 6.0LF / 16, 4.0LF / 16, 1.0LF / 16);
void main() {
  if (outside()) return;
  ivec2 p = here();
  precise double s = 0.0LF, w = 0.0LF;
  for (int k = 0; k < 5; ++k) {
    double v = packDouble2x32(texelFetch(src, p + ivec2((k - 2) * step, 0), 0).xy);
    if (nodata(v)) continue;
    s += kTaps[k] * v;
    w += kTaps[k];
  }
  imageStore(dst, p, uvec4(unpackDouble2x32(s), unpackDouble2x32(w)));
}
)";

const std::string kColumnsPass = std::string(kHeader) + R"(
layout(binding = 0) uniform usampler2D src;
layout(rg32ui, binding = 0) writeonly uniform uimage2D dst;
uniform int step;
const double kTaps[5] = double[5](1.0LF / 16, 4.0LF / 16, 6.0LF / 16, 4.0LF / 16, 1.0LF / 16);
void main() {
  if (outside()) return;
  ivec2 p = here();
  precise double s = 0.0LF, w = 0.0LF;
  for (int k = 0; k < 5; ++k) {
    uvec4 t = texelFetch(src, p + ivec2(0, (k - 2) * step), 0);
    s += kTaps[k] * packDouble2x32(t.xy);
    w += kTaps[k] * packDouble2x32(t.zw);
  }
  imageStore(dst, p, uvec4(unpackDouble2x32(w > 0.0LF ? s / w : nan_d()), 0u, 0u));
}
)";

// exp(c_J + sum soft(c_(j-1) - c_j, t_j) + bias); A <= 0 gives 0, nodata stays.
const std::string kFinalPass = std::string(kHeader) + R"(
layout(binding = 0) uniform sampler2D src;
layout(binding = 1) uniform usampler2D c0;
layout(binding = 2) uniform usampler2D c1;
layout(binding = 3) uniform usampler2D c2;
layout(binding = 4) uniform usampler2D c3;
layout(r32f, binding = 0) writeonly uniform image2D dst;
uniform int levels;
uniform double threshold[3];
uniform double bias;
double dexp(double x);
double level(int j, ivec2 p) {
  uvec2 t = j == 0 ? texelFetch(c0, p, 0).xy
          : j == 1 ? texelFetch(c1, p, 0).xy
          : j == 2 ? texelFetch(c2, p, 0).xy : texelFetch(c3, p, 0).xy;
  return packDouble2x32(t);
}
double soft(double w, double t) { return w > t ? w - t : (w < -t ? w + t : 0.0LF); }
void main() {
  if (outside()) return;
  ivec2 p = here();
  float a = texelFetch(src, p, 0).r;
  if (!(a > 0.0)) {
    imageStore(dst, p, vec4(isnan(a) ? a : 0.0, 0.0, 0.0, 0.0));
    return;
  }
  double result = level(levels, p);
  for (int j = 1; j <= levels; ++j) result += soft(level(j - 1, p) - level(j, p), threshold[j - 1]);
  imageStore(dst, p, vec4(float(dexp(result + bias)), 0.0, 0.0, 0.0));
}
)";

GLuint make_texture(GLenum format, int width, int height) {
  GLuint id = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &id);
  glTextureStorage2D(id, 1, format, width, height);
  glTextureParameteri(id, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(id, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  return id;
}

void dispatch(GLuint prog, int origin, int width, int height) {
  glProgramUniform2i(prog, glGetUniformLocation(prog, "origin"), origin, origin);
  glProgramUniform2i(prog, glGetUniformLocation(prog, "extent"), width, height);
  glUseProgram(prog);
  glDispatchCompute(static_cast<GLuint>((width + 7) / 8), static_cast<GLuint>((height + 7) / 8), 1);
  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
}

}  // namespace

WaveletPasses::~WaveletPasses() {
  if (!planes_.empty()) glDeleteTextures(static_cast<GLsizei>(planes_.size()), planes_.data());
  if (rows_) glDeleteTextures(1, &rows_);
}

Result<GLuint> WaveletPasses::program(const std::string& name) {
  if (auto it = programs_.find(name); it != programs_.end()) return it->second.id();
  const std::string& math = shader_math();
  const std::string source = name == "log"    ? kLogPass + math
                             : name == "rows" ? kRowsPass
                             : name == "cols" ? kColumnsPass
                                              : kFinalPass + math;
  GlProgram p = RELIEF_TRY(compile_compute("wavelet " + name, source));
  return programs_.emplace(name, std::move(p)).first->second.id();
}

void WaveletPasses::ensure_planes(int width, int height, size_t levels) {
  if (width != width_ || height != height_) {
    if (!planes_.empty()) glDeleteTextures(static_cast<GLsizei>(planes_.size()), planes_.data());
    if (rows_) glDeleteTextures(1, &rows_);
    planes_.clear();
    rows_ = make_texture(GL_RGBA32UI, width, height);
    width_ = width, height_ = height;
  }
  while (planes_.size() < 4 || planes_.size() < levels + 1) {
    planes_.push_back(make_texture(GL_RG32UI, width, height));
  }
}

Status WaveletPasses::run(const process::Params& params, const GlTexture& in, const GlTexture& out,
                          int origin, int width, int height) {
  const int levels = static_cast<int>(params.at("levels"));
  assert(levels >= 1 && levels <= 3);
  ensure_planes(in.width(), in.height(), static_cast<size_t>(levels));
  const GLuint log_pass = RELIEF_TRY(program("log")), rows = RELIEF_TRY(program("rows"));
  const GLuint cols = RELIEF_TRY(program("cols")), final_pass = RELIEF_TRY(program("final"));
  glBindTextureUnit(0, in.id());
  glBindImageTexture(0, planes_[0], 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RG32UI);
  dispatch(log_pass, origin, width, height);
  for (int j = 1; j <= levels; ++j) {
    const int step = 1 << (j - 1), m = 2 * step;
    const int lost = 2 * ((1 << (j - 1)) - 1);  // what c_(j-1) lost per side
    const int o = origin + lost, w = width - 2 * lost, h = height - 2 * lost;
    glProgramUniform1i(rows, glGetUniformLocation(rows, "step"), step);
    glBindTextureUnit(0, planes_[j - 1]);
    glBindImageTexture(0, rows_, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32UI);
    // Rows lose m columns per side; the columns pass then m rows.
    glProgramUniform2i(rows, glGetUniformLocation(rows, "origin"), o + m, o);
    glProgramUniform2i(rows, glGetUniformLocation(rows, "extent"), w - 2 * m, h);
    glUseProgram(rows);
    glDispatchCompute(static_cast<GLuint>((w - 2 * m + 7) / 8), static_cast<GLuint>((h + 7) / 8),
                      1);
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
    glProgramUniform1i(cols, glGetUniformLocation(cols, "step"), step);
    glBindTextureUnit(0, rows_);
    glBindImageTexture(0, planes_[j], 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RG32UI);
    dispatch(cols, o + m, w - 2 * m, h - 2 * m);
  }
  const process::WaveletShrinkage shrink =
      process::wavelet_shrinkage(params.at("looks"), params.at("k"));
  glProgramUniform1i(final_pass, glGetUniformLocation(final_pass, "levels"), levels);
  glProgramUniform1dv(final_pass, glGetUniformLocation(final_pass, "threshold"), 3,
                      shrink.threshold);
  glProgramUniform1d(final_pass, glGetUniformLocation(final_pass, "bias"), shrink.bias);
  glBindTextureUnit(0, in.id());
  for (int j = 0; j < 4; ++j) glBindTextureUnit(static_cast<GLuint>(1 + j), planes_[j]);
  glBindImageTexture(0, out.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
  const int margin = 2 * ((1 << levels) - 1);
  dispatch(final_pass, origin + margin, width - 2 * margin, height - 2 * margin);
  return {};
}

}  // namespace relief::gpuprocess
