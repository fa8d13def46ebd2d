// The fast path for WGS84 lon/lat inputs gives GDAL's warper's result.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "../support/test_support.h"
#include "built_stores.h"

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

}  // namespace
}  // namespace relief::testing
