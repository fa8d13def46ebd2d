#pragma once
// The XYZ tiling of Web Mercator (EPSG:3857) that MapLibre, Leaflet and
// OpenLayers request: 2^z x 2^z square tiles at zoom z, x east from -180°,
// y south from the top edge at 85.0511° (atan(sinh(π))), N x N pixels each.
// Pixels are areas: pixel (i, j) of tile (z, x, y) is the square whose centre
// has the normalised coordinates
//   mx = (x + (i + 0.5) / N) / 2^z,   my = (y + (j + 0.5) / N) / 2^z,
// at lon = 360 mx - 180 and lat = atan(sinh(π (1 - 2 my))).
#include <cstdint>
#include <optional>
#include <string>

#include "relief/geo/tile_key.h"

namespace relief::web {

// The latitude of the top edge of tile (0, 0, 0): the square world's edge.
inline constexpr double kMercatorMaxLatitude = 85.051128779806592;
// Zooms beyond have pixels of less than a millimetre; x and y fit 32 bits.
inline constexpr int kMaxZoom = 30;

struct XyzKey {
  int z = 0;
  uint32_t x = 0, y = 0;
  auto operator<=>(const XyzKey&) const = default;
  bool valid() const;  // z in [0, kMaxZoom], x and y in [0, 2^z)
  geo::GeoBox bounds() const;
  std::string to_string() const;  // "z/x/y"
};

// Longitude and latitude (degrees) of normalised Mercator coordinates in
// [0, 1] (my = 0 at the top), and back.
double mercator_lon(double mx);
double mercator_lat(double my);
double mercator_my(double lat);

double pixel_lon(const XyzKey& key, int tile_size, int i);
double pixel_lat(const XyzKey& key, int tile_size, int j);

// Inclusive ranges of the tiles of zoom z that meet a box (clipped to the
// square world); nullopt when none does.
struct XyzRange {
  uint32_t x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};
std::optional<XyzRange> xyz_tiles_meeting(int z, const geo::GeoBox& box);

}  // namespace relief::web
