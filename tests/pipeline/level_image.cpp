#include "level_image.h"

#include <cmath>
#include <stdexcept>

namespace relief::testing {

float LevelImage::at(int64_t gx, int64_t gy) const {
  const int64_t x = gx - x0, y = gy - y0;
  if (x < 0 || y < 0 || x >= width || y >= height) return NAN;
  return v[static_cast<size_t>(y) * width + x];
}

LevelImage read_level(const tiles::Store& store, int level, int pad) {
  const auto& entries = store.index(level).entries();
  const geo::TileGrid& g = store.grid();
  int64_t tx0 = INT64_MAX, ty0 = INT64_MAX, tx1 = 0, ty1 = 0;
  for (const auto& e : entries) {
    tx0 = std::min<int64_t>(tx0, e.key.x), ty0 = std::min<int64_t>(ty0, e.key.y);
    tx1 = std::max<int64_t>(tx1, e.key.x), ty1 = std::max<int64_t>(ty1, e.key.y);
  }
  LevelImage img;
  img.x0 = tx0 * g.width() - pad;
  img.y0 = ty0 * g.height() - pad;
  img.width = static_cast<int>((tx1 - tx0 + 1) * g.width() + 2 * pad);
  img.height = static_cast<int>((ty1 - ty0 + 1) * g.height() + 2 * pad);
  img.v.assign(static_cast<size_t>(img.width) * img.height, NAN);
  for (const auto& e : entries) {
    auto tile = store.read_tile(e.key);
    if (!tile) throw std::runtime_error(tile.error().message);
    const int b = tile->header.border, w = tile->raster.width();
    const auto src = tile->raster.f32();
    for (int j = 0; j < g.height(); ++j) {
      for (int i = 0; i < g.width(); ++i) {
        const int64_t x = e.key.x * int64_t{g.width()} + i - img.x0;
        const int64_t y = e.key.y * int64_t{g.height()} + j - img.y0;
        img.v[static_cast<size_t>(y) * img.width + x] = src[static_cast<size_t>(j + b) * w + i + b];
      }
    }
  }
  return img;
}

}  // namespace relief::testing
