// Elevation layers fused at draw time (pipeline/fused_elevation.h): weighted
// like `relief fuse --weights`, tile for tile, and opened with one read of
// each layer tile (no tile fused twice, none encoded) while drawing reads
// what it draws.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <map>
#include <mutex>

#include "../ingest/built_stores.h"
#include "../support/test_support.h"
#include "relief/pipeline/fuse_stores.h"
#include "relief/pipeline/fused_elevation.h"
#include "relief/tiles/store_layout.h"

namespace relief::testing {
namespace {

namespace fs = std::filesystem;

Result<tiles::Store> draw_time(std::vector<tiles::Store> stores, pipeline::FuseMode mode,
                               std::vector<double> weights = {}) {
  std::vector<pipeline::ElevationLayer> layers;
  for (tiles::Store& s : stores) layers.push_back({s.root().string(), std::move(s)});
  ThreadExecutor ex(2);
  return pipeline::fuse_elevation_layers(std::move(layers), mode, ex, std::move(weights));
}

// Bit for bit, NaN equal to NaN.
bool same_samples(const tiles::Raster& a, const tiles::Raster& b) {
  return a.byte_size() == b.byte_size() &&
         std::memcmp(a.bytes().data(), b.bytes().data(), a.byte_size()) == 0;
}

// The weighted mean drawn from N41E001 and N42E001 as two layers is the store
// `relief fuse --weights 3,1` writes from them: every tile's samples (borders
// included) and every geometric error. The weights matter there: the coarse
// tiles along 42N mix both layers' samples.
TEST(FusedElevation, WeightedMeanEqualsTheStoreOfReliefFuseWeights) {
  const tiles::Store &n41 = srtm_store("N41E001"), &n42 = srtm_store("N42E001");
  ScratchDir dir("fused_weights");
  ThreadExecutor ex(2);
  NullProgress progress;
  ASSERT_TRUE(pipeline::fuse_stores(
      {{n41.root(), n42.root()}, {3, 1}, pipeline::FuseMode::Blend, dir / "fused"}, ex, progress));
  const tiles::Store offline = *tiles::Store::open(dir / "fused");
  auto weighted = draw_time({n41, n42}, pipeline::FuseMode::Blend, {3, 1});
  ASSERT_TRUE(weighted) << weighted.error().message;
  auto unweighted = draw_time({n41, n42}, pipeline::FuseMode::Blend);
  ASSERT_TRUE(unweighted) << unweighted.error().message;

  ASSERT_EQ(weighted->manifest().max_level, offline.manifest().max_level);
  size_t tiles = 0, changed_by_weights = 0;
  for (int level = 0; level <= offline.manifest().max_level; ++level) {
    ASSERT_EQ(weighted->index(level).size(), offline.index(level).size()) << "level " << level;
    for (const tiles::IndexEntry& e : offline.index(level).entries()) {
      const tiles::IndexEntry* d = weighted->index(level).find(e.key);
      ASSERT_NE(d, nullptr) << e.key.to_string();
      EXPECT_EQ(d->error, e.error) << e.key.to_string();
      const tiles::Tile a = must_read(*weighted, e.key), b = must_read(offline, e.key);
      ASSERT_TRUE(same_samples(a.raster, b.raster)) << e.key.to_string();
      changed_by_weights += !same_samples(a.raster, must_read(*unweighted, e.key).raster);
      ++tiles;
    }
  }
  EXPECT_GT(tiles, 50u);
  EXPECT_GT(changed_by_weights, 0u);
}

TEST(FusedElevation, BadWeightsAreOneLineErrors) {
  const tiles::Store &n41 = srtm_store("N41E001"), &n42 = srtm_store("N42E001");
  const std::pair<std::vector<double>, std::string> cases[] = {
      {{1}, "--weights: 1 weights for 2 elevation layers"},
      {{1, 2, 3}, "--weights: 3 weights for 2 elevation layers"},
      {{1, -2}, "--weights: -2 is not > 0 and finite"},
      {{0, 0}, "--weights: 0 is not > 0 and finite"},
      {{1, NAN}, "is not > 0 and finite"},
      {{INFINITY, 1}, "is not > 0 and finite"},
  };
  for (const auto& [weights, needle] : cases) {
    auto r = draw_time({n41, n42}, pipeline::FuseMode::Blend, weights);
    ASSERT_FALSE(r) << needle;
    EXPECT_NE(r.error().message.find(needle), std::string::npos) << r.error().message;
    EXPECT_EQ(r.error().message.find('\n'), std::string::npos);
  }
}

// A store directory whose tile files are counted as they are fetched.
class CountingSource final : public tiles::StoreSource {
 public:
  explicit CountingSource(const fs::path& root) : inner_(tiles::local_source(root)) {}
  std::string name() const override { return inner_->name(); }
  Result<std::vector<std::byte>> fetch(const std::string& relative) const override {
    if (tiles::tile_key_from_relative_path(relative)) {
      std::lock_guard lock(mutex_);
      ++reads_[relative];
    }
    return inner_->fetch(relative);
  }
  std::map<std::string, int> reads() const {
    std::lock_guard lock(mutex_);
    return reads_;
  }

 private:
  std::shared_ptr<const tiles::StoreSource> inner_;
  mutable std::mutex mutex_;
  mutable std::map<std::string, int> reads_;
};

// Opening reads what the fused pyramid's exact geometric errors need (every
// layer tile: the finest data under each tile) once, fuses nothing twice and
// encodes nothing; after that a tile is read (from its layers) when it is
// drawn. Before, opening fused and encoded every tile for the index, then
// read them all again for the errors. Both depths: layers of one depth, and a
// coarse layer with a fine one inside (sparse depth: a pass per level of
// leaves, and upsampled tiles sharing their source tile).
TEST(FusedElevation, OpeningReadsEachLayerTileOnce) {
  ingest::BuildOptions coarse;
  coarse.inputs = {data("srtm/N41E001.hgt.zip"), data("srtm/N42E001.hgt.zip")};
  coarse.kind = tiles::DatasetKind::Elevation;
  coarse.max_level = 7;
  const fs::path n41 = srtm_store("N41E001").root(), n42 = srtm_store("N42E001").root(),
                 pair7 = built_store("pair-level7", coarse).root();
  for (const auto& [first, fine] : {std::pair{n41, n42}, std::pair{pair7, n42}}) {
    auto a = std::make_shared<CountingSource>(first);
    auto b = std::make_shared<CountingSource>(fine);
    const tiles::Store second = *tiles::Store::open(b);
    auto fused = draw_time({*tiles::Store::open(a), second}, pipeline::FuseMode::Blend);
    ASSERT_TRUE(fused) << fused.error().message;
    size_t layer_tiles = 0;
    for (const auto& source : {a, b}) {
      const auto reads = source->reads();
      for (const auto& [file, n] : reads) EXPECT_EQ(n, 1) << source->name() << "/" << file;
      layer_tiles += reads.size();
    }
    EXPECT_GT(layer_tiles, 50u);
    // Drawing a tile reads it from the layers that have it, when asked.
    const tiles::IndexEntry* drawn = nullptr;
    for (const tiles::IndexEntry& e : fused->index(9).entries()) {
      if (second.has_tile(e.key)) drawn = &e;
    }
    ASSERT_NE(drawn, nullptr);
    const std::string file = tiles::tile_relative_path(drawn->key);
    const int before = b->reads().at(file);
    must_read(*fused, drawn->key);
    EXPECT_EQ(b->reads().at(file), before + 1);
  }
}

}  // namespace
}  // namespace relief::testing
