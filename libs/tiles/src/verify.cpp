#include "relief/tiles/verify.h"

#include <algorithm>
#include <cmath>
#include <limits>
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

// The tile is what its header says it holds: as many valid samples, within
// its min and max (exactly those of a lossless codec; JPEG and WebP colours
// are approximate).
Status check_tile_agrees(const Tile& tile, const fs::path& path) {
  const TileHeader& h = tile.header;
  const int b = h.border;
  const SampleStats s =
      tile.raster.stats(b, b, tile.raster.width() - 2 * b, tile.raster.height() - 2 * b);
  const bool lossless = h.codec == Codec::Zstd || h.codec == Codec::Png;
  const bool approximate = h.codec == Codec::Jpeg || h.codec == Codec::Webp;
  // LERC's bounds are the header's widened by max_error, which a decoded
  // float may pass by a rounding.
  const double slack = 1e-6 * std::max({1.0, std::abs(h.stats.min), std::abs(h.stats.max)});
  const bool bounded = s.valid_count == 0 || approximate ||
                       (lossless ? s.min == h.stats.min && s.max == h.stats.max
                                 : s.min >= h.stats.min - slack && s.max <= h.stats.max + slack);
  if (s.valid_count != h.stats.valid_count || !bounded) {
    return fail(fmt::format(
        "{}: the header says {} valid samples in [{}, {}], the samples are {} in [{}, {}]",
        path.string(), h.stats.valid_count, h.stats.min, h.stats.max, s.valid_count, s.min, s.max));
  }
  return {};
}

// The manifest describes the finest level's tiles: its extent meets each of
// them, its min and max are within the bounds the level index keeps of them.
Status check_manifest_range(const Store& store) {
  const Manifest& m = store.manifest();
  const auto& entries = store.index(m.max_level).entries();
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const IndexEntry& e : entries) {
    if (e.valid_count == 0) continue;
    lo = std::min(lo, static_cast<double>(e.min));
    hi = std::max(hi, static_cast<double>(e.max));
  }
  // Every tile of the finest level lies in the extent (or in it a turn of
  // the globe away: an extent may reach past the antimeridian).
  const geo::GeoBox& x = m.extent;
  for (const IndexEntry& e : entries) {
    const geo::GeoBox t = e.key.bounds();
    bool meets = false;
    for (double turn : {-360.0, 0.0, 360.0}) {
      meets = meets || t.intersects({x.west + turn, x.south, x.east + turn, x.north});
    }
    if (!meets) {
      return fail(fmt::format(
          "{}: extent W {} S {} E {} N {} does not meet tile {} (W {} S {} E {} N {}) of the "
          "finest level",
          (store.root() / kManifestName).string(), x.west, x.south, x.east, x.north,
          e.key.to_string(), t.west, t.south, t.east, t.north));
    }
  }
  if (m.stats.valid_count == 0 || lo > hi) return {};
  if (!(m.stats.min >= lo && m.stats.max <= hi)) {
    return fail(fmt::format(
        "{}: statistics min {} max {} are outside the finest level's samples, [{}, {}] by its "
        "index",
        (store.root() / kManifestName).string(), m.stats.min, m.stats.max, lo, hi));
  }
  return {};
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
  if (auto st = check_manifest_range(*store); !st) report.problems.push_back(st.error().message);
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
  size_t other_codec = 0;  // tiles not coded with the manifest's codec
  std::string other_codec_example;
  progress.begin("verify", indexed.size());
  executor.parallel_for(indexed.size(), [&](size_t i) {
    const IndexEntry& e = indexed[i];
    std::string problem, codec;
    if (on_disk.count(e.key)) {
      auto tile = store->read_tile(e.key);
      if (!tile) {
        problem = tile.error().message;
      } else if (tile->header.stats.valid_count != e.valid_count) {
        problem = fmt::format("{}: valid sample count {} disagrees with the index ({})",
                              store->tile_path(e.key).string(), tile->header.stats.valid_count,
                              e.valid_count);
      } else if (auto st = check_tile_agrees(*tile, store->tile_path(e.key)); !st) {
        problem = st.error().message;
      }
      if (tile && tile->header.codec != store->manifest().codec.codec) {
        codec =
            fmt::format("{} ({})", store->tile_path(e.key).string(), to_string(tile->header.codec));
      }
    }
    std::lock_guard lock(mutex);
    ++report.tiles_checked;
    if (!problem.empty()) report.problems.push_back(problem);
    if (!codec.empty() && (other_codec++ == 0 || codec < other_codec_example)) {
      other_codec_example = codec;  // the first by name, whatever the threads' order
    }
    progress.advance();
  });
  progress.end();
  // The manifest's codec contradicts the tiles: one line, not one per tile.
  if (other_codec > 0) {
    report.problems.push_back(
        fmt::format("{}: codec {} contradicts {} of the {} tiles, coded otherwise (e.g. {})",
                    (root / kManifestName).string(), to_string(store->manifest().codec.codec),
                    other_codec, indexed.size(), other_codec_example));
  }
  // Only over tiles that read back: a broken tile is reported above already.
  if (report.ok() && store->manifest().kind == DatasetKind::Elevation) {
    check_geometric_errors(*store, executor, progress, report);
  }
  std::sort(report.problems.begin(), report.problems.end());
  return report;
}

}  // namespace relief::tiles
