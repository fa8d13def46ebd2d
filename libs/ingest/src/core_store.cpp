#include "core_store.h"

#include <algorithm>

#include <fmt/format.h>

#include "relief/base/file_io.h"
#include "relief/tiles/store_layout.h"
#include "relief/tiles/tile_file.h"

namespace relief::ingest {
namespace fs = std::filesystem;

CoreStore::CoreStore(fs::path dir, tiles::TileShape shape, uint64_t cache_budget_bytes)
    : dir_(std::move(dir)),
      shape_(shape),
      cache_(cache_budget_bytes, [](const tiles::Raster& r) { return r.byte_size(); }) {}

fs::path CoreStore::path_of(const geo::TileKey& key) const {
  return dir_ / tiles::tile_relative_path(key);
}

bool CoreStore::exists(const geo::TileKey& key) const {
  std::error_code ec;
  return fs::exists(path_of(key), ec);
}

Status CoreStore::write(const geo::TileKey& key, tiles::Raster core) {
  // Scratch data favours speed: the lowest zstd level.
  auto bytes = tiles::encode_tile(core, 0, {tiles::Codec::Zstd, 0, 0, 1});
  if (!bytes) return std::unexpected(bytes.error());
  RELIEF_CHECK(write_file_atomic(path_of(key), *bytes));
  // Cached once on disk: the next phase takes it from memory instead of
  // reading the file back and decoding it.
  cache_.put(key, std::make_shared<const tiles::Raster>(std::move(core)));
  return {};
}

Result<std::shared_ptr<const tiles::Raster>> CoreStore::read(const geo::TileKey& key) {
  if (auto hit = cache_.get(key)) return hit;
  const fs::path path = path_of(key);
  std::error_code ec;
  if (!fs::exists(path, ec)) return std::shared_ptr<const tiles::Raster>();
  auto bytes = read_file(path);
  if (!bytes) return std::unexpected(bytes.error());
  auto tile = tiles::decode_tile(*bytes, path.string(), shape_);
  if (!tile) return std::unexpected(tile.error());
  auto raster = std::make_shared<const tiles::Raster>(std::move(tile->raster));
  cache_.put(key, raster);
  return raster;
}

std::vector<geo::TileKey> CoreStore::list(int level) const {
  std::vector<geo::TileKey> keys;
  const fs::path root = dir_ / fmt::format("{}", level);
  std::error_code ec;
  if (!fs::is_directory(root, ec)) return keys;
  for (auto it = fs::recursive_directory_iterator(root, ec);
       it != fs::recursive_directory_iterator(); it.increment(ec)) {
    if (ec || !it->is_regular_file() || is_temporary_file(it->path())) continue;
    const std::string rel = fs::relative(it->path(), dir_).generic_string();
    if (auto key = tiles::tile_key_from_relative_path(rel)) keys.push_back(*key);
  }
  std::sort(keys.begin(), keys.end(),
            [](const auto& a, const auto& b) { return std::tie(a.y, a.x) < std::tie(b.y, b.x); });
  return keys;
}

}  // namespace relief::ingest
