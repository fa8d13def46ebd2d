#pragma once
// Scratch storage for tile interiors ("cores") during a build. Cores of every
// level are written once (atomically, so a killed build resumes from them),
// and kept in a byte-budgeted LRU cache from which parents and bordered tiles
// are assembled: a core still cached is never read back from disk. Lives in
// <store>/.build/cores and is deleted when the build ends.
#include <filesystem>
#include <memory>
#include <optional>
#include <vector>

#include "relief/base/lru_cache.h"
#include "relief/base/result.h"
#include "relief/geo/tile_key.h"
#include "relief/tiles/raster.h"
#include "relief/tiles/tile_file.h"

namespace relief::ingest {

class CoreStore {
 public:
  // Every core has `shape` (no border); a core file of another shape is an error.
  CoreStore(std::filesystem::path dir, tiles::TileShape shape, uint64_t cache_budget_bytes);

  bool exists(const geo::TileKey& key) const;
  Status write(const geo::TileKey& key, tiles::Raster core);
  // nullptr when the core does not exist (an empty tile).
  Result<std::shared_ptr<const tiles::Raster>> read(const geo::TileKey& key);
  // Every core written so far at `level`, sorted by (y, x).
  std::vector<geo::TileKey> list(int level) const;

 private:
  std::filesystem::path path_of(const geo::TileKey& key) const;
  std::filesystem::path dir_;
  tiles::TileShape shape_;
  LruCache<geo::TileKey, tiles::Raster, geo::TileKeyHash> cache_;
};

}  // namespace relief::ingest
