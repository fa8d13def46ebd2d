#include "relief/lod/tile_provider.h"

#include <cmath>

#include "relief/base/lru_cache.h"
#include "relief/tiles/store.h"

namespace relief::lod {

namespace {

class BlockingProvider final : public TileProvider {
 public:
  BlockingProvider(const tiles::Store& store, uint64_t cache_bytes)
      : store_(store), tiles_(cache_bytes, [](const tiles::Raster& r) { return r.byte_size(); }) {}

  bool blocking() const override { return true; }

  Result<TilePtr> get(const geo::TileKey& key) override {
    if (auto hit = tiles_.get(key)) return hit;
    TilePtr tile = RELIEF_TRY(decode_tile(store_, key));
    tiles_.put(key, tile);
    return tile;
  }

 private:
  const tiles::Store& store_;
  LruCache<geo::TileKey, tiles::Raster, geo::TileKeyHash> tiles_;
};

}  // namespace

std::unique_ptr<TileProvider> blocking_provider(const tiles::Store& store, uint64_t cache_bytes) {
  return std::make_unique<BlockingProvider>(store, cache_bytes);
}

Result<TilePtr> decode_heights(const tiles::Store& store, const geo::TileKey& key) {
  tiles::Tile t = RELIEF_TRY(store.read_tile(key));
  if (t.raster.type() != tiles::SampleType::Float32) {
    return fail(store.root().string() + ": not an elevation store (imagery tiles)");
  }
  for (float& v : t.raster.f32()) {
    if (std::isnan(v)) v = 0;
  }
  return std::make_shared<const tiles::Raster>(std::move(t.raster));
}

Result<TilePtr> decode_tile(const tiles::Store& store, const geo::TileKey& key) {
  if (store.manifest().sample_type == tiles::SampleType::Float32) return decode_heights(store, key);
  tiles::Tile t = RELIEF_TRY(store.read_tile(key));
  // Colours premultiplied by alpha, so that linear filtering at the edge of
  // the data blends towards what is drawn beneath, not towards black.
  auto px = t.raster.u8();
  for (size_t p = 0; p + 3 < px.size(); p += 4) {
    const unsigned a = px[p + 3];
    if (a == 255) continue;
    for (size_t c = 0; c < 3; ++c) px[p + c] = static_cast<uint8_t>((px[p + c] * a + 127) / 255);
  }
  return std::make_shared<const tiles::Raster>(std::move(t.raster));
}

}  // namespace relief::lod
