#pragma once
// GLSL of the terrain: every vertex built on the GPU from quad-space (u, v),
// its quad's record (quad_records.h) and the height sampled from the quad's
// elevation tile; nothing per vertex is computed on the CPU.

#include <string>

namespace relief::render {

// Positions. A vertex is its anchor (a corner known in double on the CPU,
// minus the eye, as float) plus its offset from the anchor computed in float
// with differences of angles (sin and 1 - cos = 2 sin^2(x/2) of the angle
// differences): errors stay relative to the quad's size at any distance from
// the origin. The anchor is the corner at or north-west of the vertex on the
// lattice of the coarsest quad sharing the vertex (the parent's for vertices on
// a side or corner shared with a coarser quad), and the offset is an exact
// multiple of that lattice's spacing: every quad sharing a vertex computes it
// from the same floats with the same operations, so shared vertices are
// bit-identical.
//
// Heights: bilinear between the four samples around a point given in interior
// sample coordinates, with texelFetch so every quad sharing a vertex computes
// the same value from the same samples with the same weights.
inline constexpr const char* kTerrainVertexShader = R"(#version 450 core
layout(location = 0) in vec2 uv;          // quad space
layout(location = 1) in uint flags;       // side bits | corner bits << 4
layout(location = 2) in uint quad_index;  // per draw (instanced: the draw's base instance)

// The quad's record (quad_records.h), 22 texels of a buffer texture:
// anchor[8] (xyz: corner minus the eye, metres; w: prime vertical radius
// there), trig[8] (cos lat, sin lat, cos lon, sin lon of the corner), own,
// parent and imagery windows (x0, y0, width, height), size (width, height in
// degrees, north, south latitude), slots (layers of own heights, parent
// heights, imagery; bits), shade (north-south sample spacing, metres). A
// buffer texture rather than a storage buffer: llvmpipe gathers its texels
// eight vertices at a time.
uniform samplerBuffer records;
vec4 record(int i) { return texelFetch(records, int(quad_index) * 22 + i); }
// The texels that do not depend on the vertex's corner come as attributes
// of the quad's draw instead (the records' buffer bound per instance, each
// draw's base instance its quad): llvmpipe loads an attribute, where a
// texel goes through its sampler (a third of the shader's fetches).
layout(location = 3) in vec4 own_window;      // texel 16
layout(location = 4) in vec4 parent_window;   // 17
layout(location = 5) in vec4 imagery_window;  // 18
layout(location = 6) in vec4 quad_size;       // 19
layout(location = 7) in uvec4 slots;          // 20 (integer: the bits as they are)
layout(location = 8) in float spacing;        // 21.x

uniform mat4 view_projection;
uniform sampler2DArray heights;
uniform int border;
uniform float exaggeration;

out vec2 sample_position;
out vec2 imagery_position;
out float height;
out float cos_lat;
flat out ivec2 layers;  // own heights, imagery
flat out uint has;      // 1: own heights, 4: imagery
flat out float sample_metres;
out vec3 captured_position;  // tests: relative to the eye, with the height

const float kA = 6378137.0, kE2 = 6.69437999014e-3, kDeg = 0.017453292519943295;

// sin with a small relative error for small angles too (GLSL's sin promises
// an absolute error only).
float sin_rel(float x) {
  if (abs(x) > 0.25) return sin(x);
  float x2 = x * x;
  return x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0))));
}

float bilinear(int layer, vec2 p) {
  vec2 s = p - 0.5 + float(border);
  vec2 i0 = floor(s);
  vec2 f = s - i0;
  ivec2 size = textureSize(heights, 0).xy - 1;
  ivec2 a = clamp(ivec2(i0), ivec2(0), size), b = min(a + 1, size);
  float t00 = texelFetch(heights, ivec3(a, layer), 0).r;
  float t10 = texelFetch(heights, ivec3(b.x, a.y, layer), 0).r;
  float t01 = texelFetch(heights, ivec3(a.x, b.y, layer), 0).r;
  float t11 = texelFetch(heights, ivec3(b, layer), 0).r;
  float top = t00 + (t10 - t00) * f.x;
  float bottom = t01 + (t11 - t01) * f.x;
  return top + (bottom - top) * f.y;
}

void main() {
  uint bits = slots.w;
  uint coarse_sides = (bits >> 4) & 15u, coarse_corners = (bits >> 8) & 15u;
  bool parent = ((flags & 15u) & coarse_sides) != 0u || (((flags >> 4) & 15u) & coarse_corners) != 0u;
  // Heights: the parent data where a quad touching the vertex draws coarser
  // data (lod::SelectedQuad::parent_data_sides; the same bits but for sparse depth).
  uint data_sides = (bits >> 14) & 15u, data_corners = (bits >> 18) & 15u;
  bool parent_data = ((flags & 15u) & data_sides) != 0u || (((flags >> 4) & 15u) & data_corners) != 0u;

  // The anchor and the offset from it, in degrees (exact).
  vec2 p = uv;
  float scale = 1.0;
  int first = 0;
  if (parent) {
    p = (vec2(float((bits >> 12) & 1u), float((bits >> 13) & 1u)) + uv) * 0.5;
    scale = 2.0;
    first = 4;
  }
  ivec2 a = ivec2(p.x == 1.0 ? 1 : 0, p.y == 1.0 ? 1 : 0);
  int corner = first + a.y * 2 + a.x;
  vec2 d = p - vec2(a);
  float lam = d.x * (scale * quad_size.x) * kDeg;
  float phi = -(d.y * (scale * quad_size.y)) * kDeg;

  vec4 anchor = record(corner);
  vec4 t = record(8 + corner);
  float cpa = t.x, spa = t.y, cla = t.z, sla = t.w;
  float s_l = sin_rel(lam), h_l = sin_rel(0.5 * lam), s_p = sin_rel(phi), h_p = sin_rel(0.5 * phi);
  float vers_l = 2.0 * h_l * h_l, vers_p = 2.0 * h_p * h_p;  // 1 - cos
  float dcp = -cpa * vers_p - spa * s_p;  // cos lat - cos lat(anchor)
  float dsp = -spa * vers_p + cpa * s_p;
  float dcl = -cla * vers_l - sla * s_l;
  float dsl = -sla * vers_l + cla * s_l;
  float cp = cpa + dcp, sp = spa + dsp, cl = cla + dcl, sl = sla + dsl;
  // N - N(anchor) with N = a / sqrt(1 - e2 sin^2 lat), without cancellation.
  float wa = 1.0 - kE2 * spa * spa, dw = kE2 * dsp * (2.0 * spa + dsp);
  float sw = sqrt(wa - dw), swa = sqrt(wa);
  float dn = kA * dw / (sw * swa * (sw + swa));
  float na = anchor.w;
  float dr = dn * cp + na * dcp;  // N cos lat - its value at the anchor
  vec3 offset = vec3(dr * cl + na * cpa * dcl, dr * sl + na * cpa * dsl,
                     (1.0 - kE2) * (dn * sp + na * dsp));
  vec3 up = vec3(cp * cl, cp * sl, sp);

  float h = 0.0;
  if (parent_data) {
    if ((bits & 2u) != 0u) h = bilinear(int(slots.y), parent_window.xy + uv * parent_window.zw);
  } else if ((bits & 1u) != 0u) {
    h = bilinear(int(slots.x), own_window.xy + uv * own_window.zw);
  }
  sample_position = own_window.xy + uv * own_window.zw;
  imagery_position = imagery_window.xy + uv * imagery_window.zw;
  height = h;
  cos_lat = cp;  // of the vertex's latitude, made above without a cosine
  layers = ivec2(slots.xz);
  has = bits & 5u;
  sample_metres = spacing;
  vec3 position = anchor.xyz + offset + up * (h * exaggeration);
  captured_position = position;
  gl_Position = view_projection * vec4(position, 1.0);
}
)";

// Colours: hypsometric tints times a hillshade, or the imagery (or texture
// layers' composite) draped. DRAPED 0 (fragment_shader(false)) leaves the
// imagery out for scenes without any: llvmpipe runs both sides of a branch
// for a whole block of pixels, so the derivatives and the sampling would
// cost every pixel (a fifth of the shader) for nothing.
inline constexpr const char* kTerrainFragmentShader = R"(#version 450 core
#ifndef DRAPED
#define DRAPED 1
#endif
in vec2 sample_position;
in vec2 imagery_position;
in float height;
in float cos_lat;
flat in ivec2 layers;
flat in uint has;
flat in float sample_metres;
uniform sampler2DArray slopes, imagery;
uniform int border, imagery_border;
uniform float exaggeration;
out vec4 colour;

// Piecewise linear between the stops, without branches: each segment moves
// the colour from the previous stop's to its own by how far the height has
// gone through it (0 before it, 1 past it).
vec3 hypsometric(float h) {
  const float stops[6] = float[](-50.0, 0.0, 300.0, 1000.0, 2000.0, 3500.0);
  const vec3 colours[6] = vec3[](vec3(0.35, 0.55, 0.75), vec3(0.40, 0.62, 0.38), vec3(0.55, 0.70, 0.40),
                                 vec3(0.78, 0.72, 0.50), vec3(0.62, 0.50, 0.40), vec3(0.95, 0.95, 0.95));
  vec3 c = colours[0];
  for (int i = 1; i < 6; ++i) {
    c = mix(c, colours[i], clamp((h - stops[i - 1]) / (stops[i] - stops[i - 1]), 0.0, 1.0));
  }
  return c;
}

void main() {
  // Hillshade from the local slope (sun from the north-west, 45 degrees up):
  // the height differences across the sample, east - west and south - north,
  // made once per tile (height_slopes.h), one fetch.
  vec2 d = vec2(0.0);
  if ((has & 1u) != 0u) {
    d = textureLod(slopes, vec3((sample_position + float(border)) / vec2(textureSize(slopes, 0).xy), float(layers.x)), 0.0).rg;
  }
  float dx = d.x / (2.0 * sample_metres * max(cos_lat, 0.01));
  float dy = d.y / (2.0 * sample_metres);
  vec3 n = normalize(vec3(-dx * exaggeration, dy * exaggeration, 1.0));  // east, north, up (rows run south)
  vec3 sun = normalize(vec3(-1.0, 1.0, 1.414));
  float shade = clamp(dot(n, sun), 0.0, 1.0);
  vec4 drape = vec4(0.0);
#if DRAPED
  // Where the imagery has no data (alpha 0) the terrain shows its own colours
  // (imagery colours are premultiplied by alpha). Derivatives taken in uniform
  // control, the texture read only where there is imagery.
  vec2 st = (imagery_position + float(imagery_border)) / vec2(textureSize(imagery, 0).xy);
  vec2 st_dx = dFdx(st), st_dy = dFdy(st);
  if ((has & 4u) != 0u) drape = textureGrad(imagery, vec3(st, float(layers.y)), st_dx, st_dy);
#endif
  vec3 base = hypsometric(height) * (1.0 - drape.a) + drape.rgb;
  float light = mix(0.35 + 0.65 * shade, 0.75 + 0.25 * shade, drape.a);
  colour = vec4(base * light, 1.0);
}
)";

// The fragment shader with (`draped`) or without the imagery.
inline std::string fragment_shader(bool draped) {
  std::string source = kTerrainFragmentShader;
  if (!draped) source.insert(source.find('\n') + 1, "#define DRAPED 0\n");
  return source;
}

}  // namespace relief::render
