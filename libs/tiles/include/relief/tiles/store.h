#pragma once
// Read access to a store directory on the local file system. Writers use the
// free functions below; every write is atomic.
#include <filesystem>
#include <optional>
#include <vector>

#include "relief/base/result.h"
#include "relief/geo/tile_grid.h"
#include "relief/tiles/level_index.h"
#include "relief/tiles/manifest.h"
#include "relief/tiles/store_source.h"
#include "relief/tiles/tile_file.h"

namespace relief::tiles {

class Store {
 public:
  // Reads the manifest and every level index of a local store directory.
  static Result<Store> open(const std::filesystem::path& root);
  // The same through any source (HTTP servers: libs/net).
  static Result<Store> open(std::shared_ptr<const StoreSource> source);

  const std::filesystem::path& root() const { return root_; }
  const Manifest& manifest() const { return manifest_; }
  const geo::TileGrid& grid() const { return grid_; }
  const LevelIndex& index(int level) const;  // empty index outside the level range
  // What every tile file of the store must hold (checked before decoding).
  const TileShape& tile_shape() const { return shape_; }

  // The tile's file under root(): a path for local stores, a URL otherwise.
  std::filesystem::path tile_path(const geo::TileKey& key) const;
  bool has_tile(const geo::TileKey& key) const { return index(key.level).find(key) != nullptr; }
  // Reads and checks one tile; a tile absent from the index is an error too.
  Result<Tile> read_tile(const geo::TileKey& key) const;
  // Nearest-sample value at (lon, lat) on `level`; nullopt where there is no
  // data (no tile, or a nodata sample). Float32 stores only.
  Result<std::optional<float>> sample(double lon, double lat, int level) const;

 private:
  std::filesystem::path root_;
  std::shared_ptr<const StoreSource> source_;
  Manifest manifest_;
  geo::TileGrid grid_;
  TileShape shape_;
  std::vector<LevelIndex> indices_;
};

// The tile shape a manifest declares; an error if its grid is out of range.
Result<TileShape> tile_shape_of(const Manifest& manifest);

// The index record of a tile file with this header and size.
IndexEntry index_entry_for(const geo::TileKey& key, const TileHeader& header, size_t file_bytes);
// Whether a tile file (its header and size) is the one `listed` describes; an
// error naming `path` if not (a valid tile in the wrong place). Store::read_tile
// checks every tile it reads.
Status check_listed_tile(const IndexEntry& listed, const TileHeader& header, size_t file_bytes,
                         const std::filesystem::path& path);

Status write_tile_file(const std::filesystem::path& root, const geo::TileKey& key,
                       std::span<const std::byte> bytes);
Status write_level_index(const std::filesystem::path& root, const LevelIndex& index);
Status write_manifest(const std::filesystem::path& root, const Manifest& manifest);

}  // namespace relief::tiles
