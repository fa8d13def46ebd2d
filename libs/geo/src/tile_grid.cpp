#include "relief/geo/tile_grid.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

namespace relief::geo {

Result<TileGrid> TileGrid::create(int log2_height, int border) {
  if (log2_height < 1 || log2_height > 12) {
    return fail(fmt::format("tile height 2^{} is out of range (2^1 .. 2^12)", log2_height));
  }
  if (border < 0 || border > (1 << log2_height)) {
    return fail(fmt::format("tile border {} is out of range (0 .. {})", border, 1 << log2_height));
  }
  return TileGrid(log2_height, border);
}

double TileGrid::sample_spacing(int level) const {
  return 180.0 / std::ldexp(1.0, level + log2_height_);
}

int TileGrid::level_for_spacing(double spacing_deg) const {
  for (int level = 0; level < kMaxLevel; ++level) {
    if (sample_spacing(level) <= spacing_deg * (1 + 1e-9)) return level;
  }
  return kMaxLevel;
}

double TileGrid::sample_lon(const TileKey& t, double i) const {
  return -180.0 + (static_cast<double>(t.x) * width() + i + 0.5) * sample_spacing(t.level);
}

double TileGrid::sample_lat(const TileKey& t, double j) const {
  return 90.0 - (static_cast<double>(t.y) * height() + j + 0.5) * sample_spacing(t.level);
}

SampleIndex TileGrid::locate(int level, double lon, double lat) const {
  const double d = sample_spacing(level);
  lon = std::fmod(lon + 180.0, 360.0);
  if (lon < 0) lon += 360.0;
  const int64_t columns = int64_t{width()} << level;
  const int64_t rows = int64_t{height()} << level;
  const int64_t gi = std::clamp<int64_t>(static_cast<int64_t>(std::floor(lon / d)), 0, columns - 1);
  const int64_t gj =
      std::clamp<int64_t>(static_cast<int64_t>(std::floor((90.0 - lat) / d)), 0, rows - 1);
  SampleIndex s;
  s.tile = {level, static_cast<uint32_t>(gi / width()), static_cast<uint32_t>(gj / height())};
  s.i = static_cast<int>(gi % width());
  s.j = static_cast<int>(gj % height());
  return s;
}

void TileGrid::to_sample_coords(const TileKey& t, double lon, double lat, double& fi,
                                double& fj) const {
  const double d = sample_spacing(t.level);
  const GeoBox b = t.bounds();
  fi = (lon - b.west) / d - 0.5;
  fj = (b.north - lat) / d - 0.5;
}

}  // namespace relief::geo
