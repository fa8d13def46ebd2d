#include "relief/geo/ellipsoid.h"

#include <cmath>
#include <numbers>

namespace relief::geo {

double degrees_to_radians(double deg) {
  return deg * std::numbers::pi / 180.0;
}
double radians_to_degrees(double rad) {
  return rad * 180.0 / std::numbers::pi;
}

Ecef to_ecef(const Geodetic& g) {
  using namespace wgs84;
  const double lat = degrees_to_radians(g.lat_deg);
  const double lon = degrees_to_radians(g.lon_deg);
  const double s = std::sin(lat), c = std::cos(lat);
  const double n = prime_vertical_radius(s);
  return {(n + g.height_m) * c * std::cos(lon), (n + g.height_m) * c * std::sin(lon),
          (n * (1.0 - kFirstEccentricitySquared) + g.height_m) * s};
}

Geodetic to_geodetic(const Ecef& p) {
  using namespace wgs84;
  const double a = kSemiMajorAxis;
  const double e2 = kFirstEccentricitySquared;
  const double e4 = e2 * e2;
  const double w2 = p.x * p.x + p.y * p.y;
  const double w = std::sqrt(w2);
  const double pp = w2 / (a * a);
  const double q = (1.0 - e2) / (a * a) * p.z * p.z;
  const double r = (pp + q - e4) / 6.0;
  const double s = e4 * pp * q / (4.0 * r * r * r);
  const double t = std::cbrt(1.0 + s + std::sqrt(s * (2.0 + s)));
  const double u = r * (1.0 + t + 1.0 / t);
  const double v = std::sqrt(u * u + e4 * q);
  const double uv = u + v;
  const double wk = e2 * (uv - q) / (2.0 * v);
  const double k = uv / (std::sqrt(wk * wk + uv) + wk);
  const double d = k * w / (k + e2);
  const double hyp = std::sqrt(d * d + p.z * p.z);
  Geodetic g;
  g.height_m = (k + e2 - 1.0) / k * hyp;
  g.lat_deg = radians_to_degrees(2.0 * std::atan2(p.z, d + hyp));
  g.lon_deg = radians_to_degrees(std::atan2(p.y, p.x));
  return g;
}

}  // namespace relief::geo
