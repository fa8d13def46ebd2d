#pragma once
// What a Web Mercator pixel of a relief store should hold, computed here
// from the documented rules (docs/web.md) and the store's own samples, not
// from libs/web's resampler: the pixel centre's lon/lat, the level its row
// reads, and the bilinear mean of the 4 samples around it.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include "relief/tiles/store.h"

namespace relief::testing {

struct PixelCentre {
  double lon = 0, lat = 0;
};

inline PixelCentre pixel_centre(int z, uint32_t x, uint32_t y, int n, int i, int j) {
  const double tiles = std::ldexp(1.0, z);
  const double mx = (x + (i + 0.5) / n) / tiles, my = (y + (j + 0.5) / n) / tiles;
  return {360 * mx - 180,
          std::atan(std::sinh(std::numbers::pi * (1 - 2 * my))) * 180 / std::numbers::pi};
}

// L = z + log2(N) - 9 + floor(log2(1 / cos(lat))), within the store's levels.
inline int level_for_pixel(const tiles::Store& s, int z, int n, double lat) {
  const int log2_n = static_cast<int>(std::lround(std::log2(n)));
  const int finer =
      static_cast<int>(std::floor(std::log2(1 / std::cos(lat * std::numbers::pi / 180))));
  return std::clamp(z + log2_n - 9 + finer, s.manifest().min_level, s.manifest().max_level);
}

// The bilinear height at (lon, lat) over the level's cell-centred samples,
// read one by one with Store::sample; nullopt unless all 4 have data.
inline std::optional<double> bilinear_height(const tiles::Store& s, int level, PixelCentre p) {
  const double d = 180 / std::ldexp(1.0, level + 8);
  const double fx = (p.lon + 180) / d - 0.5, fy = (90 - p.lat) / d - 0.5;
  const double c = std::floor(fx), r = std::floor(fy), tx = fx - c, ty = fy - r;
  double sum = 0;
  for (const int dc : {0, 1}) {
    for (const int dr : {0, 1}) {
      const auto v = s.sample(-180 + (c + dc + 0.5) * d, 90 - (r + dr + 0.5) * d, level);
      if (!v || !*v) return std::nullopt;
      sum += (dc ? tx : 1 - tx) * (dr ? ty : 1 - ty) * **v;
    }
  }
  return sum;
}

}  // namespace relief::testing
