#pragma once
// Cesium quantized-mesh terrain from an elevation store (docs/web.md).
//
// relief's quad (l, X, Y) is exactly the two Cesium tiles (l, 2X, y) and
// (l, 2X + 1, y) of the geographic tiling scheme, y = 2^l - 1 - Y counted
// from the south (TMS): 256 x 256 samples each, whose cell corners form the
// tile's 257 x 257 lattice (each corner the mean of the 4 samples around it,
// the renderer's bilinear height). The mesh is the lattice's RTIN cut at the
// level's error, with the errors of the neighbours' sides seeded along every
// edge so that two tiles of one level keep the same edge vertices.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "relief/base/result.h"
#include "relief/geo/tile_key.h"

namespace relief::tiles {
class Store;
}

namespace relief::web {

// A tile of Cesium's geographic scheme: 2 x 1 tiles at level 0, x east from
// -180, y north from -90 (the TMS row).
struct TerrainKey {
  int level = 0;
  uint32_t x = 0, y = 0;
  auto operator<=>(const TerrainKey&) const = default;
  geo::GeoBox bounds() const;
  std::string to_string() const;  // "level/x/y"
};

struct TerrainKeyHash {
  size_t operator()(const TerrainKey& k) const {
    return std::hash<uint64_t>{}((uint64_t{k.x} << 32 | k.y) * 31 + static_cast<uint64_t>(k.level));
  }
};

struct TerrainOptions {
  int max_level = -1;  // the finest level served; -1: the store's finest
  // Only tiles meeting this box (and the two level-0 tiles, which a client
  // always needs) are available.
  std::optional<geo::GeoBox> bbox;
  // The mesh's largest vertical distance from the lattice, metres, at every
  // level; unset: cesium_level_error(level), an eighth of it at the store's
  // finest level (no finer level follows: its mesh stays within an eighth of
  // a sample spacing of the data).
  std::optional<float> max_error;
  bool normals = true;                        // the octvertexnormals extension
  uint64_t cache_bytes = uint64_t{64} << 20;  // decoded store tiles kept
};

class TerrainTiler {
 public:
  // The store must hold elevation (Float32, one band).
  static Result<TerrainTiler> create(std::shared_ptr<const tiles::Store> store,
                                     TerrainOptions options = {});
  ~TerrainTiler();
  TerrainTiler(TerrainTiler&&) noexcept;
  TerrainTiler& operator=(TerrainTiler&&) noexcept;

  int max_level() const;
  float max_error(int level) const;
  bool available(const TerrainKey& key) const;
  // Every available tile of a level, sorted by (y, x).
  std::vector<TerrainKey> available_tiles(int level) const;
  // layer.json: the tileset's description and availability.
  std::string layer_json(const std::string& name) const;
  // The tile's quantized-mesh bytes, gzip-compressed. Thread-safe.
  Result<std::vector<std::byte>> tile(const TerrainKey& key) const;

 private:
  struct Impl;
  explicit TerrainTiler(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace relief::web
