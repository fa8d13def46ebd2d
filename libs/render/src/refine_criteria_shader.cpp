#include "refine_criteria_shader.h"

namespace relief::render {

// One invocation per four diamond slots of one quad, packed as four bytes of
// one uint: lod::CriterionClass of the criterion refine_criterion.cpp's
// pixels() computes exactly, in the same order of operations (its shortcuts
// only settle which side of the threshold a value is on): the diamond's ball
// from the grid's sines and cosines (angle sums), its box, then
// screen_error.cpp's vertical_error_parts() with the area's normals.
const char* const kRefineCriteriaShader = R"(#version 450 core
layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer Errors { uint errors[]; };
// sin, cos of i cells (i = 0 .. 2n); cos, sin of each class's spread; the
// prime vertical radius of each row.
layout(std430, binding = 1) readonly buffer Grid { double grid[]; };
layout(std430, binding = 2) readonly buffer Sides { float sides[]; };
layout(std430, binding = 3) writeonly buffer Classes { uint classes[]; };

uniform dvec3 eye, view_right, view_up, view_forward;
uniform double pixels_per_radian, corner, threshold, band;
uniform double west_sin, west_cos, north_sin, north_cos, cell, level_error;
uniform double arc, rounding, e2;
uniform int n, class_count, has_errors, slot_count, spreads_at, normals_at;
// The first slot of each class, and the end of the last (a buffer: a
// uniform array indexed by a variable, llvmpipe copies whole per invocation).
layout(std430, binding = 4) readonly buffer ClassOffsets { int offsets[]; };
uniform int side_first[4], side_count[4];

const double kDegree = 3.14159265358979323846LF / 180.0LF;
const double kHuge = 1.0e300LF;

// The largest value of a side's table in [a, b], clamped to the side.
double side_max(int side, int a, int b) {
  a = max(a, 0);
  b = min(b, side_count[side] - 1);
  float m = 0.0;
  for (int i = a; i <= b; ++i) m = max(m, sides[side_first[side] + i]);
  return double(m);
}

// The largest |sin| and |cos| of the angle between the view direction and
// the normals within `spread` of `up` (screen_error.cpp's angle_bounds).
void angle_bounds(dvec3 up, double cos_spread, double sin_spread, out double s, out double c) {
  const double cos_centre = clamp(dot(up, view_forward), -1.0LF, 1.0LF);
  const double sin_centre = sqrt(max(0.0LF, 1.0LF - cos_centre * cos_centre));
  double sin_lo = 0.0LF, cos_lo = 1.0LF, sin_hi = 0.0LF, cos_hi = -1.0LF;
  if (cos_centre < cos_spread) {
    sin_lo = sin_centre * cos_spread - cos_centre * sin_spread;
    cos_lo = cos_centre * cos_spread + sin_centre * sin_spread;
  }
  if (cos_centre > -cos_spread) {
    sin_hi = sin_centre * cos_spread + cos_centre * sin_spread;
    cos_hi = cos_centre * cos_spread - sin_centre * sin_spread;
  }
  s = cos_lo >= 0.0LF && cos_hi <= 0.0LF ? 1.0LF : max(sin_lo, sin_hi);
  c = max(abs(cos_lo), abs(cos_hi));
}

// `slack`: pixels by which the CPU's value may differ beyond the relative
// band (below).
double criterion(uint slot, out double slack) {
  slack = 0.0LF;
  int c = 0;
  while (c + 1 < class_count && uint(offsets[c + 1]) <= slot) ++c;
  const bool diagonal = c % 2 == 0;
  // Class 2j: diagonals of h = 2^j; class 2j - 1: axis diamonds of s = 2^j.
  const int j = diagonal ? c / 2 : c / 2 + 1;
  const int size = 1 << j;
  const int columns = n >> j;
  uint i = slot - uint(offsets[c]);
  ivec2 p;
  if (diagonal) {
    p = ivec2((2 * int(i % uint(columns)) + 1) * size, (2 * int(i / uint(columns)) + 1) * size);
  } else {
    const uint horizontal = uint(columns) * uint((n >> (j + 1)) + 1);
    if (i < horizontal) {
      p = ivec2((2 * int(i % uint(columns)) + 1) * size, int(i / uint(columns)) * 2 * size);
    } else {
      i -= horizontal;
      const uint across = uint(columns + 1);
      p = ivec2(int(i % across) * 2 * size, (2 * int(i / across) + 1) * size);
    }
  }
  double error = 0.0LF, lo = 0.0LF, hi = 0.0LF;
  if (has_errors != 0) {
    const uint range = errors[2u * slot + 1u];
    error = double(uintBitsToFloat(errors[2u * slot]));
    lo = double(int(range << 16) >> 16);
    hi = double(int(range) >> 16);
  }
  const int r = diagonal ? 3 * size : 2 * size;
  double edge = 0.0LF;
  if (p.x - r <= 0) edge = max(edge, side_max(0, p.y - r, p.y + r));
  if (p.x + r >= 2 * n) edge = max(edge, side_max(1, p.y - r, p.y + r));
  if (p.y - r <= 0) edge = max(edge, side_max(2, p.x - r, p.x + r));
  if (p.y + r >= n) edge = max(edge, side_max(3, p.x - r, p.x + r));
  const double hypotenuse = diagonal ? 2.0LF * sqrt(2.0LF) * double(size) : 2.0LF * double(size);
  const double theta = hypotenuse * cell * kDegree;
  const double pad = level_error + edge + arc * theta * theta / 8.0LF;
  const double metres = error + pad;
  if (metres <= 0.0LF) return 0.0LF;
  const double xs = grid[2 * p.x], xc = grid[2 * p.x + 1];
  const double ys = grid[2 * p.y], yc = grid[2 * p.y + 1];
  const double sin_lon = west_sin * xc + west_cos * xs;
  const double cos_lon = west_cos * xc - west_sin * xs;
  const double sin_lat = north_sin * yc - north_cos * ys;
  const double cos_lat = north_cos * yc + north_sin * ys;
  const double h = (lo + hi) / 2.0LF;
  const double normal = grid[normals_at + p.y];
  const dvec3 centre = dvec3((normal + h) * cos_lat * cos_lon, (normal + h) * cos_lat * sin_lon,
                             (normal * (1.0LF - e2) + h) * sin_lat);
  const double radius = arc * sqrt(2.0LF) * double(r) * cell * kDegree + (hi - lo) / 2.0LF + pad +
                        rounding;
  // Most diamonds are far under the threshold: the distance bound from the
  // ball's centre settles them as pixels() does first (a margin of 1e-6
  // instead of its 1e-9: a diamond this takes is under on both processors).
  const dvec3 to_centre = centre - eye;
  const double reach =
      pixels_per_radian * (1.0LF + corner) / threshold * metres + sqrt(3.0LF) * radius;
  if (dot(to_centre, to_centre) > reach * reach * (1.0LF + 1.0e-6LF)) return 0.0LF;
  const dvec3 box_lo = centre - dvec3(radius), box_hi = centre + dvec3(radius);
  const dvec3 d = max(max(box_lo - eye, dvec3(0.0LF)), eye - box_hi);
  const double distance = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
  const double by_distance =
      distance > 0.0LF ? pixels_per_radian * metres * (1.0LF + corner) / distance : kHuge;
  double z_min = kHuge, t = 0.0LF;
  for (int k = 0; k < 8; ++k) {
    const dvec3 q = dvec3((k & 1) != 0 ? box_hi.x : box_lo.x, (k & 2) != 0 ? box_hi.y : box_lo.y,
                          (k & 4) != 0 ? box_hi.z : box_lo.z) - eye;
    const double z = dot(q, view_forward);
    if (z <= 0.0LF) return by_distance;  // behind the eye: the distance bound alone
    z_min = min(z_min, z);
    const double x = dot(q, view_right), y = dot(q, view_up);
    t = max(t, sqrt(x * x + y * y) / z);
  }
  double s, cs;
  angle_bounds(dvec3(cos_lat * cos_lon, cos_lat * sin_lon, sin_lat), grid[spreads_at + 2 * c],
               grid[spreads_at + 2 * c + 1], s, cs);
  const double by_angle = pixels_per_radian * metres * (s + t * cs) / z_min;
  // Looking straight at the normal, sin(centre) = sqrt(1 - cos^2) loses
  // half its digits: the CPU's, from trigonometry instead of angle sums,
  // may differ by ~2e-8 in absolute terms, which the bound multiplies by
  // K m / z_min (relative, it can exceed the band near the nadir).
  if (by_angle < by_distance) slack = pixels_per_radian * metres / z_min * 1.0e-7LF;
  return min(by_distance, by_angle);
}

void main() {
  // Rows of at most 65 535 groups (glDispatchCompute's guaranteed limit).
  const uint index = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u;
  uint word = 0u;
  for (uint m = 0u; m < 4u; ++m) {
    const uint slot = 4u * index + m;
    if (slot >= uint(slot_count)) break;
    double slack;
    const double v = criterion(slot, slack);
    const double margin = threshold * band + slack;
    const uint cls = v < threshold - margin ? 0u : v > threshold + margin ? 1u : 2u;
    word |= cls << (8u * m);
  }
  if (4u * index < uint(slot_count)) classes[index] = word;
}
)";

}  // namespace relief::render
