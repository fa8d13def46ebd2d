#include "relief/pipeline/fused_elevation.h"

#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "relief/base/first_error.h"
#include "relief/base/progress.h"
#include "relief/tiles/geometric_error.h"
#include "relief/tiles/store_layout.h"

namespace relief::pipeline {
namespace {

using RasterPtr = std::shared_ptr<const tiles::Raster>;

struct Layers {
  std::vector<ElevationLayer> layers;
  FuseMode mode = FuseMode::First;
  std::vector<double> weights;
  geo::TileGrid grid;
  // Fused tiles are encoded only to pass through tiles::Store: fast and
  // lossless, so the decoded samples are the fused ones.
  tiles::CodecOptions codec{tiles::Codec::Zstd, 0.0, 90, 1};

  // The fused bordered tile, nodata as NaN; null where no layer has it.
  Result<RasterPtr> fused(const geo::TileKey& key) const {
    std::vector<tiles::Tile> held;
    held.reserve(layers.size());
    std::vector<const tiles::Raster*> rasters(layers.size(), nullptr);
    for (size_t i = 0; i < layers.size(); ++i) {
      if (!layers[i].store.has_tile(key)) continue;
      held.push_back(RELIEF_TRY(layers[i].store.read_tile(key)));
      rasters[i] = &held.back().raster;
    }
    if (held.empty()) return RasterPtr{};
    if (held.size() == 1) return std::make_shared<const tiles::Raster>(std::move(held[0].raster));
    auto out = std::make_shared<tiles::Raster>(tiles::Raster::empty(
        tiles::SampleType::Float32, grid.padded_width(), grid.padded_height()));
    fuse_float(rasters, weights, mode, *out);
    return RasterPtr(std::move(out));
  }

  Result<std::vector<std::byte>> encoded(const geo::TileKey& key) const {
    const RasterPtr r = RELIEF_TRY(fused(key));
    if (!r) return fail(fmt::format("tile {} is in none of the layers", key.to_string()));
    return tiles::encode_tile(*r, grid.border(), codec);
  }
};

// Serves the fused store's files from memory (manifest, level indexes) and
// fuses its tiles when fetched.
class FusedSource final : public tiles::StoreSource {
 public:
  FusedSource(std::string name, std::shared_ptr<const Layers> layers, std::string manifest,
              std::vector<std::vector<std::byte>> indices)
      : name_(std::move(name)),
        layers_(std::move(layers)),
        manifest_(std::move(manifest)),
        indices_(std::move(indices)) {}

  std::string name() const override { return name_; }

  Result<std::vector<std::byte>> fetch(const std::string& relative) const override {
    if (relative == tiles::kManifestName) {
      const auto* p = reinterpret_cast<const std::byte*>(manifest_.data());
      return std::vector<std::byte>(p, p + manifest_.size());
    }
    for (size_t level = 0; level < indices_.size(); ++level) {
      if (relative == tiles::level_index_relative_path(static_cast<int>(level))) {
        return indices_[level];
      }
    }
    const auto key = tiles::tile_key_from_relative_path(relative);
    if (!key) return fail(fmt::format("{}/{}: no such file", name_, relative));
    return layers_->encoded(*key);
  }

 private:
  std::string name_;
  std::shared_ptr<const Layers> layers_;
  std::string manifest_;
  std::vector<std::vector<std::byte>> indices_;
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
  if (m.max_level != first.max_level) {
    return fail(fmt::format(
        "{}: finest level {} differs from the first elevation layer's {}; layers of different "
        "depths are not fused at draw time yet (relief fuse --allow-upsampling does it offline)",
        layer.name, m.max_level, first.max_level));
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

}  // namespace

Result<tiles::Store> fuse_elevation_layers(std::vector<ElevationLayer> layers, FuseMode mode,
                                           Executor& executor) {
  if (layers.empty()) return fail("elevation layers: none given");
  for (const ElevationLayer& l : layers) RELIEF_CHECK(check_layer(layers[0].store.manifest(), l));
  tiles::Manifest manifest = layers[0].store.manifest();
  std::string name = layers[0].name;
  for (size_t i = 1; i < layers.size(); ++i) {
    const tiles::Manifest& m = layers[i].store.manifest();
    manifest.min_level = std::min(manifest.min_level, m.min_level);
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
  shared->weights.assign(layers.size(), 1.0);
  shared->layers = std::move(layers);
  manifest.codec = shared->codec;

  // Per level: the union of the layers' tiles, bounds from the fused samples.
  std::vector<tiles::LevelIndex> indices;
  for (int level = manifest.min_level; level <= manifest.max_level; ++level) {
    std::vector<geo::TileKey> keys;
    for (const ElevationLayer& l : shared->layers) {
      for (const tiles::IndexEntry& e : l.store.index(level).entries()) keys.push_back(e.key);
    }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    std::vector<tiles::IndexEntry> entries(keys.size());
    FirstError error;
    executor.parallel_for(keys.size(), [&](size_t k) {
      auto bytes = shared->encoded(keys[k]);
      if (!bytes) return error.set(bytes.error());
      auto header = tiles::parse_tile_header(*bytes, name);
      if (!header) return error.set(header.error());
      entries[k] = tiles::index_entry_for(keys[k], *header, bytes->size());
    });
    RELIEF_CHECK(error.status());
    tiles::LevelIndex index(level);
    for (const tiles::IndexEntry& e : entries) index.add(e);
    indices.push_back(std::move(index));
  }
  // Exact geometric errors of the fused pyramid, as `relief build` computes
  // a store's: fusing changes the coarse tiles and the finest data alike, so
  // the layers' own errors do not bound the fused mesh.
  NullProgress progress;
  const tiles::TileShape shape = *tiles::tile_shape_of(manifest);
  RELIEF_CHECK(tiles::compute_geometric_errors(
      indices, shape, [&shared](const geo::TileKey& key) { return shared->fused(key); }, executor,
      progress));

  std::vector<std::vector<std::byte>> serialized(static_cast<size_t>(manifest.max_level) + 1);
  for (tiles::LevelIndex& index : indices) {
    serialized[static_cast<size_t>(index.level())] = index.serialize();
  }
  auto source = std::make_shared<const FusedSource>(name, std::move(shared), manifest.to_json(),
                                                    std::move(serialized));
  return tiles::Store::open(std::move(source));
}

}  // namespace relief::pipeline
