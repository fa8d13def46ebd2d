#include "relief/gpuprocess/composite.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <map>

#include <fmt/format.h>

#include "gl.h"
#include "gl_program.h"
#include "relief/geo/tangent_plane.h"

namespace relief::gpuprocess {

namespace {

// One pass per layer: the layer's sample under each output texel (nearest),
// mapped to a premultiplied colour, then "over" what the layers below left in
// `accum`. Positions in interior samples of the layer's tile.
// Compiled per variant (layer_variant): RGBA, BOTTOM, TOP and VIRIDIS are
// constants, so a variant holds only its own fetches and stores (llvmpipe
// runs both sides of a branch under a mask, a dead side costs as much).
constexpr const char* kLayerPass = R"(
layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 0) uniform sampler2D values;   // R32F, single-band layers
layout(binding = 1) uniform sampler2D colours;  // RGBA8 premultiplied, imagery layers
layout(rgba32f, binding = 0) uniform image2D accum;
layout(rgba8, binding = 1) writeonly uniform image2D result;  // the renderer's array layer
const bool rgba = RGBA != 0;
const bool bottom = BOTTOM != 0;  // the first layer: nothing below, accum not read
const bool top = TOP != 0;        // the last layer: the composite goes to result, accum not written
uniform ivec2 size;      // output texels: interior plus a one-sample border
uniform vec4 window;     // x0, y0, width, height of the composite in the layer's interior
uniform ivec2 first;     // texel of the layer's interior sample (0, 0)
uniform ivec2 interior;  // the layer's interior size; one border sample is readable beyond it
uniform vec2 range;
uniform float opacity;

bool nodata(float v) { return (floatBitsToUint(v) & 0x7fffffffu) > 0x7f800000u; }

// Viridis, a degree-6 polynomial fit (Matt Zucker, CC0).
vec3 viridis(float t) {
  const vec3 c0 = vec3(0.2777273272234177, 0.005407344544966578, 0.3340998053353061);
  const vec3 c1 = vec3(0.1050930431085774, 1.404613529898575, 1.384590162594685);
  const vec3 c2 = vec3(-0.3308618287255563, 0.214847559468213, 0.09509516302823659);
  const vec3 c3 = vec3(-4.634230498983486, -5.799100973351585, -19.33244095627987);
  const vec3 c4 = vec3(6.228269936347081, 14.17993336680509, 56.69055260068105);
  const vec3 c5 = vec3(4.776384997670288, -13.74514537774601, -65.35303263337234);
  const vec3 c6 = vec3(-5.435455855934631, 4.645852612178535, 26.3124352495832);
  return clamp(c0 + t * (c1 + t * (c2 + t * (c3 + t * (c4 + t * (c5 + t * c6))))), 0.0, 1.0);
}

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(p, size))) return;
  vec2 u = (vec2(p) - 0.5) / vec2(size - 2);  // 0..1 over the composite's interior
  ivec2 s = clamp(ivec2(floor(window.xy + u * window.zw)), ivec2(-1), interior);
  vec4 c;
  if (rgba) {
    c = texelFetch(colours, first + s, 0);
  } else {
    float v = texelFetch(values, first + s, 0).r;
    if (nodata(v)) {
      c = vec4(0.0);
    } else {
      float t = clamp((v - range.x) / (range.y - range.x), 0.0, 1.0);
      c = vec4(VIRIDIS != 0 ? viridis(t) : vec3(t), 1.0);
    }
  }
  c *= opacity;
  if (!bottom) c += imageLoad(accum, p) * (1.0 - c.a);
  if (top) {
    imageStore(result, p, clamp(c, 0.0, 1.0));
  } else {
    imageStore(accum, p, c);
  }
}
)";

// The accumulated composite into the renderer's RGBA8 array layer.
constexpr const char* kStorePass = R"(#version 450 core
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) readonly uniform image2D accum;
layout(rgba8, binding = 1) writeonly uniform image2D result;
uniform ivec2 size;
void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(p, size))) return;
  imageStore(result, p, clamp(imageLoad(accum, p), 0.0, 1.0));
}
)";

// A lens: the samples of `lens_values` inside the circle replace those of
// `values` (both the tile's interior plus a one-sample border). Positions
// relative to the lens centre, in degrees, then metres on the local tangent
// plane (lenses are small against the Earth).
constexpr const char* kLensPass = R"(#version 450 core
layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 0) uniform sampler2D lens_values;
layout(r32f, binding = 0) uniform image2D values;
uniform ivec2 size;
uniform ivec2 lens_first;  // texel of the lens result's (0, 0)
uniform vec2 base;         // texel (0, 0) minus the centre, degrees (lon, lat)
uniform vec2 step_deg;     // from one texel to the next (lon, lat: negative, rows run south)
uniform vec2 metres;       // per degree of lon, lat at the centre
uniform float radius;
void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(p, size))) return;
  vec2 d = (base + vec2(p) * step_deg) * metres;
  if (dot(d, d) <= radius * radius) {
    imageStore(values, p, texelFetch(lens_values, lens_first + p, 0));
  }
}
)";

constexpr double kMetresPerDegree = geo::kTangentMetresPerDegree;  // as the CPU's lens distance

struct Texture2D {
  GLuint id = 0;
  int width = 0, height = 0;
  GLenum format = 0;
  Texture2D() = default;
  Texture2D(const Texture2D&) = delete;
  Texture2D& operator=(const Texture2D&) = delete;
  ~Texture2D() {
    if (id) glDeleteTextures(1, &id);
  }
  void ensure(GLenum internal_format, int w, int h) {
    if (id && width == w && height == h && format == internal_format) return;
    if (id) glDeleteTextures(1, &id);
    glCreateTextures(GL_TEXTURE_2D, 1, &id);
    glTextureStorage2D(id, 1, internal_format, w, h);
    glTextureParameteri(id, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(id, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    width = w, height = h, format = internal_format;
  }
};

GLuint groups(int n) {
  return static_cast<GLuint>((n + 7) / 8);
}

}  // namespace

bool lens_touches(const CompositeLens& lens, const geo::GeoBox& box) {
  const double dlat = lens.radius_m / kMetresPerDegree;
  const double dlon = dlat / std::max(std::cos(lens.lat * 3.14159265358979323846 / 180), 1e-6);
  // One sample's margin is the caller's: boxes here include the kept border.
  return box.intersects({lens.lon - dlon, lens.lat - dlat, lens.lon + dlon, lens.lat + dlat});
}

Result<ColorMap> parse_colormap(const std::string& name) {
  if (name == "grey" || name == "gray") return ColorMap::grey;
  if (name == "viridis") return ColorMap::viridis;
  return fail(fmt::format("unknown colour map '{}' (grey, viridis)", name));
}

const char* to_string(ColorMap map) {
  return map == ColorMap::viridis ? "viridis" : "grey";
}

namespace {

// viridis() of kLayerPass in float, evaluated as written (no fused
// multiply-adds: the build targets no FMA).
void viridis_cpu(float t, float out[3]) {
  static constexpr float c[7][3] = {
      {0.2777273272234177f, 0.005407344544966578f, 0.3340998053353061f},
      {0.1050930431085774f, 1.404613529898575f, 1.384590162594685f},
      {-0.3308618287255563f, 0.214847559468213f, 0.09509516302823659f},
      {-4.634230498983486f, -5.799100973351585f, -19.33244095627987f},
      {6.228269936347081f, 14.17993336680509f, 56.69055260068105f},
      {4.776384997670288f, -13.74514537774601f, -65.35303263337234f},
      {-5.435455855934631f, 4.645852612178535f, 26.3124352495832f}};
  for (int k = 0; k < 3; ++k) {
    float v = c[6][k];
    for (int i = 5; i >= 0; --i) v = c[i][k] + t * v;
    out[k] = std::clamp(v, 0.0f, 1.0f);
  }
}

// A unorm8 channel as GL stores it: round(clamp(v) * 255), to nearest even
// (adding and taking away 1.5 * 2^23 rounds a float below 2^22 to an
// integer: no call to lrintf per channel).
uint8_t unorm8(float v) {
  constexpr float kRound = 12582912.0f;
  return static_cast<uint8_t>((std::clamp(v, 0.0f, 1.0f) * 255.0f + kRound) - kRound);
}

}  // namespace

tiles::Raster map_colours_cpu(const tiles::Raster& values, float range_min, float range_max,
                              ColorMap map, float opacity) {
  assert(values.type() == tiles::SampleType::Float32 && values.bands() == 1);
  tiles::Raster out(tiles::SampleType::UInt8, 4, values.width(), values.height());
  const auto src = values.f32();
  const auto dst = out.u8();
  const float span = range_max - range_min;
  const uint8_t alpha = unorm8(opacity);
  for (size_t i = 0; i < src.size(); ++i) {
    const float v = src[i];
    uint8_t* p = &dst[4 * i];
    if (std::isnan(v)) {
      p[0] = p[1] = p[2] = p[3] = 0;
      continue;
    }
    const float t = std::clamp((v - range_min) / span, 0.0f, 1.0f);
    if (map == ColorMap::viridis) {
      float rgb[3];
      viridis_cpu(t, rgb);
      for (int k = 0; k < 3; ++k) p[k] = unorm8(rgb[k] * opacity);
    } else {
      p[0] = p[1] = p[2] = unorm8(t * opacity);
    }
    p[3] = alpha;
  }
  return out;
}

struct Compositor::Impl {
  std::map<int, GlProgram> layer_passes;  // by layer_variant()
  GlProgram store_pass, lens_pass;
  Texture2D accum, colours, values;

  // The layer pass for an RGBA layer or not, the bottom one or not, the top
  // one or not, through viridis or grey; compiled on first use.
  Result<GLuint> layer_pass(bool rgba, bool bottom, bool top, bool viridis) {
    const int variant = (rgba ? 1 : 0) | (bottom ? 2 : 0) | (top ? 4 : 0) | (viridis ? 8 : 0);
    if (auto it = layer_passes.find(variant); it != layer_passes.end()) return it->second.id();
    const std::string source = fmt::format(
        "#version 450 core\n#define RGBA {}\n#define BOTTOM {}\n#define TOP {}\n"
        "#define VIRIDIS {}\n{}",
        rgba ? 1 : 0, bottom ? 1 : 0, top ? 1 : 0, viridis ? 1 : 0, kLayerPass);
    GlProgram p = RELIEF_TRY(compile_compute("composite layer", source));
    return layer_passes.emplace(variant, std::move(p)).first->second.id();
  }

  // The layer's values with its lenses merged in, in `values`; returns the
  // texel of interior sample (0, 0) there.
  Result<int> merge_lenses(GpuProcessor& gpu, const CompositeLayer& l, const GpuTile& global) {
    const tiles::Raster& t = *l.tile;
    values.ensure(GL_R32F, global.width, global.height);
    glCopyImageSubData(global.texture, GL_TEXTURE_2D, 0, global.offset, global.offset, 0, values.id,
                       GL_TEXTURE_2D, 0, 0, 0, 0, global.width, global.height, 1);
    const int iw = t.width() - 2 * l.border, ih = t.height() - 2 * l.border;
    const double dx = l.bounds.width() / iw, dy = l.bounds.height() / ih;
    const GLuint lp = lens_pass.id();
    for (const CompositeLens& lens : l.lenses) {
      const geo::GeoBox kept{l.bounds.west - dx, l.bounds.south - dy, l.bounds.east + dx,
                             l.bounds.north + dy};
      if (!lens_touches(lens, kept)) continue;
      const GpuTile g = RELIEF_TRY(gpu.run_on_gpu(*lens.chain, t, l.border, l.stats));
      glUseProgram(lp);
      auto u = [lp](const char* name) { return glGetUniformLocation(lp, name); };
      glProgramUniform2i(lp, u("size"), global.width, global.height);
      glProgramUniform2i(lp, u("lens_first"), g.offset, g.offset);
      // Texel (0, 0) is interior sample (-1, -1), whose centre is half a sample out.
      glProgramUniform2f(lp, u("base"), static_cast<float>(l.bounds.west - 0.5 * dx - lens.lon),
                         static_cast<float>(l.bounds.north + 0.5 * dy - lens.lat));
      glProgramUniform2f(lp, u("step_deg"), static_cast<float>(dx), static_cast<float>(-dy));
      const double m = kMetresPerDegree;
      glProgramUniform2f(lp, u("metres"),
                         static_cast<float>(m * std::cos(lens.lat * 3.14159265358979323846 / 180)),
                         static_cast<float>(m));
      glProgramUniform1f(lp, u("radius"), static_cast<float>(lens.radius_m));
      glBindTextureUnit(0, g.texture);
      glBindImageTexture(0, values.id, 0, GL_FALSE, 0, GL_READ_WRITE, GL_R32F);
      glDispatchCompute(groups(global.width), groups(global.height), 1);
      glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
                      GL_TEXTURE_UPDATE_BARRIER_BIT);
    }
    glBindTextureUnit(0, values.id);
    return 1;
  }
};

Compositor::Compositor(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Compositor::~Compositor() = default;

Result<std::unique_ptr<Compositor>> Compositor::create() {
  auto impl = std::make_unique<Impl>();
  RELIEF_TRY(impl->layer_pass(false, true, true, false));  // the shader compiles
  impl->store_pass = RELIEF_TRY(compile_compute("composite store", kStorePass));
  impl->lens_pass = RELIEF_TRY(compile_compute("composite lens", kLensPass));
  return std::unique_ptr<Compositor>(new Compositor(std::move(impl)));
}

Status Compositor::composite(GpuProcessor& gpu, std::span<const CompositeLayer> layers,
                             uint32_t array_texture, int array_layer, int width, int height) {
  Impl& im = *impl_;
  im.accum.ensure(GL_RGBA32F, width, height);
  // The first layer's pass starts the composite and the last one's stores it
  // (one pass for one layer: no clear, no store pass).
  if (layers.empty()) {
    const float clear[4] = {0, 0, 0, 0};
    glClearTexImage(im.accum.id, 0, GL_RGBA, GL_FLOAT, clear);
  }
  for (size_t i = 0; i < layers.size(); ++i) {
    const CompositeLayer& l = layers[i];
    const tiles::Raster& t = *l.tile;
    const int iw = t.width() - 2 * l.border, ih = t.height() - 2 * l.border;
    const bool rgba = t.type() == tiles::SampleType::UInt8;
    int first = l.border;
    if (rgba) {
      im.colours.ensure(GL_RGBA8, t.width(), t.height());
      glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
      glTextureSubImage2D(im.colours.id, 0, 0, 0, t.width(), t.height(), GL_RGBA, GL_UNSIGNED_BYTE,
                          t.u8().data());
      glBindTextureUnit(1, im.colours.id);
    } else {
      static const OperatorChain kNone;
      const GpuTile g =
          RELIEF_TRY(gpu.run_on_gpu(l.chain ? *l.chain : kNone, t, l.border, l.stats));
      first = g.offset + 1;
      glBindTextureUnit(0, g.texture);
      if (!l.lenses.empty()) first = RELIEF_TRY(im.merge_lenses(gpu, l, g));
    }
    const GLuint lp = RELIEF_TRY(
        im.layer_pass(rgba, i == 0, i + 1 == layers.size(), l.colormap == ColorMap::viridis));
    auto uniform = [lp](const char* name) { return glGetUniformLocation(lp, name); };
    glUseProgram(lp);
    glProgramUniform2i(lp, uniform("size"), width, height);
    glProgramUniform4f(lp, uniform("window"), static_cast<float>(l.window[0]),
                       static_cast<float>(l.window[1]), static_cast<float>(l.window[2]),
                       static_cast<float>(l.window[3]));
    glProgramUniform2i(lp, uniform("first"), first, first);
    glProgramUniform2i(lp, uniform("interior"), iw, ih);
    glProgramUniform2f(lp, uniform("range"), l.range_min, l.range_max);
    glProgramUniform1f(lp, uniform("opacity"), l.opacity);
    glBindImageTexture(0, im.accum.id, 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
    glBindImageTexture(1, array_texture, 0, GL_FALSE, array_layer, GL_WRITE_ONLY, GL_RGBA8);
    glDispatchCompute(groups(width), groups(height), 1);
    // The next layer reads what this one stored; the processor reuses its textures.
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
                    GL_TEXTURE_UPDATE_BARRIER_BIT);
  }
  if (layers.empty()) {  // nothing drawn: transparent
    const GLuint sp = im.store_pass.id();
    glUseProgram(sp);
    glProgramUniform2i(sp, glGetUniformLocation(sp, "size"), width, height);
    glBindImageTexture(0, im.accum.id, 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
    glBindImageTexture(1, array_texture, 0, GL_FALSE, array_layer, GL_WRITE_ONLY, GL_RGBA8);
    glDispatchCompute(groups(width), groups(height), 1);
  }
  // The terrain shader samples the result.
  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
  glUseProgram(0);
  if (const GLenum e = glGetError(); e != GL_NO_ERROR) {
    return fail(fmt::format("compositing texture layers: GL error 0x{:x}", e));
  }
  return {};
}

}  // namespace relief::gpuprocess
