#include "relief/web/geographic_tiles.h"

#include <cstring>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "relief/tiles/codec.h"

namespace relief::web {

Result<GeographicTiles> GeographicTiles::create(std::shared_ptr<const tiles::Store> store) {
  const tiles::Manifest& m = store->manifest();
  if (m.kind != tiles::DatasetKind::Imagery) {
    return fail(
        fmt::format("{}: holds {}, not imagery", store->root().string(), tiles::to_string(m.kind)));
  }
  if (store->grid().width() != 2 * kTileSize || store->grid().height() != kTileSize) {
    return fail(fmt::format("{}: tiles of {} x {}; geographic web tiles need 512 x 256",
                            store->root().string(), store->grid().width(), store->grid().height()));
  }
  return GeographicTiles(std::move(store));
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
  const tiles::Tile tile = RELIEF_TRY(store_->read_tile({key.level, key.x / 2, key.y}));
  const int b = store_->grid().border(), w = tile.raster.width();
  tiles::Raster out =
      tiles::Raster::uninitialised(tiles::SampleType::UInt8, 4, kTileSize, kTileSize);
  const std::span<const uint8_t> in = tile.raster.u8();
  const std::span<uint8_t> to = out.u8();
  const size_t column = b + (key.x % 2) * kTileSize, row_bytes = size_t{4} * kTileSize;
  for (int j = 0; j < kTileSize; ++j) {
    const size_t from = (static_cast<size_t>(j + b) * static_cast<size_t>(w) + column) * 4;
    std::memcpy(to.data() + static_cast<size_t>(j) * row_bytes, in.data() + from, row_bytes);
  }
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
