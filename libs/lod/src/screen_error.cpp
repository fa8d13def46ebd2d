#include "relief/lod/screen_error.h"

#include <algorithm>
#include <cmath>

namespace relief::lod {

namespace {

constexpr double kDegree = 3.14159265358979323846 / 180;
constexpr double kHalfPi = 3.14159265358979323846 / 2;

// Largest |sin| and |cos| of the angle between the view direction and any
// geodetic normal of `area`: the normals lie within `spread` radians of the
// centre's (half the box's extent along a meridian plus along a parallel).
void angle_bounds(const View& view, const geo::GeoBox& area, double& s, double& c) {
  const double lon = (area.west + area.east) / 2, lat = (area.south + area.north) / 2;
  const double centre = std::acos(std::clamp(dot(up_at(lon, lat), view.forward), -1.0, 1.0));
  const double spread = (area.width() + area.height()) / 2 * kDegree;
  const double lo = std::max(0.0, centre - spread), hi = std::min(2 * kHalfPi, centre + spread);
  s = lo <= kHalfPi && hi >= kHalfPi ? 1.0 : std::max(std::sin(lo), std::sin(hi));
  c = std::max(std::abs(std::cos(lo)), std::abs(std::cos(hi)));
}

}  // namespace

VerticalErrorParts vertical_error_parts(const View& view, const Box& box, const geo::GeoBox& area,
                                        double metres) {
  VerticalErrorParts e;
  if (metres <= 0) return e;
  const double f = view.pixels_per_radian;
  const double corner = view.tan_half_x * view.tan_half_x + view.tan_half_y * view.tan_half_y;
  e.distance = distance_to(box, view.eye);
  e.distance_bound = e.distance > 0 ? f * metres * (1 + corner) / e.distance : INFINITY;
  e.pixels = e.distance_bound;
  double z_min = INFINITY, t = 0;
  for (int i = 0; i < 8; ++i) {
    const Vec3 p = Vec3{i & 1 ? box.hi.x : box.lo.x, i & 2 ? box.hi.y : box.lo.y,
                        i & 4 ? box.hi.z : box.lo.z} -
                   view.eye;
    const double z = dot(p, view.forward);
    if (z <= 0) {  // behind the eye: only the distance bound holds
      e.behind = true;
      return e;
    }
    z_min = std::min(z_min, z);
    const double x = dot(p, view.right), y = dot(p, view.up);
    t = std::max(t, std::sqrt(x * x + y * y) / z);
  }
  double s = 1, c = 1;
  angle_bounds(view, area, s, c);
  e.z_min = z_min;
  e.tangent = t;
  e.sin_bound = s;
  e.cos_bound = c;
  e.pixels = std::min(e.distance_bound, f * metres * (s + t * c) / z_min);
  return e;
}

double vertical_error_pixels(const View& view, const Box& box, const geo::GeoBox& area,
                             double metres) {
  return vertical_error_parts(view, box, area, metres).pixels;
}

}  // namespace relief::lod
