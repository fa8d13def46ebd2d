#include "relief/pipeline/processed_elevation.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <unordered_map>
#include <unordered_set>

#include <fmt/format.h>

#include "relief/base/progress.h"
#include "relief/geo/tangent_plane.h"
#include "relief/tiles/geometric_error.h"
#include "relief/tiles/store_layout.h"

#include "memory_store.h"

namespace relief::pipeline {
namespace {

using RasterPtr = std::shared_ptr<const tiles::Raster>;

// The border the processed tiles keep: the hillshade's slope reads heights
// one sample beyond a tile's edge, bilinearly (libs/render/src/shaders.h), so
// two samples shade the tiles' edges as the input's border does.
constexpr int kKeptBorder = 2;

// What the presented store's tiles are made from; shared by its source and
// the pass that builds its indexes.
struct Processing {
  tiles::Store input;
  ElevationProcessing processing;
  geo::TileGrid grid;  // the input's, with its overlap border
  int max_level = 0;
  process::GlobalStats stats;
  // Processed tiles are encoded only to pass through tiles::Store: fast and
  // lossless, so the decoded samples are the processed ones.
  tiles::CodecOptions codec{tiles::Codec::Zstd, 0.0, 90, 1};

  // Which samples of the processed tile at `key` (interior plus the kept
  // border, `w` x `h`) lie in `lens`: by each sample's own position (its
  // global column wrapped around the globe), so a sample is in or out
  // whichever tile holds it.
  std::vector<uint8_t> inside(const ElevationLens& lens, const geo::TileKey& key, int w,
                              int h) const {
    const double d = grid.sample_spacing(key.level);
    const int64_t columns = int64_t{grid.width()} << key.level;
    std::vector<double> lons(static_cast<size_t>(w));
    for (int x = 0; x < w; ++x) {
      int64_t gx = int64_t{key.x} * grid.width() + x - kKeptBorder;
      gx = (gx % columns + columns) % columns;
      lons[static_cast<size_t>(x)] = -180.0 + (static_cast<double>(gx) + 0.5) * d;
    }
    std::vector<uint8_t> in(static_cast<size_t>(w) * static_cast<size_t>(h));
    for (int y = 0; y < h; ++y) {
      const int64_t gy = int64_t{key.y} * grid.height() + y - kKeptBorder;
      const double lat = 90.0 - (static_cast<double>(gy) + 0.5) * d;
      for (int x = 0; x < w; ++x) {
        in[static_cast<size_t>(y) * static_cast<size_t>(w) + static_cast<size_t>(x)] =
            lens_distance_m(lens.lon, lens.lat, lons[static_cast<size_t>(x)], lat) <= lens.radius_m;
      }
    }
    return in;
  }

  // The processed tile at `key`: its interior and the kept border. The
  // chains' CPU reference keeps one sample around what it takes as the
  // interior: given one sample less of border, it keeps two.
  Result<RasterPtr> processed(const geo::TileKey& key) const {
    const tiles::Tile tile = RELIEF_TRY(input.read_tile(key));
    // Masks keep their size on the ground: level `key.level` is 2^(max -
    // level) times coarser than the finest, for which parameters are given.
    const double factor = std::ldexp(1.0, max_level - key.level);
    InlineExecutor inline_executor;  // one tile per reading thread
    tiles::Raster out = RELIEF_TRY(
        gpuprocess::run_chain_cpu(gpuprocess::scale_chain(processing.chain, factor), tile.raster,
                                  grid.border() - (kKeptBorder - 1), &stats, inline_executor));
    for (const ElevationLens& lens : processing.lenses) {
      const std::vector<uint8_t> in = inside(lens, key, out.width(), out.height());
      if (std::ranges::none_of(in, [](uint8_t v) { return v != 0; })) continue;
      const tiles::Raster l = RELIEF_TRY(
          gpuprocess::run_chain_cpu(gpuprocess::scale_chain(lens.chain, factor), tile.raster,
                                    grid.border() - (kKeptBorder - 1), &stats, inline_executor));
      const auto src = l.f32();
      const auto dst = out.f32();
      for (size_t i = 0; i < in.size(); ++i) {
        if (in[i]) dst[i] = src[i];
      }
    }
    return std::make_shared<const tiles::Raster>(std::move(out));
  }

  Result<std::vector<std::byte>> encoded(const geo::TileKey& key) const {
    if (!input.has_tile(key)) {
      return fail(fmt::format("{}: no tile {}", input.root().string(), key.to_string()));
    }
    const RasterPtr r = RELIEF_TRY(processed(key));
    return tiles::encode_tile(*r, kKeptBorder, codec);
  }
};

// The pass that builds the indexes: every processed tile once (the error pass
// compares every finest tile with each of its ancestors, so the tiles with
// children are kept until the indexes are built; concurrent requests for one
// wait for one processing), each tile's index entry from its samples, and the
// statistics of the finest level's.
class OpenPass {
 public:
  OpenPass(const Processing& p, std::unordered_set<geo::TileKey, geo::TileKeyHash> keep)
      : p_(p), keep_(std::move(keep)) {}

  Result<RasterPtr> read(const geo::TileKey& key) {
    if (!keep_.contains(key)) return seen(key, p_.processed(key));
    std::shared_ptr<Slot> slot;
    {
      std::lock_guard lock(mutex_);
      std::shared_ptr<Slot>& s = slots_[key];
      if (!s) s = std::make_shared<Slot>();
      slot = s;
    }
    std::lock_guard lock(slot->mutex);
    if (!slot->value) slot->value = seen(key, p_.processed(key));
    return *slot->value;
  }

  // The entry of a tile (processed now if the error pass did not reach it).
  Result<tiles::IndexEntry> entry(const geo::TileKey& key) {
    {
      std::lock_guard lock(mutex_);
      if (auto it = entries_.find(key); it != entries_.end()) return it->second;
    }
    RELIEF_TRY(read(key));
    std::lock_guard lock(mutex_);
    return entries_.at(key);
  }

  // Statistics of the valid interior samples of the finest level.
  tiles::SampleStats finest_stats() const {
    if (count_ == 0) return {};
    tiles::SampleStats s;
    const double n = static_cast<double>(count_);
    s.min = min_, s.max = max_, s.valid_count = count_;
    s.mean = sum_ / n;
    s.stddev = std::sqrt(std::max(0.0, sum2_ / n - s.mean * s.mean));
    return s;
  }

 private:
  struct Slot {
    std::mutex mutex;
    std::optional<Result<RasterPtr>> value;
  };

  Result<RasterPtr> seen(const geo::TileKey& key, Result<RasterPtr> tile) {
    if (!tile) return tile;
    const int w = p_.grid.width(), h = p_.grid.height();
    tiles::TileHeader header;
    header.stats = (*tile)->stats(kKeptBorder, kKeptBorder, w, h);
    const tiles::IndexEntry e =
        tiles::index_entry_for(key, header, p_.input.index(key.level).find(key)->file_bytes);
    std::lock_guard lock(mutex_);
    if (!entries_.emplace(key, e).second || key.level != p_.max_level) return tile;
    const tiles::SampleStats& s = header.stats;
    if (s.valid_count > 0) {
      const double n = static_cast<double>(s.valid_count);
      count_ += s.valid_count;
      min_ = std::min(min_, s.min), max_ = std::max(max_, s.max);
      sum_ += n * s.mean;
      sum2_ += n * (s.stddev * s.stddev + s.mean * s.mean);
    }
    return tile;
  }

  const Processing& p_;
  std::unordered_set<geo::TileKey, geo::TileKeyHash> keep_;
  std::mutex mutex_;
  std::map<geo::TileKey, std::shared_ptr<Slot>> slots_;
  std::unordered_map<geo::TileKey, tiles::IndexEntry, geo::TileKeyHash> entries_;
  uint64_t count_ = 0;
  double min_ = INFINITY, max_ = -INFINITY, sum_ = 0, sum2_ = 0;
};

// The chain's margins within the input's border less the kept border, else
// a one-line error naming the step that overflows.
Status check_room(const gpuprocess::OperatorChain& chain, int border, const std::string& name) {
  const int room = border - kKeptBorder;
  if (room < 0) {
    return fail(fmt::format("{}: a {}-sample border; processed heights need at least {}", name,
                            border, kKeptBorder));
  }
  int used = 0;
  for (const gpuprocess::ChainStep& s : chain.steps) {
    const int m = process::margin_of(*s.op, s.params);
    used += m;
    if (used > room) {
      return fail(fmt::format(
          "{}: {}: needs a {}-sample margin ({} for the chain so far), more than the {} of the "
          "store's {}-sample overlap border left after the {} samples the processed heights keep",
          name, s.op->name, m, used, room, border, kKeptBorder));
    }
  }
  return {};
}

// Operators valid for heights only: the SAR-only ones named (before the
// margins: a tone mapping's default radius may be the first thing wrong).
Status check_kinds(const gpuprocess::OperatorChain& chain, const std::string& name) {
  for (const gpuprocess::ChainStep& s : chain.steps) {
    if (s.op->sar_only) {
      return fail(
          fmt::format("{}: operator {} expects {}, but the store holds elevation data (heights "
                      "take mean, gauss or median)",
                      name, s.op->name, s.op->input));
    }
  }
  return {};
}

std::string describe(const gpuprocess::OperatorChain& chain) {
  std::string text;
  for (const gpuprocess::ChainStep& s : chain.steps) {
    text += (text.empty() ? "" : " ") + s.op->name;
    for (const auto& [k, v] : s.params) text += fmt::format(" {}={}", k, v);
  }
  return text.empty() ? "none" : text;
}

}  // namespace

double lens_distance_m(double lon0, double lat0, double lon, double lat) {
  return geo::tangent_plane_distance_m(lon0, lat0, lon, lat);
}

Status check_elevation_processing(const ElevationProcessing& processing,
                                  const tiles::Manifest& manifest, const std::string& name) {
  if (manifest.kind != tiles::DatasetKind::Elevation) {
    return fail(fmt::format("{}: holds {} data; elevation operators process an elevation store",
                            name, tiles::to_string(manifest.kind)));
  }
  RELIEF_CHECK(check_kinds(processing.chain, name));
  RELIEF_CHECK(check_room(processing.chain, manifest.border, name));
  RELIEF_CHECK(gpuprocess::check_chain_for(processing.chain, manifest, name));
  for (const ElevationLens& lens : processing.lenses) {
    if (!(lens.radius_m > 0) || !std::isfinite(lens.radius_m)) {
      return fail(
          fmt::format("{}: an elevation lens radius must be > 0 m, not {}", name, lens.radius_m));
    }
    if (!(std::abs(lens.lat) <= 90) || !(std::abs(lens.lon) <= 360)) {
      return fail(fmt::format("{}: elevation lens centre {},{} is not a longitude, latitude", name,
                              lens.lon, lens.lat));
    }
    RELIEF_CHECK(check_kinds(lens.chain, name + " (elevation lens)"));
    RELIEF_CHECK(check_room(lens.chain, manifest.border, name + " (elevation lens)"));
    RELIEF_CHECK(gpuprocess::check_chain_for(lens.chain, manifest, name + " (elevation lens)"));
  }
  return {};
}

Result<tiles::Store> process_elevation(tiles::Store store, const std::string& name,
                                       ElevationProcessing processing, Executor& executor) {
  const tiles::Manifest& in = store.manifest();
  RELIEF_CHECK(check_elevation_processing(processing, in, name));
  if (in.sparse_depth) {
    return fail(fmt::format(
        "{}: elevation layers of different depths cannot be processed at draw time yet", name));
  }
  auto shared = std::make_shared<Processing>();
  shared->grid = store.grid();
  shared->max_level = in.max_level;
  shared->stats = {in.stats.min, in.stats.max, in.stats.mean, in.stats.stddev};
  shared->processing = std::move(processing);
  shared->input = std::move(store);

  tiles::Manifest manifest = shared->input.manifest();
  manifest.border = kKeptBorder;
  manifest.codec = shared->codec;
  std::string described = "elevation processed at draw time: " + describe(shared->processing.chain);
  for (const ElevationLens& l : shared->processing.lenses) {
    described += fmt::format("; lens {},{} {} m: {}", l.lon, l.lat, l.radius_m, describe(l.chain));
  }
  manifest.created_by = described;

  // The input's tiles, their bounds and exact geometric errors from the
  // processed samples (the input's errors do not bound a smoothed mesh).
  std::vector<tiles::LevelIndex> indices;
  std::unordered_set<geo::TileKey, geo::TileKeyHash> parents;
  for (int level = manifest.min_level; level <= manifest.max_level; ++level) {
    tiles::LevelIndex index(level);
    for (const tiles::IndexEntry& e : shared->input.index(level).entries()) {
      index.add({e.key});
      if (e.key.level > manifest.min_level) parents.insert(*e.key.parent());
    }
    indices.push_back(std::move(index));
  }
  OpenPass pass(*shared, std::move(parents));
  const tiles::BorderedTileReader read = [&pass](const geo::TileKey& key) {
    return pass.read(key);
  };
  NullProgress progress;
  RELIEF_CHECK(tiles::compute_geometric_errors(indices, *tiles::tile_shape_of(manifest), read,
                                               executor, progress));
  for (tiles::LevelIndex& index : indices) {
    tiles::LevelIndex complete(index.level());
    for (const tiles::IndexEntry& e : index.entries()) {
      tiles::IndexEntry entry = RELIEF_TRY(pass.entry(e.key));
      entry.error = e.error;
      complete.add(entry);
    }
    index = std::move(complete);
  }
  manifest.stats = pass.finest_stats();

  return open_memory_store(name, manifest, indices,
                           [shared](const geo::TileKey& key) { return shared->encoded(key); });
}

}  // namespace relief::pipeline
