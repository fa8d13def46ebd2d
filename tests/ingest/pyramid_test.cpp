// Coarser levels are nodata-aware 2 x 2 means; voids stay nodata.
#include <gtest/gtest.h>

#include <cmath>

#include "../support/test_support.h"
#include "built_stores.h"
#include "gdal_reference.h"

namespace relief::testing {
namespace {

float interior(const tiles::Tile& t, int i, int j) {
  const int b = t.header.border;
  return t.raster.f32()[static_cast<size_t>(j + b) * t.raster.width() + i + b];
}

TEST(Pyramid, ParentSamplesAreNodataAwareMeansOfChildren) {
  const auto& store = pyrenees_store();
  const auto& g = store.grid();
  const int w = g.width(), h = g.height();
  int64_t checked = 0, nodata_parents = 0;
  for (int level = store.manifest().max_level - 1; level >= 0; --level) {
    for (const auto& e : store.index(level).entries()) {
      const tiles::Tile parent = must_read(store, e.key);
      for (int cy = 0; cy < 2; ++cy) {
        for (int cx = 0; cx < 2; ++cx) {
          const geo::TileKey ck = e.key.child(cx, cy);
          const bool has_child = store.has_tile(ck);
          tiles::Tile child;
          if (has_child) child = must_read(store, ck);
          for (int j = 0; j < h / 2; ++j) {
            for (int i = 0; i < w / 2; ++i) {
              double sum = 0;
              int n = 0;
              if (has_child) {
                for (int k = 0; k < 4; ++k) {
                  const float v = interior(child, 2 * i + k % 2, 2 * j + k / 2);
                  if (!std::isnan(v)) {
                    sum += v;
                    ++n;
                  }
                }
              }
              const float p = interior(parent, cx * w / 2 + i, cy * h / 2 + j);
              if (n == 0) {
                ASSERT_TRUE(std::isnan(p)) << e.key.to_string() << " " << i << "," << j;
                ++nodata_parents;
              } else {
                ASSERT_FLOAT_EQ(p, static_cast<float>(sum / n)) << e.key.to_string();
              }
              ++checked;
            }
          }
        }
      }
    }
  }
  EXPECT_GT(checked, 1000000);
  EXPECT_GT(nodata_parents, 0);
}

TEST(Pyramid, VoidsStayNodataNeverZero) {
  const auto& store = pyrenees_store();
  const SourceGrid src = read_source("/vsizip/" + data("srtm/N42E001.hgt.zip") + "/N42E001.hgt");
  ASSERT_TRUE(src.has_nodata);
  EXPECT_EQ(src.nodata, -32768);
  // Void pixels whose whole 3 x 3 neighbourhood is void: no bilinear support.
  int voids = 0;
  for (int j = 1; j + 1 < src.height; ++j) {
    for (int i = 1; i + 1 < src.width; ++i) {
      bool all_void = true;
      for (int k = 0; k < 9 && all_void; ++k) all_void = !src.valid(i - 1 + k % 3, j - 1 + k / 3);
      if (!all_void) continue;
      const double lon = src.gt[0] + (i + 0.5) * src.gt[1], lat = src.gt[3] + (j + 0.5) * src.gt[5];
      auto v = store.sample(lon, lat, 10);
      ASSERT_TRUE(v);
      EXPECT_FALSE(v->has_value()) << "void at " << lon << "," << lat << " holds " << **v;
      ++voids;
    }
  }
  EXPECT_GT(voids, 500);
  // The lowest point of N42E001 is 349 m: a zero (or -32768) would be a void leaking.
  for (const auto& e : store.index(10).entries()) {
    if (e.key.bounds().south < 42.0) continue;
    EXPECT_GT(e.min, 300.0f) << e.key.to_string();
  }
}

TEST(Pyramid, ManifestStatisticsMatchTheFinestLevel) {
  const auto& store = pyrenees_store();
  const auto& m = store.manifest();
  double sum = 0;
  uint64_t n = 0;
  float lo = INFINITY, hi = -INFINITY;
  for (const auto& e : store.index(m.max_level).entries()) {
    const tiles::Tile t = must_read(store, e.key);
    for (int j = 0; j < store.grid().height(); ++j) {
      for (int i = 0; i < store.grid().width(); ++i) {
        const float v = interior(t, i, j);
        if (std::isnan(v)) continue;
        sum += v;
        ++n;
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
    }
  }
  EXPECT_EQ(m.stats.valid_count, n);
  EXPECT_NEAR(m.stats.mean, sum / n, 1e-6 * std::abs(sum / n));
  EXPECT_FLOAT_EQ(m.stats.min, lo);
  EXPECT_FLOAT_EQ(m.stats.max, hi);
  EXPECT_GT(m.stats.stddev, 100);
  EXPECT_EQ(m.units, "m");
  EXPECT_EQ(m.sources.size(), 2u);
  EXPECT_EQ(m.sources[0].crs, "EPSG:4326");
}

}  // namespace
}  // namespace relief::testing
