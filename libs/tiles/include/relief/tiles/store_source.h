#pragma once
// Where a store's files come from: a local directory, or HTTP servers (see
// libs/net). A Store reads every file through its source, so the same code
// renders, verifies and processes local and remote stores.
#include <cstddef>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "relief/base/result.h"
#include "relief/tiles/tile_file.h"

namespace relief::tiles {

class StoreSource {
 public:
  virtual ~StoreSource() = default;
  // The store's location for messages ("/data/dem", "http://host:8080/dem").
  virtual std::string name() const = 0;
  // The bytes of the file at `relative` ("manifest.json", "3/index.rli",
  // tile paths); errors name the file.
  virtual Result<std::vector<std::byte>> fetch(const std::string& relative) const = 0;
  // Whether fetch() gives the store's files as written, whose sizes the level
  // indices list (a directory, a server, a cache of either); false for stores
  // made in memory, which encode their tiles when fetched.
  virtual bool holds_files() const { return true; }
  // Whether the bytes are a whole, uncorrupted store file of that name
  // (checksums of tiles and indices, JSON of the manifest).
  static Status verify(const std::string& relative, std::span<const std::byte> bytes);
};

// The largest a store file of that name may be, so that sources can refuse a
// larger one (a hostile server's endless body) before holding it: a manifest
// kMaxManifestBytes; a level index the size it has with every tile of its
// level present, at most kMaxLevelIndexBytes; a tile max_tile_file_bytes of
// the store's tile shape, or before the manifest is known, of the largest
// shape a manifest may declare.
inline constexpr uint64_t kMaxManifestBytes = uint64_t{16} << 20;
inline constexpr uint64_t kMaxLevelIndexBytes = uint64_t{256} << 20;
uint64_t max_file_bytes(const std::string& relative, const std::optional<TileShape>& shape);

// The caps of max_file_bytes for one store: sources learn the tile shape from
// the manifest that passes through them (a Store fetches it first).
// Thread-safe.
class FileCaps {
 public:
  uint64_t cap(const std::string& relative) const;
  // Learns from the bytes of `relative` if it is a valid manifest.
  void learn(const std::string& relative, std::span<const std::byte> bytes);

 private:
  mutable std::mutex mutex_;
  std::optional<TileShape> shape_;
};

// A store directory on the local file system. Only regular files are read,
// and none larger than its cap (a sparse 20 GB tile file is an error, not a
// 20 GB read).
std::shared_ptr<const StoreSource> local_source(const std::filesystem::path& root);

}  // namespace relief::tiles
