#include "relief/lod/camera_path.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace relief::lod {

namespace {

double lerp(double a, double b, double s) {
  return a + (b - a) * s;
}

// From a to b the short way round a circle of 360 degrees.
double lerp_angle(double a, double b, double s) {
  const double d = std::remainder(b - a, 360.0);
  double v = a + d * s;
  if (v > 180) v -= 360;
  if (v < -180) v += 360;
  return v;
}

}  // namespace

Camera camera_at(std::span<const Keyframe> path, double t) {
  assert(!path.empty());
  if (t <= path.front().time) return path.front().camera;
  if (t >= path.back().time) return path.back().camera;
  const auto next = std::upper_bound(path.begin(), path.end(), t,
                                     [](double v, const Keyframe& k) { return v < k.time; });
  const Keyframe& a = *(next - 1);
  const Keyframe& b = *next;
  if (b.cut) return a.camera;
  const double s = (t - a.time) / (b.time - a.time);
  Camera c = a.camera;
  c.lon = lerp_angle(a.camera.lon, b.camera.lon, s);
  c.lat = lerp(a.camera.lat, b.camera.lat, s);
  c.height = lerp(a.camera.height, b.camera.height, s);
  c.heading = lerp_angle(a.camera.heading, b.camera.heading, s);
  c.pitch = lerp(a.camera.pitch, b.camera.pitch, s);
  c.roll = lerp(a.camera.roll, b.camera.roll, s);
  return c;
}

}  // namespace relief::lod
