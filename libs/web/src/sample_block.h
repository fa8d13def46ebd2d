#pragma once
// Blocks of one level's samples across tile boundaries, read from the
// owning tiles' interiors (never from borders: with a lossy codec a border
// copy may decode to other bits than its owner, and two web tiles sharing an
// edge must see the same values). Decoded interiors are kept in a byte-
// budgeted cache shared by all threads.
#include <array>
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

// A pixel of an imagery store: R, G, B, A (alpha 0: nodata).
using Rgba = std::array<uint8_t, 4>;

// `Sample` is float for elevation stores (NaN: nodata) and Rgba for imagery
// stores (transparent: nodata); the store must hold that sample type.
template <class Sample>
class BlockReader {
 public:
  BlockReader(std::shared_ptr<const tiles::Store> store, uint64_t cache_bytes);

  // Samples of `level`, global columns [col0, col0 + width) and rows
  // [row0, row0 + height) (row 0 at the north pole): columns wrap around
  // the antimeridian, rows beyond a pole repeat the pole's row, nodata where
  // no tile or no data.
  Result<std::vector<Sample>> read(int level, int64_t col0, int64_t row0, int width,
                                   int height) const;

 private:
  using Interior = std::vector<Sample>;
  Result<std::shared_ptr<const Interior>> interior(const geo::TileKey& key) const;

  std::shared_ptr<const tiles::Store> store_;
  mutable LruCache<geo::TileKey, Interior, geo::TileKeyHash> cache_;
};

extern template class BlockReader<float>;
extern template class BlockReader<Rgba>;
using SampleBlocks = BlockReader<float>;
using PixelBlocks = BlockReader<Rgba>;

}  // namespace relief::web
