#include "relief/pipeline/fuse_stores.h"

#include <algorithm>
#include <cmath>
#include <set>

#include <fmt/format.h>

#include "relief/base/first_error.h"
#include "relief/pipeline/fuse_tiles.h"
#include "store_output.h"

namespace relief::pipeline {
namespace {

namespace fs = std::filesystem;

Status check_compatible(const tiles::Manifest& first, const tiles::Manifest& m,
                        const fs::path& name) {
  if (m.kind != first.kind) {
    return fail(fmt::format("{}: holds {} data, the first input {}", name.string(),
                            tiles::to_string(m.kind), tiles::to_string(first.kind)));
  }
  if (m.sample_type != first.sample_type || m.tile_log2_height != first.tile_log2_height ||
      m.border != first.border) {
    return fail(fmt::format("{}: tile size, border or sample type differs from the first input",
                            name.string()));
  }
  return {};
}

// RGBA: colours weighted by weight * alpha; alpha the largest of the inputs'.
void fuse_rgba(const std::vector<const tiles::Raster*>& in, const std::vector<double>& weights,
               FuseMode mode, tiles::Raster& out) {
  auto dst = out.u8();
  for (size_t p = 0; p < out.pixel_count(); ++p) {
    double sum[3] = {0, 0, 0}, wsum = 0;
    uint8_t alpha = 0;
    for (size_t i = 0; i < in.size(); ++i) {
      if (!in[i]) continue;
      const uint8_t* px = &in[i]->u8()[p * 4];
      if (px[3] == 0) continue;
      const double w = weights[i] * px[3];
      for (int c = 0; c < 3; ++c) sum[c] += w * px[c];
      wsum += w;
      alpha = std::max(alpha, px[3]);
      if (mode == FuseMode::First) break;
    }
    for (int c = 0; c < 3; ++c) {
      dst[p * 4 + c] = wsum > 0 ? static_cast<uint8_t>(std::lround(sum[c] / wsum)) : 0;
    }
    dst[p * 4 + 3] = alpha;
  }
}

// See FuseOptions::allow_upsampling. Counts are upper bounds (inputs may
// overlap), in double: 4^20 descendants of a tile do not fit 32 bits.
Status check_upsampling(const std::vector<tiles::Store>& stores,
                        const std::vector<std::filesystem::path>& paths, int max_level) {
  double own = 0, upsampled = 0;
  size_t worst = 0;
  double worst_tiles = 0;
  for (size_t i = 0; i < stores.size(); ++i) {
    const tiles::Manifest& m = stores[i].manifest();
    for (int level = m.min_level; level <= m.max_level; ++level) {
      own += static_cast<double>(stores[i].index(level).entries().size());
    }
    double tiles = 0;
    const double finest = static_cast<double>(stores[i].index(m.max_level).entries().size());
    for (int level = m.max_level + 1; level <= max_level; ++level) {
      tiles += finest * std::ldexp(1.0, 2 * (level - m.max_level));
    }
    upsampled += tiles;
    if (tiles > worst_tiles) worst_tiles = tiles, worst = i;
  }
  if (upsampled <= 4 * own) return {};
  return fail(fmt::format(
      "fuse: {} stops at level {} but the result goes to level {}: it would be upsampled into "
      "~{:.0f} interpolated tiles (the inputs hold {:.0f}); fuse stores of similar resolution, or "
      "pass --allow-upsampling",
      paths[worst].string(), stores[worst].manifest().max_level, max_level, upsampled, own));
}

geo::TileKey ancestor_at(geo::TileKey key, int level) {
  while (key.level > level) key = *key.parent();
  return key;
}

}  // namespace

Result<FuseReport> fuse_stores(const FuseOptions& o, Executor& executor, Progress& progress) {
  if (o.inputs.size() < 2) return fail("fuse: needs at least two input stores");
  const std::vector<double> weights =
      RELIEF_TRY(fuse_weights(o.weights, o.inputs.size(), "inputs"));
  std::vector<tiles::Store> stores;
  for (const auto& path : o.inputs) {
    stores.push_back(RELIEF_TRY(tiles::Store::open(path)));
    RELIEF_CHECK(check_compatible(stores.front().manifest(), stores.back().manifest(), path));
  }
  tiles::Manifest manifest = stores.front().manifest();
  for (const auto& s : stores) {
    const tiles::Manifest& m = s.manifest();
    manifest.min_level = std::min(manifest.min_level, m.min_level);
    manifest.max_level = std::max(manifest.max_level, m.max_level);
    manifest.extent.west = std::min(manifest.extent.west, m.extent.west);
    manifest.extent.south = std::min(manifest.extent.south, m.extent.south);
    manifest.extent.east = std::max(manifest.extent.east, m.extent.east);
    manifest.extent.north = std::max(manifest.extent.north, m.extent.north);
  }
  manifest.sources.clear();
  for (const auto& s : stores) {
    for (const auto& src : s.manifest().sources) manifest.sources.push_back(src);
  }
  manifest.created_by = "relief fuse";
  if (!o.allow_upsampling) RELIEF_CHECK(check_upsampling(stores, o.inputs, manifest.max_level));
  StoreOutput output =
      RELIEF_TRY(StoreOutput::create(o.output, manifest.min_level, manifest.max_level));
  const int border = manifest.border;
  const geo::TileGrid& grid = stores.front().grid();

  for (int level = manifest.min_level; level <= manifest.max_level; ++level) {
    std::set<geo::TileKey> union_keys;
    for (const auto& s : stores) {
      const int finest = s.manifest().max_level;
      if (level <= finest) {
        for (const auto& e : s.index(level).entries()) union_keys.insert(e.key);
        continue;
      }
      // Below an input's finest level: every descendant of its finest tiles.
      const uint32_t n = 1u << (level - finest);
      for (const auto& e : s.index(finest).entries()) {
        for (uint32_t dy = 0; dy < n; ++dy) {
          for (uint32_t dx = 0; dx < n; ++dx) {
            union_keys.insert({level, e.key.x * n + dx, e.key.y * n + dy});
          }
        }
      }
    }
    const std::vector<geo::TileKey> keys(union_keys.begin(), union_keys.end());
    progress.begin(fmt::format("fuse level {}", level), keys.size());
    FirstError error;
    executor.parallel_for(keys.size(), [&](size_t k) {
      const geo::TileKey& key = keys[k];
      std::vector<tiles::Tile> held;
      held.reserve(stores.size());
      std::vector<const tiles::Raster*> rasters(stores.size(), nullptr);
      // The fused bounds lie within the inputs' bounds: no scan needed.
      tiles::IndexEntry bounds{key, INFINITY, -INFINITY, 0, 0};
      for (size_t i = 0; i < stores.size(); ++i) {
        const int finest = stores[i].manifest().max_level;
        const geo::TileKey source = ancestor_at(key, finest);
        const tiles::IndexEntry* e = stores[i].index(source.level).find(source);
        if (!e) continue;
        auto tile = stores[i].read_tile(source);
        if (!tile) return error.set(tile.error());
        if (source.level != key.level) tile->raster = upsample(tile->raster, source, key, grid);
        held.push_back(std::move(*tile));
        rasters[i] = &held.back().raster;
        bounds.min = std::min(bounds.min, e->min);
        bounds.max = std::max(bounds.max, e->max);
      }
      tiles::Raster fused =
          tiles::Raster::empty(manifest.sample_type, grid.padded_width(), grid.padded_height());
      if (manifest.sample_type == tiles::SampleType::Float32) {
        fuse_float(rasters, weights, o.mode, fused);
      } else {
        fuse_rgba(rasters, weights, o.mode, fused);
      }
      // Descendants of an upsampled tile can miss its data: no empty tiles.
      const bool empty = fused.stats(border, border, grid.width(), grid.height()).valid_count == 0;
      if (!empty) {
        if (auto st = output.write(key, fused, border, manifest.codec, &bounds); !st) {
          error.set(st.error());
        }
      }
      progress.advance();
    });
    progress.end();
    RELIEF_CHECK(error.status());
  }
  const FuseReport report{output.tiles_written(), manifest.max_level - manifest.min_level + 1};
  RELIEF_CHECK(output.finish(std::move(manifest), executor, progress));
  return report;
}

}  // namespace relief::pipeline
