#include "relief/web/geographic_tiles.h"

#include <cstring>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "relief/tiles/codec.h"
#include "sample_block.h"

namespace relief::web {

Result<GeographicTiles> GeographicTiles::create(std::shared_ptr<const tiles::Store> store,
                                                uint64_t cache_bytes) {
  const tiles::Manifest& m = store->manifest();
  if (m.kind != tiles::DatasetKind::Imagery) {
    return fail(
        fmt::format("{}: holds {}, not imagery", store->root().string(), tiles::to_string(m.kind)));
  }
  if (store->grid().width() != 2 * kTileSize || store->grid().height() != kTileSize) {
    return fail(fmt::format("{}: tiles of {} x {}; geographic web tiles need 512 x 256",
                            store->root().string(), store->grid().width(), store->grid().height()));
  }
  auto pixels = std::make_shared<const Pixels>(store, cache_bytes);
  return GeographicTiles(std::move(store), std::move(pixels));
}

int GeographicTiles::max_level() const {
  return store_->manifest().max_level;
}

bool GeographicTiles::available(const geo::TileKey& key) const {
  if (key.level < 0 || key.level > max_level()) return false;
  const uint64_t rows = uint64_t{1} << key.level;
  if (key.y >= rows || key.x >= 2 * rows) return false;
  return store_->has_tile({key.level, key.x / 2, key.y});
}

Result<tiles::Raster> GeographicTiles::raster(const geo::TileKey& key) const {
  if (!available(key))
    return fail(fmt::format("geographic tile {}: not available", key.to_string()));
  // Cesium's tile is 256 of the level's global columns and rows, one half of
  // a store tile's interior.
  const std::vector<Rgba> samples = RELIEF_TRY(pixels_->read(
      key.level, int64_t{key.x} * kTileSize, int64_t{key.y} * kTileSize, kTileSize, kTileSize));
  tiles::Raster out =
      tiles::Raster::uninitialised(tiles::SampleType::UInt8, 4, kTileSize, kTileSize);
  std::memcpy(out.u8().data(), samples.data(), samples.size() * sizeof(Rgba));
  return out;
}

Result<std::vector<std::byte>> GeographicTiles::png_tile(const geo::TileKey& key) const {
  tiles::CodecOptions png;
  png.codec = tiles::Codec::Png;
  return tiles::encode(RELIEF_TRY(raster(key)), png);
}

std::string GeographicTiles::description(const std::string& name) const {
  const geo::GeoBox& b = store_->manifest().extent;
  const nlohmann::json j = {
      {"tilejson", "2.2.0"},
      {"name", name},
      {"description", "relief imagery in CesiumJS's geographic tiling (y from the north)"},
      {"version", "1.0.0"},
      {"scheme", "geographic"},
      {"tiles", {"{z}/{x}/{y}.png"}},
      {"minzoom", 0},
      {"maxzoom", max_level()},
      {"bounds", {b.west, b.south, b.east, b.north}},
      {"tileSize", kTileSize},
  };
  return j.dump(1);
}

}  // namespace relief::web
