#include "relief/tiles/upgrade.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "relief/base/file_io.h"
#include "relief/base/first_error.h"
#include "relief/tiles/geometric_error.h"
#include "relief/tiles/store.h"
#include "relief/tiles/store_layout.h"
#include "relief/tiles/store_source.h"

namespace relief::tiles {
namespace fs = std::filesystem;

namespace {

// The manifest of a format-1 store, read as the current format (the fields
// are the same; only what the indexes hold changed).
Result<Manifest> read_old_manifest(const fs::path& path, int& version) {
  const std::string text = RELIEF_TRY(read_text_file(path, kMaxManifestBytes));
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
    version = j.at("format_version").get<int>();
  } catch (const nlohmann::json::exception& ex) {
    return fail(fmt::format("{}: invalid manifest: {}", path.string(), ex.what()));
  }
  if (version == kStoreFormatVersion) return Manifest::from_json(text, path.string());
  if (version != 1) {
    return fail(fmt::format("{}: store format version {} cannot be upgraded (this relief reads {})",
                            path.string(), version, kStoreFormatVersion));
  }
  j["format_version"] = kStoreFormatVersion;
  return Manifest::from_json(j.dump(), path.string());
}

// The level's entries rebuilt from the tile files' headers: the same records a
// build writes (re-serializing the old ones would widen min/max once more).
Result<LevelIndex> read_old_index(const fs::path& root, int level, Executor& executor) {
  const fs::path path = root / level_index_relative_path(level);
  const auto bytes = RELIEF_TRY(read_file(path, kMaxLevelIndexBytes));
  const LevelIndex old = RELIEF_TRY(LevelIndex::parse_for_upgrade(bytes, path.string()));
  if (old.level() != level) {
    return fail(fmt::format("{}: index is for level {}", path.string(), old.level()));
  }
  const auto& entries = old.entries();
  std::vector<IndexEntry> fresh(entries.size());
  FirstError error;
  executor.parallel_for(entries.size(), [&](size_t i) {
    if (error.failed()) return;
    const fs::path tile = root / tile_relative_path(entries[i].key);
    auto file = read_file(tile, max_file_bytes(tile_relative_path(entries[i].key), std::nullopt));
    if (!file) return error.set(file.error());
    auto header = parse_tile_header(*file, tile.string());
    if (!header) return error.set(header.error());
    fresh[i] = index_entry_for(entries[i].key, *header, file->size());
  });
  RELIEF_CHECK(error.status());
  LevelIndex index(level);
  for (const IndexEntry& e : fresh) index.add(e);
  return index;
}

// Whether a level index of the store is of format version 1; one that is
// also damaged is that error (read as version 1, it would be upgraded).
Result<bool> has_version1_index(const fs::path& root, const Manifest& manifest) {
  for (int level = manifest.min_level; level <= manifest.max_level; ++level) {
    const fs::path path = root / level_index_relative_path(level);
    const auto bytes = RELIEF_TRY(read_file(path, kMaxLevelIndexBytes));
    if (LevelIndex::parse(bytes, path.string())) continue;
    RELIEF_CHECK(LevelIndex::parse_for_upgrade(bytes, path.string()));
    return true;
  }
  return false;
}

}  // namespace

Result<UpgradeReport> upgrade_store(const fs::path& root, Executor& executor, Progress& progress) {
  std::error_code ec;
  if (!fs::is_directory(root, ec)) {
    return fail(fmt::format("{}: no such store directory", root.string()));
  }
  UpgradeReport report;
  report.to_version = kStoreFormatVersion;
  const fs::path manifest_path = root / kManifestName;
  Manifest manifest = RELIEF_TRY(read_old_manifest(manifest_path, report.from_version));
  if (report.from_version == kStoreFormatVersion) {
    // A current manifest over version-1 indices (an upgrade killed between
    // its indices and its manifest, indices copied in): readers refuse those
    // and send the user here, so they are upgraded too.
    if (!RELIEF_TRY(has_version1_index(root, manifest))) return report;
    report.from_version = 1;
  }
  const TileShape shape = RELIEF_TRY(tile_shape_of(manifest));

  std::vector<LevelIndex> indices;
  for (int level = manifest.min_level; level <= manifest.max_level; ++level) {
    indices.push_back(RELIEF_TRY(read_old_index(root, level, executor)));
    report.tiles += indices.back().size();
  }
  if (manifest.kind == DatasetKind::Elevation) {
    RELIEF_CHECK(compute_geometric_errors(indices, shape, directory_tile_reader(root, shape),
                                          executor, progress));
  }
  for (const LevelIndex& index : indices) RELIEF_CHECK(write_level_index(root, index));
  manifest.format_version = kStoreFormatVersion;
  RELIEF_CHECK(write_manifest(root, manifest));
  return report;
}

}  // namespace relief::tiles
