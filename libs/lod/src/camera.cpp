#include "relief/lod/camera.h"

#include <algorithm>

#include <fmt/format.h>

#include "relief/geo/ellipsoid.h"

namespace relief::lod {

namespace {
constexpr double kDeg = 3.14159265358979323846 / 180;
}  // namespace

Vec3 up_at(double lon_deg, double lat_deg) {
  const double l = lon_deg * kDeg, p = lat_deg * kDeg;
  return {std::cos(p) * std::cos(l), std::cos(p) * std::sin(l), std::sin(p)};
}
Vec3 east_at(double lon_deg) {
  const double l = lon_deg * kDeg;
  return {-std::sin(l), std::cos(l), 0};
}
Vec3 north_at(double lon_deg, double lat_deg) {
  const double l = lon_deg * kDeg, p = lat_deg * kDeg;
  return {-std::sin(p) * std::cos(l), -std::sin(p) * std::sin(l), std::cos(p)};
}
Vec3 ecef(double lon_deg, double lat_deg, double height_m) {
  const geo::Ecef e = geo::to_ecef({lon_deg, lat_deg, height_m});
  return {e.x, e.y, e.z};
}

double distance_to(const Box& b, const Vec3& p) {
  const double dx = std::max({b.lo.x - p.x, 0.0, p.x - b.hi.x});
  const double dy = std::max({b.lo.y - p.y, 0.0, p.y - b.hi.y});
  const double dz = std::max({b.lo.z - p.z, 0.0, p.z - b.hi.z});
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

Camera look_at(double lon, double lat, double height, double range, double heading, double pitch,
               double fov_y, int width, int height_px) {
  // Direction from the camera to the target in the target's local frame,
  // then back out along it.
  const double h = heading * kDeg, p = pitch * kDeg;
  const Vec3 forward =
      (east_at(lon) * std::sin(h) + north_at(lon, lat) * std::cos(h)) * std::cos(p) +
      up_at(lon, lat) * std::sin(p);
  const Vec3 eye = ecef(lon, lat, height) - forward * range;
  const geo::Geodetic g = geo::to_geodetic({eye.x, eye.y, eye.z});
  // Heading and pitch at the eye's own frame, so the target stays centred.
  const Vec3 e = east_at(g.lon_deg), n = north_at(g.lon_deg, g.lat_deg),
             u = up_at(g.lon_deg, g.lat_deg);
  Camera c;
  c.lon = g.lon_deg;
  c.lat = g.lat_deg;
  c.height = g.height_m;
  c.heading = std::atan2(dot(forward, e), dot(forward, n)) / kDeg;
  c.pitch = std::asin(std::clamp(dot(forward, u), -1.0, 1.0)) / kDeg;
  c.roll = 0;
  c.fov_y = fov_y;
  c.width = width;
  c.height_px = height_px;
  return c;
}

bool View::project(const Vec3& p, double& sx, double& sy) const {
  const Vec3 d = p - eye;
  const double z = dot(d, forward);
  if (z <= 0) return false;
  const double x = dot(d, right) / (z * tan_half_x), y = dot(d, up) / (z * tan_half_y);
  sx = (x + 1) * 0.5 * width;
  sy = (1 - y) * 0.5 * height;
  return true;
}

Result<View> make_view(const Camera& c) {
  if (!(c.width >= 1 && c.height_px >= 1 && c.width <= 16384 && c.height_px <= 16384)) {
    return fail(fmt::format("the view's size {}x{} is not between 1x1 and 16384x16384", c.width,
                            c.height_px));
  }
  if (!(c.fov_y > 1 && c.fov_y < 170)) {
    return fail(fmt::format("the field of view of {} degrees is not in (1, 170)", c.fov_y));
  }
  if (!(c.lat >= -90 && c.lat <= 90) || !(c.lon >= -360 && c.lon <= 360) ||
      !std::isfinite(c.height)) {
    return fail(fmt::format("the camera's {},{} is not a longitude, latitude", c.lon, c.lat));
  }
  if (c.height <= -1000) {
    return fail(fmt::format("the camera's height {} m is inside the ellipsoid", c.height));
  }
  View v;
  v.eye = ecef(c.lon, c.lat, c.height);
  const double h = c.heading * kDeg, p = c.pitch * kDeg, r = c.roll * kDeg;
  const Vec3 e = east_at(c.lon), n = north_at(c.lon, c.lat), u = up_at(c.lon, c.lat);
  const Vec3 level_forward = e * std::sin(h) + n * std::cos(h);
  const Vec3 level_right = e * std::cos(h) - n * std::sin(h);
  v.forward = normalize(level_forward * std::cos(p) + u * std::sin(p));
  const Vec3 right0 = level_right;
  const Vec3 up0 = cross(right0, v.forward);
  v.right = normalize(right0 * std::cos(r) + up0 * std::sin(r));
  v.up = normalize(cross(v.right, v.forward));
  v.width = c.width;
  v.height = c.height_px;
  v.tan_half_y = std::tan(c.fov_y * kDeg / 2);
  v.tan_half_x = v.tan_half_y * c.width / c.height_px;
  v.pixels_per_radian = c.height_px / (2 * v.tan_half_y);
  // Reversed float depth (1 at the near plane, 0 at infinity) keeps its
  // relative precision at every distance, so a close near plane costs
  // nothing and never clips terrain beneath a low camera.
  v.near = 0.1;
  auto plane = [&](const Vec3& normal) { return Plane{normal, -dot(normal, v.eye)}; };
  v.planes[0] = Plane{v.forward, -dot(v.forward, v.eye) - v.near};
  v.planes[1] = plane(normalize(v.right + v.forward * v.tan_half_x));
  v.planes[2] = plane(normalize(-v.right + v.forward * v.tan_half_x));
  v.planes[3] = plane(normalize(v.up + v.forward * v.tan_half_y));
  v.planes[4] = plane(normalize(-v.up + v.forward * v.tan_half_y));
  return v;
}

Result<View> with_window(const View& view, const PixelRect& w) {
  if (w.empty() || w.x < 0 || w.y < 0 || w.x > view.width - w.width ||
      w.y > view.height - w.height) {
    return fail(fmt::format("window {}x{}+{}+{} is not inside the {}x{} view", w.width, w.height,
                            w.x, w.y, view.width, view.height));
  }
  View v = view;
  v.window = w;
  return v;
}

std::array<Plane, 5> window_planes(const View& v) {
  if (v.window.empty()) return v.planes;
  // Normalised device coordinates of the window's sides (y up).
  const double left = 2.0 * v.window.x / v.width - 1,
               right = 2.0 * (v.window.x + v.window.width) / v.width - 1,
               top = 1 - 2.0 * v.window.y / v.height,
               bottom = 1 - 2.0 * (v.window.y + v.window.height) / v.height;
  auto plane = [&](const Vec3& normal) { return Plane{normal, -dot(normal, v.eye)}; };
  std::array<Plane, 5> p;
  p[0] = v.planes[0];
  p[1] = plane(normalize(v.right - v.forward * (left * v.tan_half_x)));
  p[2] = plane(normalize(-v.right + v.forward * (right * v.tan_half_x)));
  p[3] = plane(normalize(v.up - v.forward * (bottom * v.tan_half_y)));
  p[4] = plane(normalize(-v.up + v.forward * (top * v.tan_half_y)));
  return p;
}

bool outside(const std::array<Plane, 5>& planes, const Vec3& lo, const Vec3& hi) {
  for (const Plane& pl : planes) {
    // The box corner furthest along the plane normal.
    const Vec3 far{pl.normal.x >= 0 ? hi.x : lo.x, pl.normal.y >= 0 ? hi.y : lo.y,
                   pl.normal.z >= 0 ? hi.z : lo.z};
    if (dot(pl.normal, far) + pl.d < 0) return true;
  }
  return false;
}

}  // namespace relief::lod
