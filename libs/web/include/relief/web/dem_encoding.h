#pragma once
// Heights as the RGB of a PNG pixel: the two encodings MapLibre's
// `raster-dem` sources read (docs/web.md). Both put a 24-bit integer v in
// R, G, B (R = v >> 16, G = (v >> 8) & 255, B = v & 255):
//   Mapbox Terrain-RGB  h = -10000 + v * 0.1       (0.1 m steps)
//   Tilezen Terrarium   h = v / 256 - 32768        (1/256 m steps)
// Encoding rounds to the nearest step and clamps to the 24-bit range; a
// NaN (nodata) height is written as 0 m, as a client needs some height.
#include <cstdint>
#include <optional>
#include <string_view>

namespace relief::web {

enum class DemEncoding { TerrainRgb, Terrarium };

// The name MapLibre's `encoding` property gives: "mapbox", "terrarium".
std::string_view maplibre_name(DemEncoding e);
// relief's format name: "terrain-rgb", "terrarium".
std::string_view format_name(DemEncoding e);
std::optional<DemEncoding> dem_encoding_from_format(std::string_view format);

struct Rgb {
  uint8_t r = 0, g = 0, b = 0;
  auto operator<=>(const Rgb&) const = default;
};

Rgb encode_height(DemEncoding e, double metres);
double decode_height(DemEncoding e, Rgb rgb);

}  // namespace relief::web
