#include "relief/web/web_mercator.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

namespace relief::web {

bool XyzKey::valid() const {
  return z >= 0 && z <= kMaxZoom && x < (1u << z) && y < (1u << z);
}

geo::GeoBox XyzKey::bounds() const {
  const double n = std::ldexp(1.0, z);
  return {mercator_lon(x / n), mercator_lat((y + 1) / n), mercator_lon((x + 1) / n),
          mercator_lat(y / n)};
}

std::string XyzKey::to_string() const {
  return fmt::format("{}/{}/{}", z, x, y);
}

double mercator_lon(double mx) {
  return 360.0 * mx - 180.0;
}

double mercator_lat(double my) {
  return std::atan(std::sinh(std::numbers::pi * (1 - 2 * my))) * 180.0 / std::numbers::pi;
}

double mercator_my(double lat) {
  const double phi = lat * std::numbers::pi / 180.0;
  return (1 - std::asinh(std::tan(phi)) / std::numbers::pi) / 2;
}

double pixel_lon(const XyzKey& key, int tile_size, int i) {
  return mercator_lon((key.x + (i + 0.5) / tile_size) / std::ldexp(1.0, key.z));
}

double pixel_lat(const XyzKey& key, int tile_size, int j) {
  return mercator_lat((key.y + (j + 0.5) / tile_size) / std::ldexp(1.0, key.z));
}

std::optional<XyzRange> xyz_tiles_meeting(int z, const geo::GeoBox& box) {
  const double west = std::max(box.west, -180.0), east = std::min(box.east, 180.0);
  const double north = std::min(box.north, kMercatorMaxLatitude);
  const double south = std::max(box.south, -kMercatorMaxLatitude);
  if (!(west < east && south < north)) return std::nullopt;
  const double n = std::ldexp(1.0, z);
  const auto last = static_cast<double>((1u << z) - 1);
  // A tile meets the box when their interiors overlap: a box edge on a tile
  // edge does not bring in the tile beyond it (the ceil - 1).
  const auto first_tile = [&](double t) { return std::clamp(std::floor(t * n), 0.0, last); };
  const auto last_tile = [&](double t) { return std::clamp(std::ceil(t * n) - 1, 0.0, last); };
  const double mx0 = (west + 180) / 360, mx1 = (east + 180) / 360;
  const double my0 = mercator_my(north), my1 = mercator_my(south);
  return XyzRange{static_cast<uint32_t>(first_tile(mx0)), static_cast<uint32_t>(first_tile(my0)),
                  static_cast<uint32_t>(last_tile(mx1)), static_cast<uint32_t>(last_tile(my1))};
}

}  // namespace relief::web
