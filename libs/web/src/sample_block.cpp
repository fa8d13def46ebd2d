#include "sample_block.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <type_traits>

#include "relief/tiles/store.h"

namespace relief::web {
namespace {
template <class Sample>
Sample nodata() {
  if constexpr (std::is_same_v<Sample, float>) {
    return std::numeric_limits<float>::quiet_NaN();
  } else {
    return Sample{};  // transparent
  }
}
}  // namespace

template <class Sample>
BlockReader<Sample>::BlockReader(std::shared_ptr<const tiles::Store> store, uint64_t cache_bytes)
    : store_(std::move(store)),
      cache_(cache_bytes, [](const Interior& v) { return v.size() * sizeof(Sample) + 64; }) {}

template <class Sample>
Result<std::shared_ptr<const typename BlockReader<Sample>::Interior>> BlockReader<Sample>::interior(
    const geo::TileKey& key) const {
  if (auto hit = cache_.get(key)) return hit;
  const auto& grid = store_->grid();
  auto values = std::make_shared<Interior>(
      static_cast<size_t>(grid.width()) * static_cast<size_t>(grid.height()), nodata<Sample>());
  if (store_->has_tile(key)) {
    auto tile = store_->read_tile(key);
    if (!tile) return std::unexpected(tile.error());
    // Both sample types are pixel-interleaved: a row of samples is a run of bytes.
    const std::span<const std::byte> bordered = tile->raster.bytes();
    const size_t b = static_cast<size_t>(grid.border()),
                 pw = static_cast<size_t>(tile->raster.width());
    const size_t w = static_cast<size_t>(grid.width());
    for (size_t j = 0; j < static_cast<size_t>(grid.height()); ++j) {
      std::memcpy(values->data() + j * w, bordered.data() + ((j + b) * pw + b) * sizeof(Sample),
                  w * sizeof(Sample));
    }
  }
  cache_.put(key, values);
  return std::shared_ptr<const Interior>(std::move(values));
}

template <class Sample>
Result<std::vector<Sample>> BlockReader<Sample>::read(int level, int64_t col0, int64_t row0,
                                                      int width, int height) const {
  const auto& grid = store_->grid();
  const int64_t tw = grid.width(), th = grid.height();
  const int64_t columns = tw << level, rows = th << level;
  std::vector<Sample> out(static_cast<size_t>(width) * static_cast<size_t>(height));
  for (int j = 0; j < height; ++j) {
    const int64_t row = std::clamp<int64_t>(row0 + j, 0, rows - 1);
    Sample* dst = out.data() + static_cast<size_t>(j) * static_cast<size_t>(width);
    for (int i = 0; i < width;) {
      // The run of this row inside one tile.
      const int64_t col = (((col0 + i) % columns) + columns) % columns;
      const int64_t in_tile = col % tw;
      const int run = static_cast<int>(std::min<int64_t>(tw - in_tile, width - i));
      const geo::TileKey key{level, static_cast<uint32_t>(col / tw),
                             static_cast<uint32_t>(row / th)};
      if (!store_->has_tile(key)) {
        // Not even cached: a web tile may span large empty parts of a level.
        std::fill(dst + i, dst + i + run, nodata<Sample>());
      } else {
        auto values = interior(key);
        if (!values) return std::unexpected(values.error());
        const Sample* src = (*values)->data() + (row % th) * tw + in_tile;
        std::copy(src, src + run, dst + i);
      }
      i += run;
    }
  }
  return out;
}

template class BlockReader<float>;
template class BlockReader<Rgba>;

}  // namespace relief::web
