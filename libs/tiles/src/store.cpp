#include "relief/tiles/store.h"

#include <cmath>

#include <fmt/format.h>

#include "relief/base/file_io.h"
#include "relief/tiles/store_layout.h"

namespace relief::tiles {
namespace fs = std::filesystem;

Result<Store> Store::open(const fs::path& root) {
  std::error_code ec;
  if (!fs::is_directory(root, ec)) {
    return fail(fmt::format("{}: no such store directory", root.string()));
  }
  if (!fs::exists(root / kManifestName, ec)) {
    return fail(fmt::format("{}: not a relief store (no {}; an interrupted build?)", root.string(),
                            kManifestName));
  }
  return open(local_source(root));
}

Result<Store> Store::open(std::shared_ptr<const StoreSource> source) {
  const std::string name = source->name();
  const std::string manifest_name = (fs::path(name) / kManifestName).string();
  auto bytes = RELIEF_TRY(source->fetch(kManifestName));
  const std::string text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  auto manifest = RELIEF_TRY(Manifest::from_json(text, manifest_name));
  auto grid = geo::TileGrid::create(manifest.tile_log2_height, manifest.border);
  if (!grid) return fail(fmt::format("{}: {}", manifest_name, grid.error().message));
  const TileShape shape = *tile_shape_of(manifest);

  Store store;
  store.root_ = name;
  store.source_ = std::move(source);
  store.manifest_ = std::move(manifest);
  store.grid_ = *grid;
  store.shape_ = shape;
  for (int level = 0; level <= store.manifest_.max_level; ++level) {
    if (level < store.manifest_.min_level) {
      store.indices_.emplace_back(level);
      continue;
    }
    const std::string relative = level_index_relative_path(level);
    const std::string path = (fs::path(name) / relative).string();
    auto index_bytes = RELIEF_TRY(store.source_->fetch(relative));
    auto index = LevelIndex::parse(index_bytes, path);
    if (!index) return std::unexpected(index.error());
    if (index->level() != level)
      return fail(fmt::format("{}: index is for level {}", path, index->level()));
    store.indices_.push_back(std::move(*index));
  }
  return store;
}

const LevelIndex& Store::index(int level) const {
  static const LevelIndex kEmpty;
  if (level < 0 || level >= static_cast<int>(indices_.size())) return kEmpty;
  return indices_[static_cast<size_t>(level)];
}

fs::path Store::tile_path(const geo::TileKey& key) const {
  return root_ / tile_relative_path(key);
}

Result<Tile> Store::read_tile(const geo::TileKey& key) const {
  const fs::path path = tile_path(key);
  if (!has_tile(key)) {
    return fail(fmt::format("{}: tile {} is not in the store", path.string(), key.to_string()));
  }
  auto bytes = source_->fetch(tile_relative_path(key));
  if (!bytes) return std::unexpected(bytes.error());
  Tile tile = RELIEF_TRY(decode_tile(*bytes, path.string(), shape_));
  const IndexEntry& listed = *index(key.level).find(key);
  RELIEF_CHECK(check_listed_tile(listed, tile.header,
                                 source_->holds_files() ? bytes->size() : listed.file_bytes, path));
  return tile;
}

// A valid tile file in the wrong place (two tiles swapped, a neighbour copied
// over, another store's tile from a server or a cache) decodes without error;
// the level index, which the store read first, says what this key's file is:
// its size, its count of valid samples and bounds around its values.
Status check_listed_tile(const IndexEntry& listed, const TileHeader& header, size_t file_bytes,
                         const fs::path& path) {
  const SampleStats& s = header.stats;
  const bool same = listed.file_bytes == file_bytes && listed.valid_count == s.valid_count &&
                    (s.valid_count == 0 || (s.min >= listed.min && s.max <= listed.max));
  if (same) return {};
  return fail(fmt::format(
      "{}: is not the tile the level index lists for {} ({} bytes, {} valid samples; the index: "
      "{} bytes, {} valid samples): a tile in the wrong place or from another store",
      path.string(), listed.key.to_string(), file_bytes, s.valid_count, listed.file_bytes,
      listed.valid_count));
}

Result<TileShape> tile_shape_of(const Manifest& m) {
  const auto grid = RELIEF_TRY(geo::TileGrid::create(m.tile_log2_height, m.border));
  return TileShape{m.sample_type, m.bands, grid.padded_width(), grid.padded_height(),
                   grid.border()};
}

Result<std::optional<float>> Store::sample(double lon, double lat, int level) const {
  if (manifest_.sample_type != SampleType::Float32) {
    return fail(fmt::format("{}: sampling needs a float32 store", root_.string()));
  }
  const geo::SampleIndex s = grid_.locate(level, lon, lat);
  if (!has_tile(s.tile)) return std::optional<float>();
  auto tile = read_tile(s.tile);
  if (!tile) return std::unexpected(tile.error());
  const int w = tile->raster.width();
  const float v =
      tile->raster.f32()[static_cast<size_t>(s.j + grid_.border()) * static_cast<size_t>(w) +
                         static_cast<size_t>(s.i + grid_.border())];
  if (std::isnan(v)) return std::optional<float>();
  return std::optional<float>(v);
}

IndexEntry index_entry_for(const geo::TileKey& key, const TileHeader& h, size_t file_bytes) {
  return {key, static_cast<float>(h.stats.min), static_cast<float>(h.stats.max),
          static_cast<uint32_t>(h.stats.valid_count), static_cast<uint32_t>(file_bytes)};
}

Status write_tile_file(const fs::path& root, const geo::TileKey& key,
                       std::span<const std::byte> bytes) {
  return write_file_atomic(root / tile_relative_path(key), bytes);
}

Status write_level_index(const fs::path& root, const LevelIndex& index) {
  const auto bytes = index.serialize();
  return write_file_atomic(root / level_index_relative_path(index.level()), bytes, true);
}

Status write_manifest(const fs::path& root, const Manifest& manifest) {
  const fs::path path = root / kManifestName;
  // JSON has no infinity or NaN (they would be written as null): a manifest
  // that cannot be read back would leave a store that nothing opens.
  const std::pair<const char*, double> numbers[] = {
      {"statistics min", manifest.stats.min},       {"statistics max", manifest.stats.max},
      {"statistics mean", manifest.stats.mean},     {"statistics std", manifest.stats.stddev},
      {"extent west", manifest.extent.west},        {"extent south", manifest.extent.south},
      {"extent east", manifest.extent.east},        {"extent north", manifest.extent.north},
      {"codec max_error", manifest.codec.max_error}};
  for (const auto& [name, value] : numbers) {
    if (!std::isfinite(value)) {
      return fail(fmt::format("{}: not written: its {} is {} (not a finite number)", path.string(),
                              name, value));
    }
  }
  const std::string text = manifest.to_json();
  if (auto back = Manifest::from_json(text, path.string()); !back) {
    return fail(fmt::format("not written: {}", back.error().message));
  }
  return write_text_file_atomic(path, text, true);
}

}  // namespace relief::tiles
