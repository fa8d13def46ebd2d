#pragma once

namespace relief::render {

// Heights: bilinear between the four samples around a point given in interior
// sample coordinates, with texelFetch so every quad sharing a vertex computes
// the same value from the same samples with the same weights.
inline constexpr const char* kTerrainVertexShader = R"(#version 450 core
layout(location = 0) in vec3 rel_position;  // ellipsoid point minus the eye, metres
layout(location = 1) in vec3 up;            // geodetic normal
layout(location = 2) in vec2 uv;            // quad space
layout(location = 3) in uint flags;         // side bits | corner bits << 4

uniform mat4 view_projection;
uniform sampler2D own_heights, parent_heights;
uniform vec4 own_window, parent_window, imagery_window;  // x0, y0, width, height
uniform int border, has_own, has_parent;
uniform uint coarse_sides, coarse_corners;
uniform float exaggeration;
uniform vec2 lat_range;  // north, south, degrees

out vec2 sample_position;
out vec2 imagery_position;
out float height;
out float cos_lat;

float bilinear(sampler2D t, vec2 p) {
  vec2 s = p - 0.5 + float(border);
  vec2 i0 = floor(s);
  vec2 f = s - i0;
  ivec2 size = textureSize(t, 0) - 1;
  ivec2 a = clamp(ivec2(i0), ivec2(0), size), b = min(a + 1, size);
  float top = texelFetch(t, a, 0).r + (texelFetch(t, ivec2(b.x, a.y), 0).r - texelFetch(t, a, 0).r) * f.x;
  float bottom = texelFetch(t, ivec2(a.x, b.y), 0).r +
                 (texelFetch(t, b, 0).r - texelFetch(t, ivec2(a.x, b.y), 0).r) * f.x;
  return top + (bottom - top) * f.y;
}

void main() {
  bool parent = ((flags & 15u) & coarse_sides) != 0u || (((flags >> 4) & 15u) & coarse_corners) != 0u;
  float h = 0.0;
  if (parent) {
    if (has_parent != 0) h = bilinear(parent_heights, parent_window.xy + uv * parent_window.zw);
  } else if (has_own != 0) {
    h = bilinear(own_heights, own_window.xy + uv * own_window.zw);
  }
  sample_position = own_window.xy + uv * own_window.zw;
  imagery_position = imagery_window.xy + uv * imagery_window.zw;
  height = h;
  cos_lat = cos(radians(mix(lat_range.x, lat_range.y, uv.y)));
  gl_Position = view_projection * vec4(rel_position + up * (h * exaggeration), 1.0);
}
)";

inline constexpr const char* kTerrainFragmentShader = R"(#version 450 core
in vec2 sample_position;
in vec2 imagery_position;
in float height;
in float cos_lat;
uniform sampler2D own_heights, imagery;
uniform int border, has_own, has_imagery, imagery_border;
uniform float sample_metres;  // north-south sample spacing, metres
uniform float exaggeration;
out vec4 colour;

float h_at(vec2 p) {
  return has_own != 0 ? textureLod(own_heights, (p + float(border)) / vec2(textureSize(own_heights, 0)), 0.0).r : 0.0;
}

vec3 hypsometric(float h) {
  const float stops[6] = float[](-50.0, 0.0, 300.0, 1000.0, 2000.0, 3500.0);
  const vec3 colours[6] = vec3[](vec3(0.35, 0.55, 0.75), vec3(0.40, 0.62, 0.38), vec3(0.55, 0.70, 0.40),
                                 vec3(0.78, 0.72, 0.50), vec3(0.62, 0.50, 0.40), vec3(0.95, 0.95, 0.95));
  if (h <= stops[0]) return colours[0];
  for (int i = 1; i < 6; ++i) {
    if (h < stops[i]) return mix(colours[i - 1], colours[i], (h - stops[i - 1]) / (stops[i] - stops[i - 1]));
  }
  return colours[5];
}

void main() {
  // Hillshade from the local slope (sun from the north-west, 45 degrees up).
  float dx = (h_at(sample_position + vec2(1, 0)) - h_at(sample_position - vec2(1, 0))) /
             (2.0 * sample_metres * max(cos_lat, 0.01));
  float dy = (h_at(sample_position + vec2(0, 1)) - h_at(sample_position - vec2(0, 1))) / (2.0 * sample_metres);
  vec3 n = normalize(vec3(-dx * exaggeration, dy * exaggeration, 1.0));  // east, north, up (rows run south)
  vec3 sun = normalize(vec3(-1.0, 1.0, 1.414));
  float shade = clamp(dot(n, sun), 0.0, 1.0);
  // Where the imagery has no data (alpha 0) the terrain shows its own colours
  // (imagery colours are premultiplied by alpha).
  vec4 drape = has_imagery != 0
                   ? texture(imagery, (imagery_position + float(imagery_border)) / vec2(textureSize(imagery, 0)))
                   : vec4(0.0);
  vec3 base = hypsometric(height) * (1.0 - drape.a) + drape.rgb;
  float light = mix(0.35 + 0.65 * shade, 0.75 + 0.25 * shade, drape.a);
  colour = vec4(base * light, 1.0);
}
)";

}  // namespace relief::render
