#include "geometry.h"

#include <algorithm>
#include <cmath>

#include "relief/geo/ellipsoid.h"

namespace relief::view::controls {

using lod::Vec3;

Frame frame_of(const lod::Camera& c) {
  const double h = c.heading * kDeg, p = c.pitch * kDeg, r = c.roll * kDeg;
  const Vec3 e = lod::east_at(c.lon), n = lod::north_at(c.lon, c.lat), u = lod::up_at(c.lon, c.lat);
  const Vec3 level_forward = e * std::sin(h) + n * std::cos(h);
  const Vec3 level_right = e * std::cos(h) - n * std::sin(h);
  Frame f;
  f.eye = lod::ecef(c.lon, c.lat, c.height);
  f.forward = lod::normalize(level_forward * std::cos(p) + u * std::sin(p));
  const Vec3 up0 = lod::cross(level_right, f.forward);
  f.right = lod::normalize(level_right * std::cos(r) + up0 * std::sin(r));
  f.up = lod::normalize(lod::cross(f.right, f.forward));
  return f;
}

lod::Camera with_frame(lod::Camera c, const Vec3& eye, const Vec3& forward, const Vec3& up) {
  const geo::Geodetic g = geo::to_geodetic({eye.x, eye.y, eye.z});
  c.lon = g.lon_deg;
  c.lat = g.lat_deg;
  c.height = g.height_m;
  const Vec3 e = lod::east_at(c.lon), n = lod::north_at(c.lon, c.lat), u = lod::up_at(c.lon, c.lat);
  const Vec3 f = lod::normalize(forward);
  // Straight down (or up) the heading is the screen's top's (bottom's)
  // direction over the ground, with no roll.
  const Vec3 level = lod::length(f - u * lod::dot(f, u)) > 1e-9 ? f : up * -lod::dot(f, u);
  c.heading = std::atan2(lod::dot(level, e), lod::dot(level, n)) / kDeg;
  c.pitch = std::asin(std::clamp(lod::dot(f, u), -1.0, 1.0)) / kDeg;
  // make_view's right is level_right turned by the roll towards up0.
  const double h = c.heading * kDeg;
  const Vec3 level_right = e * std::cos(h) - n * std::sin(h);
  const Vec3 up0 = lod::cross(level_right, f);
  const Vec3 right = lod::cross(f, lod::normalize(up));
  c.roll = std::atan2(lod::dot(right, up0), lod::dot(right, level_right)) / kDeg;
  return c;
}

lod::Camera move_level(lod::Camera c, double forward_m, double right_m) {
  const double h = c.heading * kDeg;
  const Vec3 e = lod::east_at(c.lon), n = lod::north_at(c.lon, c.lat);
  const Vec3 ahead = e * std::sin(h) + n * std::cos(h);
  const Vec3 right = e * std::cos(h) - n * std::sin(h);
  const Vec3 p = lod::ecef(c.lon, c.lat, c.height) + ahead * forward_m + right * right_m;
  const geo::Geodetic g = geo::to_geodetic({p.x, p.y, p.z});
  c.lon = g.lon_deg;
  c.lat = g.lat_deg;
  // The same direction over the ground, read in the new local frame.
  c.heading = std::atan2(lod::dot(ahead, lod::east_at(c.lon)),
                         lod::dot(ahead, lod::north_at(c.lon, c.lat))) /
              kDeg;
  return c;
}

Vec3 rotate(const Vec3& v, const Vec3& k, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return v * c + lod::cross(k, v) * s + k * (lod::dot(k, v) * (1 - c));
}

double ground_or_zero(const Ground& ground, double lon, double lat) {
  if (!ground) return 0;
  return ground(lon, lat).value_or(0.0);
}

}  // namespace relief::view::controls
