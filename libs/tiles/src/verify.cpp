#include "relief/tiles/verify.h"

#include <algorithm>
#include <mutex>
#include <set>

#include <fmt/format.h>

#include "relief/base/file_io.h"
#include "relief/tiles/geometric_error.h"
#include "relief/tiles/store.h"
#include "relief/tiles/store_layout.h"

namespace relief::tiles {
namespace fs = std::filesystem;

namespace {

// The errors recomputed from the tiles must be those in the indexes, bit for bit.
void check_geometric_errors(const Store& store, Executor& executor, Progress& progress,
                            VerifyReport& report) {
  const Manifest& m = store.manifest();
  std::vector<LevelIndex> indices;
  for (int level = m.min_level; level <= m.max_level; ++level)
    indices.push_back(store.index(level));
  auto st = compute_geometric_errors(indices, store.tile_shape(), store_tile_reader(store),
                                     executor, progress);
  if (!st) {
    report.problems.push_back(st.error().message);
    return;
  }
  for (const LevelIndex& index : indices) {
    for (const IndexEntry& e : index.entries()) {
      const IndexEntry* stored = store.index(e.key.level).find(e.key);
      if (stored && stored->error != e.error) {
        report.problems.push_back(
            fmt::format("{}: tile {} has a geometric error of {} in the level index, {} recomputed",
                        (store.root() / level_index_relative_path(e.key.level)).string(),
                        e.key.to_string(), stored->error, e.error));
      }
    }
  }
}

}  // namespace

VerifyReport verify_store(const fs::path& root, Executor& executor, Progress& progress) {
  VerifyReport report;
  auto store = Store::open(root);
  if (!store) {
    report.problems.push_back(store.error().message);
    return report;
  }
  // Every file under the level directories: tiles, indices, and nothing else.
  std::set<geo::TileKey> on_disk;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(root, ec);
       !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    if (!it->is_regular_file()) continue;
    const std::string rel = fs::relative(it->path(), root).generic_string();
    if (rel == kManifestName || rel.ends_with(std::string("/") + kLevelIndexName)) continue;
    if (auto key = tile_key_from_relative_path(rel)) {
      on_disk.insert(*key);
    } else if (is_temporary_file(it->path())) {
      report.problems.push_back(
          fmt::format("{}: leftover temporary file of an interrupted write", it->path().string()));
    } else {
      report.problems.push_back(
          fmt::format("{}: unexpected file in the store", it->path().string()));
    }
  }
  std::vector<IndexEntry> indexed;
  for (int level = store->manifest().min_level; level <= store->manifest().max_level; ++level) {
    for (const auto& e : store->index(level).entries()) indexed.push_back(e);
  }
  // The manifest's statistics are those of the finest level's tiles.
  uint64_t finest_valid = 0;
  for (const auto& e : store->index(store->manifest().max_level).entries()) {
    finest_valid += e.valid_count;
  }
  if (finest_valid != store->manifest().stats.valid_count) {
    report.problems.push_back(fmt::format(
        "{}: statistics count {} valid samples, the finest level's index {}",
        (root / kManifestName).string(), store->manifest().stats.valid_count, finest_valid));
  }
  for (const auto& e : indexed) {
    if (!on_disk.count(e.key)) {
      report.problems.push_back(fmt::format("{}: tile {} is in the index but missing",
                                            store->tile_path(e.key).string(), e.key.to_string()));
    }
  }
  std::set<geo::TileKey> indexed_keys;
  for (const auto& e : indexed) indexed_keys.insert(e.key);
  for (const auto& key : on_disk) {
    if (!indexed_keys.count(key)) {
      report.problems.push_back(fmt::format("{}: tile {} is not in the level index",
                                            store->tile_path(key).string(), key.to_string()));
    }
  }

  std::mutex mutex;
  progress.begin("verify", indexed.size());
  executor.parallel_for(indexed.size(), [&](size_t i) {
    const IndexEntry& e = indexed[i];
    std::string problem;
    if (on_disk.count(e.key)) {
      auto tile = store->read_tile(e.key);
      if (!tile) {
        problem = tile.error().message;
      } else if (tile->header.stats.valid_count != e.valid_count) {
        problem = fmt::format("{}: valid sample count {} disagrees with the index ({})",
                              store->tile_path(e.key).string(), tile->header.stats.valid_count,
                              e.valid_count);
      }
    }
    std::lock_guard lock(mutex);
    ++report.tiles_checked;
    if (!problem.empty()) report.problems.push_back(problem);
    progress.advance();
  });
  progress.end();
  // Only over tiles that read back: a broken tile is reported above already.
  if (report.ok() && store->manifest().kind == DatasetKind::Elevation) {
    check_geometric_errors(*store, executor, progress, report);
  }
  std::sort(report.problems.begin(), report.problems.end());
  return report;
}

}  // namespace relief::tiles
