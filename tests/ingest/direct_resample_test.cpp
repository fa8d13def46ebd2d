// The fast path for WGS84 lon/lat inputs gives GDAL's warper's result.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <thread>

#include "../support/test_support.h"
#include "built_stores.h"
#include "gdal_env.h"
#include "warp.h"

namespace relief::testing {
namespace {

void expect_same_stores(const tiles::Store& a, const tiles::Store& b) {
  ASSERT_EQ(a.manifest().max_level, b.manifest().max_level);
  int64_t compared = 0;
  for (int level = a.manifest().min_level; level <= a.manifest().max_level; ++level) {
    ASSERT_EQ(a.index(level).size(), b.index(level).size()) << "level " << level;
    for (const auto& e : a.index(level).entries()) {
      const tiles::Tile ta = must_read(a, e.key), tb = must_read(b, e.key);
      const auto va = ta.raster.f32(), vb = tb.raster.f32();
      for (size_t k = 0; k < va.size(); ++k) {
        ASSERT_EQ(std::isnan(va[k]), std::isnan(vb[k])) << e.key.to_string() << " sample " << k;
        if (!std::isnan(va[k])) {
          // Two ulps: the source coordinate is computed in a different order.
          ASSERT_NEAR(va[k], vb[k], std::max(1e-5, 2.5e-7 * std::abs(vb[k])))
              << e.key.to_string() << " sample " << k;
          ++compared;
        }
      }
    }
  }
  EXPECT_GT(compared, 1000000);
}

TEST(DirectResampling, SrtmMosaicMatchesGdalWarper) {
  ingest::BuildOptions o;
  o.inputs = pyrenees_inputs();
  o.kind = tiles::DatasetKind::Elevation;
  o.direct_resampling = false;
  o.min_level = 7;
  const auto& gdal = built_store("pyrenees_gdal_warp", o);
  o.direct_resampling = true;
  const auto& direct = built_store("pyrenees_direct", o);
  expect_same_stores(direct, gdal);
}

// Voids next to valid samples, the edges of the source and an upsampling
// factor that is not a power of two exercise every branch of the kernel.
TEST(DirectResampling, VoidsEdgesAndOddScalesMatchGdalWarper) {
  ingest::BuildOptions o;
  o.inputs = {data("srtm/N42E001.hgt.zip")};
  o.kind = tiles::DatasetKind::Elevation;
  o.max_level = 11;
  o.min_level = 10;
  o.direct_resampling = false;
  const auto& gdal = built_store("n42_gdal_l11", o);
  o.direct_resampling = true;
  const auto& direct = built_store("n42_direct_l11", o);
  expect_same_stores(direct, gdal);
}

// Workers sharing the build's direct-path datasets (reads serialised, each
// block read once) resample exactly as a warper with datasets of its own.
TEST(DirectResampling, WarpersSharingDatasetsAcrossThreadsMatchAPrivateWarper) {
  ingest::init_gdal();
  std::vector<ingest::Source> sources;
  for (const auto& path : pyrenees_inputs()) {
    auto s = ingest::describe_source(path, tiles::DatasetKind::Elevation, std::nullopt);
    ASSERT_TRUE(s) << s.error().message;
    sources.push_back(*s);
  }
  const auto groups = ingest::group_sources(sources);
  const auto grid = geo::TileGrid::create();
  ASSERT_TRUE(grid);
  const int level = 10;
  std::vector<geo::TileKey> keys;  // a 4 x 4 block across the seam of the two inputs
  const uint32_t x0 = 515, y0 = 271;
  for (uint32_t y = y0; y < y0 + 4; ++y) {
    for (uint32_t x = x0; x < x0 + 4; ++x) keys.push_back({level, x, y});
  }
  ingest::TileWarper own(sources, groups, tiles::DatasetKind::Elevation, *grid, 0.125, true);
  ingest::SharedDirectSources shared(groups.size());
  std::vector<std::optional<Result<tiles::Raster>>> got(keys.size());
  std::vector<std::thread> workers;
  for (int t = 0; t < 2; ++t) {
    workers.emplace_back([&, t] {
      ingest::TileWarper w(sources, groups, tiles::DatasetKind::Elevation, *grid, 0.125, true,
                           &shared);
      for (size_t i = static_cast<size_t>(t); i < keys.size(); i += 2) got[i] = w.warp(keys[i]);
    });
  }
  for (auto& w : workers) w.join();
  size_t valid = 0;
  for (size_t i = 0; i < keys.size(); ++i) {
    auto expected = own.warp(keys[i]);
    ASSERT_TRUE(expected) << expected.error().message;
    ASSERT_TRUE(*got[i]) << got[i]->error().message;
    const tiles::Raster& a = **got[i];
    ASSERT_EQ(a.byte_size(), expected->byte_size());
    EXPECT_EQ(std::memcmp(a.bytes().data(), expected->bytes().data(), a.byte_size()), 0)
        << keys[i].to_string();
    valid += a.stats(0, 0, a.width(), a.height()).valid_count;
  }
  EXPECT_GT(valid, 1000000u);  // most of the block lies inside the data
}

}  // namespace
}  // namespace relief::testing
