#pragma once
// Decoded tile interiors of an input store, shared between the tiles that
// need them as neighbours (a byte-budget LRU cache; concurrent requests for
// one tile may decode it twice, which costs time, never correctness).
#include <array>
#include <memory>

#include "relief/base/lru_cache.h"
#include "relief/base/result.h"
#include "relief/tiles/store.h"

namespace relief::pipeline {

class TileReader {
 public:
  TileReader(const tiles::Store& store, uint64_t budget_bytes);
  using Interior = std::shared_ptr<const tiles::Raster>;
  // The interior of `key`, or nullptr where the store has no such tile.
  Result<Interior> interior(const geo::TileKey& key);
  // The tile's interior with `border` samples of its neighbours around it
  // (nodata beyond the poles and where neighbours are absent).
  Result<tiles::Raster> window(const geo::TileKey& key, int border);

 private:
  const tiles::Store& store_;
  LruCache<geo::TileKey, tiles::Raster, geo::TileKeyHash> cache_;
};

}  // namespace relief::pipeline
