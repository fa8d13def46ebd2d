#include "tile_reader.h"

#include "relief/tiles/assemble.h"

namespace relief::pipeline {

TileReader::TileReader(const tiles::Store& store, uint64_t budget_bytes)
    : store_(store), cache_(budget_bytes, [](const tiles::Raster& r) { return r.byte_size(); }) {}

Result<TileReader::Interior> TileReader::interior(const geo::TileKey& key) {
  if (!store_.has_tile(key)) return Interior{};
  if (auto hit = cache_.get(key)) return hit;
  tiles::Tile tile = RELIEF_TRY(store_.read_tile(key));
  const int b = tile.header.border, w = tile.header.interior_width(),
            h = tile.header.interior_height();
  auto inner = std::make_shared<tiles::Raster>(tile.raster.type(), tile.raster.bands(), w, h);
  inner->copy_from(tile.raster, b, b, 0, 0, w, h);
  cache_.put(key, inner);
  return Interior(inner);
}

Result<tiles::Raster> TileReader::window(const geo::TileKey& key, int border) {
  std::array<Interior, 9> held;
  std::array<const tiles::Raster*, 9> around{};
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      const auto n = key.neighbour(dx, dy);
      if (!n) continue;
      const size_t i = static_cast<size_t>((dy + 1) * 3 + dx + 1);
      held[i] = RELIEF_TRY(interior(*n));
      around[i] = held[i].get();
    }
  }
  const geo::TileGrid& g = store_.grid();
  return tiles::assemble_bordered(around, g.width(), g.height(), border,
                                  store_.manifest().sample_type);
}

}  // namespace relief::pipeline
