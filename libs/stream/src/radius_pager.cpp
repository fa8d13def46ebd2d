#include "relief/stream/radius_pager.h"

#include <algorithm>
#include <cmath>

#include "relief/geo/ellipsoid.h"

namespace relief::stream {

namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

Result<size_t> request_radius(lod::TerrainModel& terrain, const tiles::Store& store,
                              const lod::Vec3& eye, double radius_tiles) {
  const double r = std::hypot(eye.x, eye.y);
  const double eye_lon = std::atan2(eye.y, eye.x) * 180 / kPi;
  const double eye_lat = std::atan2(eye.z, r) * 180 / kPi;
  size_t count = 0;
  for (int level = 1; level <= store.manifest().max_level; ++level) {
    const double tile_deg = 180.0 / std::ldexp(1.0, level);
    const double extent = tile_deg * kPi / 180 * geo::wgs84::kSemiMajorAxis;
    const double radius = radius_tiles * extent;
    // Tiles whose boxes may be within the radius: a lat/lon window around
    // the eye (the radius as an angle, widened towards the poles), then exact.
    const double reach = radius / geo::wgs84::kSemiMinorAxis * 180 / kPi + tile_deg;
    const double lon_reach = reach / std::max(0.01, std::cos(eye_lat * kPi / 180));
    const int n = static_cast<int>(std::ldexp(1.0, level));
    const int y0 = std::max(0, static_cast<int>((90 - eye_lat - reach) / tile_deg));
    const int y1 = std::min(n - 1, static_cast<int>((90 - eye_lat + reach) / tile_deg));
    const double lon_deg = 2 * tile_deg;
    const int span = std::min(n, static_cast<int>(2 * lon_reach / lon_deg) + 2);
    const int xc = static_cast<int>((eye_lon + 180) / lon_deg);
    for (int y = y0; y <= y1; ++y) {
      for (int i = -span / 2; i <= span / 2; ++i) {
        const geo::TileKey key{level, static_cast<uint32_t>(((xc + i) % n + n) % n),
                               static_cast<uint32_t>(y)};
        if (!store.has_tile(key)) continue;
        const lod::TerrainModel::QuadInfo* info = RELIEF_TRY(terrain.quad(key));
        const double d = lod::distance_to(info->box, eye);
        if (d > radius || terrain.available(key)) continue;
        terrain.request(key, (store.manifest().max_level - level + 1) * 1e12 - d);
        ++count;
      }
    }
  }
  return count;
}

}  // namespace relief::stream
