#pragma once
// Blocks of one level's samples across tile boundaries, read from the
// owning tiles' interiors (never from borders: with a lossy codec a border
// copy may decode to other bits than its owner, and two web tiles sharing an
// edge must see the same values). Decoded interiors are kept in a byte-
// budgeted cache shared by all threads.
#include <cstdint>
#include <memory>
#include <vector>

#include "relief/base/lru_cache.h"
#include "relief/base/result.h"
#include "relief/geo/tile_key.h"

namespace relief::tiles {
class Store;
}

namespace relief::web {

class SampleBlocks {
 public:
  SampleBlocks(std::shared_ptr<const tiles::Store> store, uint64_t cache_bytes);

  // Samples of `level`, global columns [col0, col0 + width) and rows
  // [row0, row0 + height) (row 0 at the north pole): columns wrap around
  // the antimeridian, rows beyond a pole repeat the pole's row, NaN where no
  // tile or no data.
  Result<std::vector<float>> read(int level, int64_t col0, int64_t row0, int width,
                                  int height) const;

 private:
  using Interior = std::vector<float>;
  Result<std::shared_ptr<const Interior>> interior(const geo::TileKey& key) const;

  std::shared_ptr<const tiles::Store> store_;
  mutable LruCache<geo::TileKey, Interior, geo::TileKeyHash> cache_;
};

}  // namespace relief::web
