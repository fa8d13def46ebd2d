#include "angle_bound_range.h"

#include <algorithm>
#include <cmath>

namespace relief::lod {

namespace {

// Rounding, generously: of ECEF coordinates and their products (~1e-9 m at
// 1e7 m), relative on the result (~1e-15), and on the normal and angles.
constexpr double kMetres = 1e-6, kRelative = 1e-9, kAngle = 1e-12;

double l1(const Vec3& v) {
  return std::abs(v.x) + std::abs(v.y) + std::abs(v.z);
}

}  // namespace

AngleBoundRange angle_bound_range(const View& view, const Vec3& centre, double half,
                                  const Vec3& normal, double spread, double metres) {
  AngleBoundRange r;
  const Vec3 d = centre - view.eye;
  const double x = dot(d, view.right), y = dot(d, view.up), z = dot(d, view.forward);
  const double slack = kMetres + kRelative * (std::abs(x) + std::abs(y) + std::abs(z) + 3 * half);
  const double z_min = z - half * l1(view.forward);
  r.z_lo = z_min - slack;
  if (!(r.z_lo > 0)) return r;
  r.in_front = true;
  r.z_hi = z_min + slack;
  const double xs = std::abs(x) + half * l1(view.right) + slack;
  const double ys = std::abs(y) + half * l1(view.up) + slack;
  r.t_hi = std::sqrt(xs * xs + ys * ys) / r.z_lo;
  r.t_lo = std::max(0.0, std::sqrt(x * x + y * y) - slack) / (z + slack);
  const double u = std::abs(dot(normal, view.forward));
  const double u_lo = std::max(0.0, u - kAngle), u_hi = std::min(1.0, u + kAngle);
  const double widest = spread + kAngle;
  r.s_lo = std::max(0.0, std::sqrt(std::max(0.0, 1 - u_hi * u_hi)) - kAngle);
  r.s_hi = std::min(1.0, std::sqrt(std::max(0.0, 1 - u_lo * u_lo)) + widest + kAngle);
  r.c_lo = std::max(0.0, u_lo - kAngle);
  r.c_hi = std::min(1.0, u_hi + widest + kAngle);
  const double k = view.pixels_per_radian * metres;
  r.lo = k * (r.s_lo + r.t_lo * r.c_lo) / r.z_hi * (1 - kRelative);
  r.hi = k * (r.s_hi + r.t_hi * r.c_hi) / r.z_lo * (1 + kRelative);
  return r;
}

}  // namespace relief::lod
