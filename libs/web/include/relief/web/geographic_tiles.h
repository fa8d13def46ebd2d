#pragma once
// Imagery in CesiumJS's geographic tiling (GeographicTilingScheme: two tiles
// at level 0, y from the north, 256 x 256 pixels): relief's quad (z, X, Y)
// of 512 x 256 samples is Cesium's tiles (z, 2X, Y) and (z, 2X + 1, Y), so
// each tile is half a store tile's interior, its samples as they are (no
// resampling, no Web Mercator cut at ±85°). For imagery stores of 512 x 256
// tiles (docs/web.md, "Geographic imagery").
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "relief/base/result.h"
#include "relief/geo/tile_key.h"
#include "relief/tiles/store.h"

namespace relief::web {

template <class Sample>
class BlockReader;

class GeographicTiles {
 public:
  // Fails for a store that is not imagery or whose tiles are not 512 x 256.
  // Decoded store tiles are kept within `cache_bytes` (both halves of one,
  // and a coloured layer's chain, are made once).
  static Result<GeographicTiles> create(std::shared_ptr<const tiles::Store> store,
                                        uint64_t cache_bytes = uint64_t{64} << 20);

  int max_level() const;
  // Cesium's tile (level, x, y): within the level and over a store tile.
  bool available(const geo::TileKey& key) const;
  // Its 256 x 256 RGBA samples, row-major from the north-west.
  Result<tiles::Raster> raster(const geo::TileKey& key) const;
  Result<std::vector<std::byte>> png_tile(const geo::TileKey& key) const;
  // A TileJSON-like description: tiles "{z}/{x}/{y}.png", max zoom, bounds,
  // tileSize 256 and "scheme": "geographic".
  std::string description(const std::string& name) const;

  static constexpr int kTileSize = 256;

 private:
  using Pixels = BlockReader<std::array<uint8_t, 4>>;
  GeographicTiles(std::shared_ptr<const tiles::Store> store, std::shared_ptr<const Pixels> pixels)
      : store_(std::move(store)), pixels_(std::move(pixels)) {}
  std::shared_ptr<const tiles::Store> store_;
  std::shared_ptr<const Pixels> pixels_;  // the store's interiors, cached
};

}  // namespace relief::web
