#pragma once
// Distances on the plane tangent to a sphere of the equatorial radius at a
// point: how lenses measure their circles, in the texture layers' lens pass
// (gpuprocess/composite.cpp, the same formula in GLSL), in the elevation
// operators' lenses (pipeline) and when the viewer drags a lens (view). Not a
// geodesic: a lens is a few kilometres across, where the two agree closely,
// and the shader can do the same sums.
#include <cmath>
#include <numbers>

#include "relief/geo/ellipsoid.h"

namespace relief::geo {

// Metres per degree of arc on that sphere.
inline constexpr double kTangentMetresPerDegree = wgs84::kSemiMajorAxis * std::numbers::pi / 180;

// Metres from (lon0, lat0) to (lon, lat), degrees, across the antimeridian too.
inline double tangent_plane_distance_m(double lon0, double lat0, double lon, double lat) {
  double dlon = lon - lon0;
  dlon -= 360 * std::round(dlon / 360);
  const double x = dlon * kTangentMetresPerDegree * std::cos(lat0 * std::numbers::pi / 180);
  const double y = (lat - lat0) * kTangentMetresPerDegree;
  return std::hypot(x, y);
}

}  // namespace relief::geo
