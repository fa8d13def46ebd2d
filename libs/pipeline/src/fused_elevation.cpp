#include "relief/pipeline/fused_elevation.h"

#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include <fmt/format.h>

#include "relief/base/progress.h"
#include "relief/tiles/geometric_error.h"
#include "relief/tiles/store_layout.h"

#include "memory_store.h"

namespace relief::pipeline {
namespace {

using RasterPtr = std::shared_ptr<const tiles::Raster>;

// Layer tiles read while the layers are opened. The error pass compares every
// finest tile with each of its ancestors, and upsampled tiles share their
// source tile: the layer tiles with a child in the fused store are kept until
// the indexes are built, so that opening reads every layer tile once (the
// others are read once anyway). Concurrent requests for one tile wait for
// one read.
class OpenCache {
 public:
  explicit OpenCache(std::unordered_set<geo::TileKey, geo::TileKeyHash> keep)
      : keep_(std::move(keep)) {}

  Result<RasterPtr> get(size_t layer, const geo::TileKey& key,
                        const std::function<Result<RasterPtr>()>& read) {
    if (!keep_.contains(key)) return read();
    std::shared_ptr<Slot> slot;
    {
      std::lock_guard lock(mutex_);
      std::shared_ptr<Slot>& s = slots_[{layer, key}];
      if (!s) s = std::make_shared<Slot>();
      slot = s;
    }
    std::lock_guard lock(slot->mutex);
    if (!slot->value) slot->value = read();
    return *slot->value;
  }

 private:
  struct Slot {
    std::mutex mutex;
    std::optional<Result<RasterPtr>> value;
  };
  std::unordered_set<geo::TileKey, geo::TileKeyHash> keep_;
  std::mutex mutex_;
  std::map<std::pair<size_t, geo::TileKey>, std::shared_ptr<Slot>> slots_;
};

struct Layers {
  std::vector<ElevationLayer> layers;
  FuseMode mode = FuseMode::First;
  std::vector<double> weights;
  geo::TileGrid grid;
  // Fused tiles are encoded only to pass through tiles::Store: fast and
  // lossless, so the decoded samples are the fused ones.
  tiles::CodecOptions codec{tiles::Codec::Zstd, 0.0, 90, 1};

  // The layers in the order their samples are taken: the deeper first (a
  // layer upsampled beyond its finest level never hides finer data), then in
  // the order given.
  std::vector<size_t> order;

  // Layer i's own tile at `key` (through `cache` while opening).
  Result<RasterPtr> read(size_t i, const geo::TileKey& key, OpenCache* cache) const {
    auto read_once = [this, i, &key]() -> Result<RasterPtr> {
      return std::make_shared<const tiles::Raster>(
          RELIEF_TRY(layers[i].store.read_tile(key)).raster);
    };
    return cache ? cache->get(i, key, read_once) : read_once();
  }

  // Where layer i's data at `key` comes from: its own tile, or below its
  // finest level its finest tile there; nullopt where it has none.
  std::optional<geo::TileKey> source_of(size_t i, const geo::TileKey& key) const {
    const int m = std::max(0, key.level - layers[i].store.manifest().max_level);
    const geo::TileKey a{key.level - m, key.x >> m, key.y >> m};
    if (!layers[i].store.has_tile(a)) return std::nullopt;
    return a;
  }

  // Layer i's tile at `key`: its own, or below its finest level its finest
  // tile there upsampled (pipeline/fuse_tiles.h); null where it has no data.
  Result<RasterPtr> layer_tile(size_t i, const geo::TileKey& key, OpenCache* cache) const {
    const auto a = source_of(i, key);
    if (!a) return RasterPtr{};
    const RasterPtr t = RELIEF_TRY(read(i, *a, cache));
    if (a->level == key.level) return t;
    return std::make_shared<const tiles::Raster>(upsample(*t, *a, key, grid));
  }

  // Whether some layer has data at `key` (its own tile, or its finest above).
  bool has_data(const geo::TileKey& key) const {
    for (size_t i = 0; i < layers.size(); ++i) {
      if (source_of(i, key)) return true;
    }
    return false;
  }

  // The bytes of the layers' tiles that make the fused tile at `key`: what
  // the fused store's index says a tile costs to fetch (it is encoded only
  // when fetched).
  uint64_t source_bytes(const geo::TileKey& key) const {
    uint64_t bytes = 0;
    for (size_t i = 0; i < layers.size(); ++i) {
      if (const auto a = source_of(i, key)) {
        bytes += layers[i].store.index(a->level).find(*a)->file_bytes;
      }
    }
    return bytes;
  }

  // The fused bordered tile, nodata as NaN; null where no layer has it.
  Result<RasterPtr> fused(const geo::TileKey& key, OpenCache* cache = nullptr) const {
    std::vector<RasterPtr> held;
    std::vector<const tiles::Raster*> rasters;
    std::vector<double> w;
    for (size_t i : order) {
      RasterPtr r = RELIEF_TRY(layer_tile(i, key, cache));
      if (!r) continue;
      rasters.push_back(r.get());
      w.push_back(weights[i]);
      held.push_back(std::move(r));
    }
    if (held.empty()) return RasterPtr{};
    if (held.size() == 1) return held[0];
    auto out = std::make_shared<tiles::Raster>(tiles::Raster::empty(
        tiles::SampleType::Float32, grid.padded_width(), grid.padded_height()));
    fuse_float(rasters, w, mode, *out);
    return RasterPtr(std::move(out));
  }

  Result<std::vector<std::byte>> encoded(const geo::TileKey& key) const {
    const RasterPtr r = RELIEF_TRY(fused(key));
    if (!r) return fail(fmt::format("tile {} is in none of the layers", key.to_string()));
    return tiles::encode_tile(*r, grid.border(), codec);
  }
};

Status check_layer(const tiles::Manifest& first, const ElevationLayer& layer) {
  const tiles::Manifest& m = layer.store.manifest();
  if (m.kind != tiles::DatasetKind::Elevation) {
    return fail(fmt::format("{}: holds {} data; an elevation layer must be an elevation store",
                            layer.name, tiles::to_string(m.kind)));
  }
  if (m.tile_log2_height != first.tile_log2_height || m.border != first.border) {
    return fail(fmt::format("{}: tile size or border differs from the first elevation layer's",
                            layer.name));
  }
  return {};
}

// Statistics of the union of the layers' samples (overlaps counted twice:
// they describe the data, not one sample per place).
tiles::SampleStats pooled_stats(const std::vector<ElevationLayer>& layers) {
  tiles::SampleStats s{INFINITY, -INFINITY, 0, 0, 0};
  double sum = 0, sum2 = 0;
  for (const ElevationLayer& l : layers) {
    const tiles::SampleStats& t = l.store.manifest().stats;
    if (t.valid_count == 0) continue;
    const double n = static_cast<double>(t.valid_count);
    s.min = std::min(s.min, t.min);
    s.max = std::max(s.max, t.max);
    s.valid_count += t.valid_count;
    sum += n * t.mean;
    sum2 += n * (t.stddev * t.stddev + t.mean * t.mean);
  }
  if (s.valid_count == 0) return {};
  const double n = static_cast<double>(s.valid_count);
  s.mean = sum / n;
  s.stddev = std::sqrt(std::max(0.0, sum2 / n - s.mean * s.mean));
  return s;
}

// The tiles of the fused store, per level (index = level). With layers of
// different depths (sparse depth, docs/rendering.md), a quad below a tile
// without children draws that tile's window, so data levels change where the
// finer layer ends. The fused store therefore also holds, where some layer
// has data (upsampled coarse data where the fine layer has none):
// - the four children of the parent of each tile, so a tile has no child or
//   every child with data (a missing one has none): edge-mark refinement
//   splits a quad only into children with tiles of their own;
// - the eight neighbours of the parent of each tile, so two touching quads
//   never draw data more than one level apart and each side can take the
//   coarser one, and a restricted quadtree never splits a tile without
//   children.
std::vector<std::vector<geo::TileKey>> tile_keys(const Layers& layers,
                                                 const tiles::Manifest& manifest) {
  std::vector<std::set<geo::TileKey>> sets(static_cast<size_t>(manifest.max_level) + 1);
  for (const ElevationLayer& l : layers.layers) {
    for (int level = l.store.manifest().min_level; level <= l.store.manifest().max_level; ++level) {
      for (const tiles::IndexEntry& e : l.store.index(level).entries()) {
        sets[static_cast<size_t>(level)].insert(e.key);
      }
    }
  }
  auto add = [&](const std::optional<geo::TileKey>& key) {
    if (key && layers.has_data(*key)) sets[static_cast<size_t>(key->level)].insert(*key);
  };
  for (int level = manifest.max_level; manifest.sparse_depth && level > manifest.min_level;
       --level) {
    std::set<geo::TileKey>& here = sets[static_cast<size_t>(level)];
    for (const geo::TileKey& key : std::vector<geo::TileKey>(here.begin(), here.end())) {
      const geo::TileKey parent = *key.parent();
      for (int c = 0; c < 4; ++c) add(parent.child(c & 1, c >> 1));
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) add(parent.neighbour(dx, dy));
      }
    }
  }
  std::vector<std::vector<geo::TileKey>> keys;
  for (const auto& s : sets) keys.emplace_back(s.begin(), s.end());
  return keys;
}

// Geometric errors where the finest data is not at one level: below a tile
// without child tiles, the data is that tile's (a leaf). Each level's leaves
// are compared with every ancestor as the finest level's tiles are
// (tiles/geometric_error.h), and a tile's error is the largest it gets from
// any level. Tiles with one to three children count as leaves too (their
// missing children have no data: comparing their whole tile only adds
// distances to samples that are not the finest, still an upper bound).
Status sparse_geometric_errors(std::vector<tiles::LevelIndex>& indices,
                               const tiles::TileShape& shape, const tiles::BorderedTileReader& read,
                               Executor& executor) {
  std::vector<std::unordered_map<geo::TileKey, float, geo::TileKeyHash>> worst(indices.size());
  for (size_t l = 1; l < indices.size(); ++l) {
    tiles::LevelIndex leaves(indices[l].level());
    for (const tiles::IndexEntry& e : indices[l].entries()) {
      int children = 0;
      for (int c = 0; l + 1 < indices.size() && c < 4; ++c) {
        children += indices[l + 1].find(e.key.child(c & 1, c >> 1)) != nullptr;
      }
      if (children < 4) leaves.add(e);
    }
    if (leaves.size() == 0) continue;
    std::vector<tiles::LevelIndex> pass(indices.begin(), indices.begin() + static_cast<long>(l));
    pass.push_back(std::move(leaves));
    NullProgress progress;
    RELIEF_CHECK(tiles::compute_geometric_errors(pass, shape, read, executor, progress));
    for (size_t a = 0; a < l; ++a) {
      for (const tiles::IndexEntry& e : pass[a].entries()) {
        float& w = worst[a][e.key];
        w = std::max(w, e.error);
      }
    }
  }
  for (size_t l = 0; l < indices.size(); ++l) {
    const auto entries = indices[l].entries();  // a copy: set_error edits them
    for (const tiles::IndexEntry& e : entries) {
      const auto it = worst[l].find(e.key);
      indices[l].set_error(e.key, it == worst[l].end() ? 0.0f : it->second);
    }
  }
  return {};
}

// The index entries of fused tiles from their samples, noted as the error
// pass reads them (a tile no finest tile reaches is read when asked for).
class FusedBounds {
 public:
  Result<RasterPtr> seen(const geo::TileKey& key, Result<RasterPtr> tile, const Layers& layers) {
    if (!tile || !*tile) return tile;
    {
      std::lock_guard lock(mutex_);
      if (entries_.contains(key)) return tile;
    }
    const int b = layers.grid.border();
    tiles::TileHeader header;
    header.stats = (*tile)->stats(b, b, layers.grid.width(), layers.grid.height());
    const tiles::IndexEntry e = tiles::index_entry_for(key, header, layers.source_bytes(key));
    std::lock_guard lock(mutex_);
    entries_.emplace(key, e);
    return tile;
  }

  Result<tiles::IndexEntry> entry(const geo::TileKey& key, const tiles::BorderedTileReader& read,
                                  const Layers& layers) {
    if (!find(key)) {
      const RasterPtr tile = RELIEF_TRY(read(key));
      if (!tile)
        return fail(fmt::format("{}: tile {} is in none of the layers", layers.layers[0].name,
                                key.to_string()));
    }
    return *find(key);
  }

 private:
  const tiles::IndexEntry* find(const geo::TileKey& key) {
    std::lock_guard lock(mutex_);
    const auto it = entries_.find(key);
    return it == entries_.end() ? nullptr : &it->second;
  }
  std::mutex mutex_;
  std::unordered_map<geo::TileKey, tiles::IndexEntry, geo::TileKeyHash> entries_;
};

}  // namespace

Result<tiles::Store> fuse_elevation_layers(std::vector<ElevationLayer> layers, FuseMode mode,
                                           Executor& executor, std::vector<double> weights) {
  if (layers.empty()) return fail("elevation layers: none given");
  weights = RELIEF_TRY(fuse_weights(std::move(weights), layers.size(), "elevation layers"));
  for (const ElevationLayer& l : layers) RELIEF_CHECK(check_layer(layers[0].store.manifest(), l));
  tiles::Manifest manifest = layers[0].store.manifest();
  std::string name = layers[0].name;
  for (size_t i = 1; i < layers.size(); ++i) {
    const tiles::Manifest& m = layers[i].store.manifest();
    manifest.min_level = std::min(manifest.min_level, m.min_level);
    manifest.max_level = std::max(manifest.max_level, m.max_level);
    manifest.sparse_depth |= m.max_level != layers[0].store.manifest().max_level;
    manifest.extent.west = std::min(manifest.extent.west, m.extent.west);
    manifest.extent.south = std::min(manifest.extent.south, m.extent.south);
    manifest.extent.east = std::max(manifest.extent.east, m.extent.east);
    manifest.extent.north = std::max(manifest.extent.north, m.extent.north);
    for (const auto& src : m.sources) manifest.sources.push_back(src);
    name += "+" + layers[i].name;
  }
  manifest.stats = pooled_stats(layers);
  manifest.created_by = "elevation layers fused at draw time";

  auto shared = std::make_shared<Layers>();
  shared->grid = layers[0].store.grid();
  shared->mode = mode;
  shared->weights = std::move(weights);
  for (size_t i = 0; i < layers.size(); ++i) shared->order.push_back(i);
  std::stable_sort(shared->order.begin(), shared->order.end(), [&layers](size_t a, size_t b) {
    return layers[a].store.manifest().max_level > layers[b].store.manifest().max_level;
  });
  shared->layers = std::move(layers);
  manifest.codec = shared->codec;

  // Per level: the union of the layers' tiles (plus, for layers of different
  // depths, the padding that keeps neighbouring data levels one apart).
  const std::vector<std::vector<geo::TileKey>> keys = tile_keys(*shared, manifest);
  std::vector<tiles::LevelIndex> indices;
  std::unordered_set<geo::TileKey, geo::TileKeyHash> parents;
  for (int level = manifest.min_level; level <= manifest.max_level; ++level) {
    tiles::LevelIndex index(level);
    for (const geo::TileKey& key : keys[static_cast<size_t>(level)]) {
      index.add({key});
      if (key.level > manifest.min_level) parents.insert(*key.parent());
    }
    indices.push_back(std::move(index));
  }
  // Exact geometric errors of the fused pyramid, as `relief build` computes
  // a store's: fusing changes the coarse tiles and the finest data alike, so
  // the layers' own errors do not bound the fused mesh. The one pass over the
  // fused tiles that needs also gives each tile's bounds; nothing is encoded.
  OpenCache cache(std::move(parents));
  FusedBounds bounds;
  const tiles::BorderedTileReader read = [&shared, &cache, &bounds](const geo::TileKey& key) {
    return bounds.seen(key, shared->fused(key, &cache), *shared);
  };
  const tiles::TileShape shape = *tiles::tile_shape_of(manifest);
  if (manifest.sparse_depth) {
    RELIEF_CHECK(sparse_geometric_errors(indices, shape, read, executor));
  } else {
    NullProgress progress;
    RELIEF_CHECK(tiles::compute_geometric_errors(indices, shape, read, executor, progress));
  }
  for (tiles::LevelIndex& index : indices) {
    tiles::LevelIndex complete(index.level());
    for (const tiles::IndexEntry& e : index.entries()) {
      tiles::IndexEntry entry = RELIEF_TRY(bounds.entry(e.key, read, *shared));
      entry.error = e.error;
      complete.add(entry);
    }
    index = std::move(complete);
  }

  return open_memory_store(name, manifest, indices,
                           [shared](const geo::TileKey& key) { return shared->encoded(key); });
}

}  // namespace relief::pipeline
