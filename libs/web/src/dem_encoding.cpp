#include "relief/web/dem_encoding.h"

#include <algorithm>
#include <cmath>

namespace relief::web {
namespace {

constexpr double kLargest = (1 << 24) - 1;

// The 24-bit integer of a height, and its metres per step and offset.
struct Scale {
  double steps_per_metre, offset;
};
Scale scale_of(DemEncoding e) {
  return e == DemEncoding::TerrainRgb ? Scale{10.0, 10000.0} : Scale{256.0, 32768.0};
}

}  // namespace

std::string_view maplibre_name(DemEncoding e) {
  return e == DemEncoding::TerrainRgb ? "mapbox" : "terrarium";
}

std::string_view format_name(DemEncoding e) {
  return e == DemEncoding::TerrainRgb ? "terrain-rgb" : "terrarium";
}

std::optional<DemEncoding> dem_encoding_from_format(std::string_view format) {
  if (format == "terrain-rgb") return DemEncoding::TerrainRgb;
  if (format == "terrarium") return DemEncoding::Terrarium;
  return std::nullopt;
}

Rgb encode_height(DemEncoding e, double metres) {
  if (std::isnan(metres)) metres = 0;
  const Scale s = scale_of(e);
  // Clamped before the conversion: an out-of-range double to integer is undefined.
  const double steps =
      std::clamp(std::round((metres + s.offset) * s.steps_per_metre), 0.0, kLargest);
  const auto v = static_cast<uint32_t>(steps);
  return {static_cast<uint8_t>(v >> 16), static_cast<uint8_t>((v >> 8) & 0xFF),
          static_cast<uint8_t>(v & 0xFF)};
}

double decode_height(DemEncoding e, Rgb rgb) {
  const Scale s = scale_of(e);
  const uint32_t v = uint32_t{rgb.r} << 16 | uint32_t{rgb.g} << 8 | rgb.b;
  return static_cast<double>(v) / s.steps_per_metre - s.offset;
}

}  // namespace relief::web
