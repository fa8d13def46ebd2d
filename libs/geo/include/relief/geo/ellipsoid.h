#pragma once
// WGS84 reference ellipsoid and geodetic <-> Earth-centred Earth-fixed (ECEF)
// conversion, all in double precision.
#include <cmath>

namespace relief::geo {

struct Geodetic {
  double lon_deg = 0;   // east positive, [-180, 180]
  double lat_deg = 0;   // north positive, [-90, 90]
  double height_m = 0;  // above the ellipsoid
};

struct Ecef {
  double x = 0, y = 0, z = 0;  // metres
};

namespace wgs84 {
inline constexpr double kSemiMajorAxis = 6378137.0;
inline constexpr double kFlattening = 1.0 / 298.257223563;
inline constexpr double kSemiMinorAxis = kSemiMajorAxis * (1.0 - kFlattening);
inline constexpr double kFirstEccentricitySquared = kFlattening * (2.0 - kFlattening);

// The prime vertical's radius of curvature N at a latitude, from its sine:
// to_ecef's (N + h) cos(lat) cos(lon), ...
inline double prime_vertical_radius(double sin_lat) {
  return kSemiMajorAxis / std::sqrt(1.0 - kFirstEccentricitySquared * sin_lat * sin_lat);
}
}  // namespace wgs84

Ecef to_ecef(const Geodetic& g);
// Closed-form inverse (Vermeille 2002): exact to well below a millimetre for any
// point outside a small region around the Earth's centre.
Geodetic to_geodetic(const Ecef& p);

double degrees_to_radians(double deg);
double radians_to_degrees(double rad);

}  // namespace relief::geo
