// Void filling: white-box on small grids, then on the real SRTM tile with voids.
#include "void_fill.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "built_stores.h"
#include "gdal_env.h"
#include "test_support.h"

namespace relief::ingest {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

TEST(FillVoids, FillsEnclosedHolesOnlyAndKeepsValidSamples) {
  const int w = 40, h = 30;
  std::vector<float> v(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) v[static_cast<size_t>(y) * w + x] = 100.0f + x + 2.0f * y;
  }
  const std::vector<float> original = v;
  auto at = [&](int x, int y) -> float& { return v[static_cast<size_t>(y) * w + x]; };
  for (int y = 10; y < 16; ++y) {
    for (int x = 10; x < 18; ++x) at(x, y) = kNaN;  // a void
  }
  for (int y = 0; y < h; ++y) at(w - 1, y) = at(w - 2, y) = kNaN;  // a collar on the east edge
  for (int x = 0; x < 12; ++x) at(x, 0) = kNaN;  // the collar goes on along the north edge...
  at(12, 1) = kNaN;                              // ...and on diagonally
  at(0, 20) = kNaN;  // a void cut by the west edge: 1 sample, < 1 % of the raster
  EXPECT_EQ(fill_voids(v, w, h), 49u);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      if (x >= w - 2 || (y == 0 && x < 12) || (x == 12 && y == 1)) {
        EXPECT_TRUE(std::isnan(v[i])) << x << "," << y;
      } else if (x == 0 && y == 20) {
        EXPECT_NEAR(v[i], original[i], 3.0f);
      } else if (x >= 10 && x < 18 && y >= 10 && y < 16) {
        // Filled from the surroundings: within their range, near the plane.
        EXPECT_GE(v[i], 100.0f + 9 + 2 * 9) << x << "," << y;
        EXPECT_LE(v[i], 100.0f + 18 + 2 * 16) << x << "," << y;
        EXPECT_NEAR(v[i], original[i], 6.0f) << x << "," << y;
      } else {
        EXPECT_EQ(v[i], original[i]) << x << "," << y;
      }
    }
  }
}

TEST(FillVoids, NoVoidNoChange) {
  std::vector<float> v(16, 5.0f);
  v[0] = v[1] = v[2] = v[3] = kNaN;  // a collar: a quarter of the raster, on its edge
  EXPECT_EQ(fill_voids(v, 4, 4), 0u);
  EXPECT_TRUE(std::isnan(v[0]));
}

// SRTM v2.1 N42E001 has voids (radar shadows in the high Pyrenees): the
// filled copy keeps every valid sample and fills every void within the range
// of the data.
TEST(FillVoids, SrtmVoidsAreFilledAndValidSamplesKept) {
  testing::ScratchDir dir("void_fill");
  const std::string source = testing::data("srtm/N42E001.hgt.zip");
  auto filled = fill_source_voids(source, dir.path() / "filled.tif");
  ASSERT_TRUE(filled) << filled.error().message;
  ASSERT_TRUE(filled->has_value());
  EXPECT_GT((*filled)->filled, 1000u);
  init_gdal();
  std::vector<float> before, after;
  const Dataset a = open_raster(source), b = open_raster((*filled)->path.string());
  ASSERT_TRUE(a && b);
  const int w = GDALGetRasterXSize(a.get()), h = GDALGetRasterYSize(a.get());
  ASSERT_FALSE(read_padded(GDALGetRasterBand(a.get(), 1), 0, 0, w, h, 0, before, "a"));
  ASSERT_FALSE(read_padded(GDALGetRasterBand(b.get(), 1), 0, 0, w, h, 0, after, "b"));
  uint64_t voids = 0;
  for (size_t i = 0; i < before.size(); ++i) {
    if (std::isnan(before[i])) {
      ++voids;
      ASSERT_FALSE(std::isnan(after[i])) << i;
      EXPECT_GE(after[i], 349.0f);  // the tile's valid range (SOURCES.md)
      EXPECT_LE(after[i], 3100.0f);
    } else {
      ASSERT_EQ(before[i], after[i]) << i;
    }
  }
  EXPECT_EQ(voids, (*filled)->filled);  // SRTM tiles have no collar: every hole is a void
}

// Built with --fill-voids, the store has samples where the raw build has holes.
TEST(FillVoids, BuildFillsTheStoresHoles) {
  BuildOptions o;
  o.inputs = {testing::data("srtm/N42E001.hgt.zip")};
  o.tile_log2_height = 7;
  const tiles::Store& raw = testing::built_store("n42_raw", o);
  o.fill_voids = true;
  const tiles::Store& filled = testing::built_store("n42_filled", o);
  const int level = raw.manifest().max_level;
  uint64_t raw_valid = 0, filled_valid = 0, holes_left = 0;
  for (const tiles::IndexEntry& e : raw.index(level).entries()) {
    raw_valid += e.valid_count;
    filled_valid += filled.index(level).find(e.key)->valid_count;
  }
  EXPECT_GT(filled_valid, raw_valid + 1000);
  // Nodata is left only outside the 1 degree tile: edge tiles are partial,
  // interior ones full.
  for (const tiles::IndexEntry& e : filled.index(level).entries()) {
    const geo::GeoBox b = e.key.bounds();
    const bool inside = b.west > 1.01 && b.east < 1.99 && b.south > 42.01 && b.north < 42.99;
    if (inside) holes_left += 128u * 256u - e.valid_count;
  }
  EXPECT_EQ(holes_left, 0u);
}

}  // namespace
}  // namespace relief::ingest
