#include "relief/gpuprocess/gpu_processor.h"

#include <map>

#include <fmt/format.h>

#include "gl.h"
#include "gl_program.h"
#include "operator_shaders.h"
#include "wavelet_passes.h"

namespace relief::gpuprocess {

bool runs_on_gpu(const std::string& name) {
  return name == "wavelet" || !operator_shader(name).empty();  // wavelet: wavelet_passes.h
}

struct GpuProcessor::Impl {
  std::map<std::string, GlProgram> programs;  // compiled on first use
  GlTexture ping, pong;                       // the size of the last tile
  GlTexture rows;                             // window row sums (RGBA32F), as ping
  std::map<int, GlProgram> rows_programs;     // window_rows_shader(r), on first use
  WaveletPasses wavelet;

  // Operator `name`'s program; for a constant_radius() operator, radius r's.
  Result<GLuint> program(const std::string& name, int r) {
    const bool constant = constant_radius(name);
    const std::string key = constant ? fmt::format("{} r={}", name, r) : name;
    if (auto it = programs.find(key); it != programs.end()) return it->second.id();
    GlProgram p = RELIEF_TRY(compile_compute(key, operator_shader(name, constant ? r : -1)));
    return programs.emplace(key, std::move(p)).first->second.id();
  }

  void ensure_textures(int width, int height) {
    if (ping.width() == width && ping.height() == height) return;
    ping = GlTexture(width, height);
    pong = GlTexture(width, height);
    rows = GlTexture();
  }

  // The rows pass of a window-statistics step (uses_window_rows) of radius r
  // whose output starts `origin` texels in and is width x height: the rows
  // r above and below it too. Left bound to texture unit 1.
  Status window_rows(int r, const GlTexture& in, int origin, int width, int height) {
    auto it = rows_programs.find(r);
    if (it == rows_programs.end()) {
      GlProgram p = RELIEF_TRY(compile_compute("window rows", window_rows_shader(r)));
      it = rows_programs.emplace(r, std::move(p)).first;
    }
    if (!rows.id()) rows = GlTexture(in.width(), in.height(), GL_RGBA32F);
    const GLuint prog = it->second.id();
    glUseProgram(prog);
    glProgramUniform2i(prog, glGetUniformLocation(prog, "origin"), origin, origin - r);
    glProgramUniform2i(prog, glGetUniformLocation(prog, "extent"), width, height + 2 * r);
    glBindTextureUnit(0, in.id());
    glBindImageTexture(1, rows.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    constexpr int kGroup = 8, kRun = 8;  // the shader's local size, outputs per invocation
    glDispatchCompute(static_cast<GLuint>((width + kGroup * kRun - 1) / (kGroup * kRun)),
                      static_cast<GLuint>((height + 2 * r + kGroup - 1) / kGroup), 1);
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);
    glBindTextureUnit(1, rows.id());
    return {};
  }

  // One pass: reads `in`, writes the `extent` texels of `out` from `origin` on.
  // `run`: outputs per invocation down a column (window-rows operators: 8).
  void dispatch(GLuint prog, const StepUniforms& u, const GlTexture& in, const GlTexture& out,
                int origin, int width, int height, int run) {
    glUseProgram(prog);
    glProgramUniform2i(prog, glGetUniformLocation(prog, "origin"), origin, origin);
    glProgramUniform2i(prog, glGetUniformLocation(prog, "extent"), width, height);
    if (GLint loc = glGetUniformLocation(prog, "r"); loc >= 0) glProgramUniform1i(prog, loc, u.r);
    if (GLint loc = glGetUniformLocation(prog, "k"); loc >= 0) {
      glProgramUniform1dv(prog, loc, kConstants, u.k.data());
    }
    if (GLint loc = glGetUniformLocation(prog, "w"); loc >= 0 && !u.w.empty()) {
      glProgramUniform1dv(prog, loc, static_cast<GLsizei>(u.w.size()), u.w.data());
    }
    glBindTextureUnit(0, in.id());
    glBindImageTexture(0, out.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
    constexpr int kGroup = 8;  // local_size of the shaders
    glDispatchCompute(static_cast<GLuint>((width + kGroup - 1) / kGroup),
                      static_cast<GLuint>((height + kGroup * run - 1) / (kGroup * run)), 1);
    // The next pass samples what this one stored.
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
  }
};

GpuProcessor::GpuProcessor(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
GpuProcessor::~GpuProcessor() = default;

Result<std::unique_ptr<GpuProcessor>> GpuProcessor::create() {
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  if (major * 10 + minor < 45) {
    return fail(fmt::format("GPU processing needs OpenGL 4.5 (the current context has {}.{})",
                            major, minor));
  }
  return std::unique_ptr<GpuProcessor>(new GpuProcessor(std::make_unique<Impl>()));
}

Result<tiles::Raster> GpuProcessor::run(const OperatorChain& chain, const tiles::Raster& tile,
                                        int border, const process::GlobalStats* stats) {
  const GpuTile t = RELIEF_TRY(run_on_gpu(chain, tile, border, stats));
  tiles::Raster result(tiles::SampleType::Float32, 1, t.width, t.height);
  const auto bytes = static_cast<GLsizei>(result.byte_size());
  glGetTextureSubImage(t.texture, 0, t.offset, t.offset, 0, t.width, t.height, 1, GL_RED, GL_FLOAT,
                       bytes, result.f32().data());
  if (const GLenum e = glGetError(); e != GL_NO_ERROR) {
    return fail(fmt::format("GPU processing: GL error 0x{:x}", e));
  }
  return result;
}

Result<GpuTile> GpuProcessor::run_on_gpu(const OperatorChain& chain, const tiles::Raster& tile,
                                         int border, const process::GlobalStats* stats) {
  assert(tile.type() == tiles::SampleType::Float32 && tile.bands() == 1);
  RELIEF_CHECK(check_fits(chain, border));
  RELIEF_CHECK(check_stats(chain, stats));
  for (const auto& s : chain.steps) {
    if (!runs_on_gpu(s.op->name)) {
      return fail(
          fmt::format("{}: no GPU implementation yet (docs/gpu-processing.md)", s.op->name));
    }
  }
  const int w = tile.width(), h = tile.height();
  Impl& im = *impl_;
  im.ensure_textures(w, h);
  glTextureSubImage2D(im.ping.id(), 0, 0, 0, w, h, GL_RED, GL_FLOAT, tile.f32().data());
  const process::GlobalStats no_stats;
  const GlTexture* in = &im.ping;
  const GlTexture* out = &im.pong;
  int consumed = 0;  // border used by the steps so far
  for (const auto& s : chain.steps) {
    const int m = process::margin_of(*s.op, s.params);
    if (s.op->name == "wavelet" && m > 0) {
      RELIEF_CHECK(
          im.wavelet.run(s.params, *in, *out, consumed, w - 2 * consumed, h - 2 * consumed));
    } else {
      // A wavelet without a scale left (a coarse level) is the identity, as on the CPU.
      const std::string name = s.op->name == "wavelet" ? "identity" : s.op->name;
      const StepUniforms u = step_uniforms(s, stats ? *stats : no_stats);
      const GLuint prog = RELIEF_TRY(im.program(name, u.r));
      const int o = consumed + m, ow = w - 2 * o, oh = h - 2 * o;
      if (uses_window_rows(name)) RELIEF_CHECK(im.window_rows(u.r, *in, o, ow, oh));
      im.dispatch(prog, u, *in, *out, o, ow, oh, uses_window_rows(name) ? 8 : 1);
    }
    consumed += m;
    std::swap(in, out);
  }
  if (const GLenum e = glGetError(); e != GL_NO_ERROR) {
    return fail(fmt::format("GPU processing: GL error 0x{:x}", e));
  }
  return GpuTile{in->id(), border - 1, w - 2 * (border - 1), h - 2 * (border - 1)};
}

}  // namespace relief::gpuprocess
