// Geometric errors in the level index (store format 2): recomputed naively
// from the stored tiles with the public full mesh, sample by sample, they must
// equal the build's bit for bit; nodata and the data's edge must not raise
// them, a real step in the data must.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>

#include "built_stores.h"
#include "gdal_reference.h"
#include "relief/tiles/full_mesh.h"
#include "relief/tiles/geometric_error.h"
#include "test_support.h"

namespace relief::ingest {
namespace {

using geo::TileKey;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Finest tiles are read once per store, not once per ancestor.
const tiles::Tile& cached_read(const tiles::Store& store, const TileKey& key) {
  static std::map<std::pair<const tiles::Store*, TileKey>, tiles::Tile> cache;
  auto it = cache.find({&store, key});
  if (it == cache.end())
    it = cache.emplace(std::pair(&store, key), testing::must_read(store, key)).first;
  return it->second;
}

// The definition of docs/store-format.md, with no shortcut: every finest
// sample under `key`, against `key`'s full mesh where its stencil is data.
float brute_force_error(const tiles::Store& store, const TileKey& key) {
  const int finest = store.manifest().max_level, border = store.grid().border();
  const int w = store.grid().width(), h = store.grid().height();
  const int m = finest - key.level;
  if (m == 0) return 0;
  const tiles::Tile coarse = testing::must_read(store, key);
  double worst = 0;
  for (const tiles::IndexEntry& e : store.index(finest).entries()) {
    if ((e.key.x >> m) != key.x || (e.key.y >> m) != key.y) continue;
    const tiles::Tile& fine = cached_read(store, e.key);
    const auto values = fine.raster.f32();
    for (int j = 0; j < h; ++j) {
      for (int i = 0; i < w; ++i) {
        const float value =
            values[static_cast<size_t>(j + border) * fine.raster.width() + i + border];
        if (std::isnan(value)) continue;
        const double x = std::ldexp((e.key.x - (key.x << m)) * double(w) + i + 0.5, -m);
        const double y = std::ldexp((e.key.y - (key.y << m)) * double(h) + j + 0.5, -m);
        if (!tiles::full_mesh_stencil_valid(coarse.raster, border, x, y)) continue;
        worst =
            std::max(worst, std::abs(tiles::full_mesh_height(coarse.raster, border, x, y) - value));
      }
    }
  }
  return tiles::round_up_to_float(worst);
}

TEST(GeometricError, EqualsABruteForceRecomputation) {
  const tiles::Store& store = testing::pyrenees_store();
  const int finest = store.manifest().max_level;
  int positive = 0;
  for (int level = store.manifest().min_level; level <= finest; ++level) {
    for (const tiles::IndexEntry& e : store.index(level).entries()) {
      EXPECT_EQ(e.error, brute_force_error(store, e.key)) << e.key.to_string();
      positive += e.error > 0;
    }
  }
  // Relief is not flat: most coarse tiles are measurably off.
  EXPECT_GT(positive, 20);
}

// A lossy store's errors are those of the samples readers decode, not of the
// samples the build encoded.
TEST(GeometricError, OfALossyStoreAreThoseOfTheDecodedSamples) {
  BuildOptions o;
  o.inputs = testing::pyrenees_inputs();
  o.kind = tiles::DatasetKind::Elevation;
  o.max_error = 0.5;
  const tiles::Store& store = testing::built_store("pyrenees_pair_lerc", o);
  ASSERT_EQ(store.manifest().codec.codec, tiles::Codec::Lerc);
  const int level = store.manifest().max_level - 1;
  for (const tiles::IndexEntry& e : store.index(level).entries()) {
    EXPECT_EQ(e.error, brute_force_error(store, e.key)) << e.key.to_string();
  }
}

TEST(GeometricError, RoundsUpToFloat) {
  const double d = 0.1;  // not a float
  EXPECT_GE(static_cast<double>(tiles::round_up_to_float(d)), d);
  EXPECT_LT(static_cast<double>(tiles::round_up_to_float(d)), d + 1e-8);
  EXPECT_EQ(tiles::round_up_to_float(0.5), 0.5f);
  EXPECT_EQ(tiles::round_up_to_float(0), 0.0f);
}

// A flat plateau at 1000 m, 0.01 degree samples, with a void in it and nodata
// around it: a plateau's every mesh is exact where its stencil is data, so
// every error is 0. Counting the void or the fall-off at the edge would give
// the height of the terrain instead. `step` raises the plateau's east half.
const tiles::Store& plateau(const std::string& name, float step) {
  static std::vector<std::unique_ptr<testing::ScratchDir>> dirs;
  dirs.push_back(std::make_unique<testing::ScratchDir>("plateau_" + name));
  const int n = 100;
  std::vector<float> v(static_cast<size_t>(n) * n, 1000.0f);
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      float& s = v[static_cast<size_t>(y) * n + x];
      if (x >= 30 && x < 50 && y >= 40 && y < 60) s = kNaN;  // the void
      if (x >= 70) s += step;
    }
  }
  const double gt[6] = {7.003, 0.01, 0, 45.997, 0, -0.01};
  const std::string path = (dirs.back()->path() / "plateau.tif").string();
  testing::write_geotiff(path, n, n, gt, v);
  BuildOptions o;
  o.inputs = {path};
  o.tile_log2_height = 5;
  return testing::built_store("plateau_" + name, o);
}

TEST(GeometricError, VoidsAndTheDataEdgeDoNotRaiseErrors) {
  const tiles::Store& store = plateau("flat", 0);
  const int finest = store.manifest().max_level;
  ASSERT_GE(finest, 8);
  uint64_t finest_valid = 0, finest_samples = 0;
  for (const tiles::IndexEntry& e : store.index(finest).entries()) {
    finest_valid += e.valid_count;
    finest_samples += static_cast<uint64_t>(store.grid().width()) * store.grid().height();
  }
  ASSERT_LT(finest_valid, finest_samples);  // there is nodata around the data
  for (int level = store.manifest().min_level; level <= finest; ++level) {
    for (const tiles::IndexEntry& e : store.index(level).entries()) {
      EXPECT_EQ(e.error, 0.0f) << e.key.to_string();
    }
  }
}

TEST(GeometricError, AStepInTheDataRaisesTheAncestors) {
  const tiles::Store& store = plateau("step", 200);
  const int finest = store.manifest().max_level;
  float coarse_worst = 0;
  for (int level = store.manifest().min_level; level < finest; ++level) {
    for (const tiles::IndexEntry& e : store.index(level).entries()) {
      EXPECT_EQ(e.error, brute_force_error(store, e.key)) << e.key.to_string();
      if (level == finest - 3) coarse_worst = std::max(coarse_worst, e.error);
    }
  }
  // Three levels up a cell spans 8 samples: the mesh ramps across the step.
  EXPECT_GT(coarse_worst, 50.0f);
  for (const tiles::IndexEntry& e : store.index(finest).entries()) EXPECT_EQ(e.error, 0.0f);
}

}  // namespace
}  // namespace relief::ingest
