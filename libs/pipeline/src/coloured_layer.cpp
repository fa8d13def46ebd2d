#include "relief/pipeline/coloured_layer.h"

#include <cmath>
#include <memory>
#include <utility>

#include <fmt/format.h>

#include "memory_store.h"
#include "relief/tiles/tile_file.h"

namespace relief::pipeline {
namespace {

// What the presented store's tiles are made from.
struct Colouring {
  tiles::Store input;
  ColouredLayer layer;
  process::GlobalStats stats;
  // Tiles are encoded only to pass through tiles::Store: lossless.
  tiles::CodecOptions codec{tiles::Codec::Zstd, 0.0, 90, 1};

  Result<std::vector<std::byte>> encoded(const geo::TileKey& key) const {
    const tiles::Tile tile = RELIEF_TRY(input.read_tile(key));
    const double factor = std::ldexp(1.0, input.manifest().max_level - key.level);
    InlineExecutor inline_executor;  // one tile per reading thread
    const tiles::Raster values = RELIEF_TRY(
        gpuprocess::run_chain_cpu(gpuprocess::scale_chain(layer.chain, factor), tile.raster,
                                  input.grid().border(), &stats, inline_executor));
    const tiles::Raster colours =
        gpuprocess::map_colours_cpu(values, layer.range_min, layer.range_max, layer.colormap, 1);
    return tiles::encode_tile(colours, 1, codec);
  }
};

}  // namespace

Result<tiles::Store> colour_layer(tiles::Store store, const std::string& name,
                                  ColouredLayer layer) {
  const tiles::Manifest& in = store.manifest();
  if (in.bands != 1 || in.sample_type != tiles::SampleType::Float32) {
    return fail(
        fmt::format("{}: holds {} data of {} band(s): only a single-band Float32 store is "
                    "coloured",
                    name, tiles::to_string(in.kind), in.bands));
  }
  if (!(layer.range_min < layer.range_max)) {
    return fail(fmt::format("{}: the value range [{}, {}] is empty", name, layer.range_min,
                            layer.range_max));
  }
  RELIEF_CHECK(gpuprocess::check_chain_for(layer.chain, in, name));
  auto shared = std::make_shared<Colouring>();
  shared->stats = {in.stats.min, in.stats.max, in.stats.mean, in.stats.stddev};
  shared->layer = std::move(layer);
  tiles::Manifest manifest = in;
  manifest.kind = tiles::DatasetKind::Imagery;
  manifest.sample_type = tiles::SampleType::UInt8;
  manifest.bands = 4;
  manifest.border = 1;
  manifest.codec = shared->codec;
  manifest.created_by =
      fmt::format("{} coloured ({}, [{}, {}])", name, gpuprocess::to_string(shared->layer.colormap),
                  shared->layer.range_min, shared->layer.range_max);
  std::vector<tiles::LevelIndex> indices;
  for (int level = manifest.min_level; level <= manifest.max_level; ++level) {
    tiles::LevelIndex index(level);
    for (const tiles::IndexEntry& e : store.index(level).entries()) {
      tiles::IndexEntry entry = e;
      entry.min = 0, entry.max = 255, entry.error = 0;
      index.add(entry);
    }
    indices.push_back(std::move(index));
  }
  shared->input = std::move(store);
  return open_memory_store(name, manifest, indices,
                           [shared](const geo::TileKey& key) { return shared->encoded(key); });
}

}  // namespace relief::pipeline
