#include "sample_block.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "relief/tiles/store.h"

namespace relief::web {

SampleBlocks::SampleBlocks(std::shared_ptr<const tiles::Store> store, uint64_t cache_bytes)
    : store_(std::move(store)),
      cache_(cache_bytes, [](const Interior& v) { return v.size() * sizeof(float) + 64; }) {}

Result<std::shared_ptr<const SampleBlocks::Interior>> SampleBlocks::interior(
    const geo::TileKey& key) const {
  if (auto hit = cache_.get(key)) return hit;
  const auto& grid = store_->grid();
  auto values = std::make_shared<Interior>(
      static_cast<size_t>(grid.width()) * static_cast<size_t>(grid.height()),
      std::numeric_limits<float>::quiet_NaN());
  if (store_->has_tile(key)) {
    auto tile = store_->read_tile(key);
    if (!tile) return std::unexpected(tile.error());
    const auto bordered = tile->raster.f32();
    const int b = grid.border(), pw = tile->raster.width();
    for (int j = 0; j < grid.height(); ++j) {
      const float* row = bordered.data() + static_cast<size_t>(j + b) * static_cast<size_t>(pw) + b;
      std::copy(row, row + grid.width(),
                values->begin() + static_cast<ptrdiff_t>(j) * grid.width());
    }
  }
  cache_.put(key, values);
  return std::shared_ptr<const Interior>(std::move(values));
}

Result<std::vector<float>> SampleBlocks::read(int level, int64_t col0, int64_t row0, int width,
                                              int height) const {
  const auto& grid = store_->grid();
  const int64_t tw = grid.width(), th = grid.height();
  const int64_t columns = tw << level, rows = th << level;
  std::vector<float> out(static_cast<size_t>(width) * static_cast<size_t>(height));
  for (int j = 0; j < height; ++j) {
    const int64_t row = std::clamp<int64_t>(row0 + j, 0, rows - 1);
    float* dst = out.data() + static_cast<size_t>(j) * static_cast<size_t>(width);
    for (int i = 0; i < width;) {
      // The run of this row inside one tile.
      const int64_t col = (((col0 + i) % columns) + columns) % columns;
      const int64_t in_tile = col % tw;
      const int run = static_cast<int>(std::min<int64_t>(tw - in_tile, width - i));
      const geo::TileKey key{level, static_cast<uint32_t>(col / tw),
                             static_cast<uint32_t>(row / th)};
      auto values = interior(key);
      if (!values) return std::unexpected(values.error());
      const float* src = (*values)->data() + (row % th) * tw + in_tile;
      std::copy(src, src + run, dst + i);
      i += run;
    }
  }
  return out;
}

}  // namespace relief::web
