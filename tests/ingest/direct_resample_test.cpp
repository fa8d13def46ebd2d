// The fast path for WGS84 lon/lat inputs gives GDAL's warper's result.
#include <gtest/gtest.h>
#include <ogr_srs_api.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <thread>

#include "../support/test_support.h"
#include "built_stores.h"
#include "direct_resample.h"
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

// A synthetic WGS84 raster on a grid 1.8x coarser than level 10 of 32 x 16
// tiles, covering tile `key` with a margin; column `void_x` is NaN if >= 0.
ingest::Dataset synthetic_lon_lat(const geo::TileKey& key, int void_x) {
  ingest::init_gdal();
  constexpr int kW = 40, kH = 30;
  ingest::Dataset ds(GDALCreate(GDALGetDriverByName("MEM"), "", kW, kH, 1, GDT_Float32, nullptr));
  const geo::GeoBox b = key.bounds();
  double gt[6] = {b.west - 0.1, 0.02, 0, b.north + 0.1, 0, -0.02};
  GDALSetGeoTransform(ds.get(), gt);
  // Longitude first, as GDAL's raster drivers map EPSG:4326.
  OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
  OSRImportFromEPSG(srs, 4326);
  OSRSetAxisMappingStrategy(srs, OAMS_TRADITIONAL_GIS_ORDER);
  GDALSetSpatialRef(ds.get(), srs);
  OSRDestroySpatialReference(srs);
  std::vector<float> v(kW * kH);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      v[y * kW + x] = 1000.0f + 37.25f * std::sin(0.7f * x + 1.3f * y) + x +
                      0.001f * static_cast<float>((x * 7919 + y * 104729) % 1000);
    }
  }
  for (int y = 0; void_x >= 0 && y < kH; ++y) v[y * kW + void_x] = NAN;
  EXPECT_EQ(GDALRasterIO(GDALGetRasterBand(ds.get(), 1), GF_Write, 0, 0, kW, kH, v.data(), kW, kH,
                         GDT_Float32, 0, 0),
            CE_None);
  return ds;
}

// Window rows that are all valid take a loop without validity tests; a void
// sends its rows through the general one. Both must give the same bits
// wherever the void is out of reach of the bilinear taps.
TEST(DirectResampling, RowsWithAndWithoutVoidsGiveTheSameBits) {
  const auto grid = *geo::TileGrid::create(4, 0);
  const geo::TileKey key{10, 520, 300};
  const double spacing = grid.sample_spacing(key.level);
  ASSERT_LT(spacing, 0.02);  // upsampled: the direct path applies
  const geo::GeoBox b = key.bounds();
  const double gt0 = b.west - 0.1;
  // A column of voids under the tile's third column: every window row has one.
  const int vx = static_cast<int>((grid.sample_lon(key, 2) - gt0) / 0.02);
  ingest::Dataset plain = synthetic_lon_lat(key, -1), holed = synthetic_lon_lat(key, vx);
  auto a = ingest::DirectResampler::create(plain.get(), spacing);
  auto h = ingest::DirectResampler::create(holed.get(), spacing);
  ASSERT_TRUE(a && h);
  tiles::Raster ra = tiles::Raster::empty(tiles::SampleType::Float32, grid.width(), grid.height());
  tiles::Raster rh = ra;
  ASSERT_TRUE(a->resample(grid, key, ra));
  ASSERT_TRUE(h->resample(grid, key, rh));
  int compared = 0, voided = 0;
  for (int j = 0; j < grid.height(); ++j) {
    for (int i = 0; i < grid.width(); ++i) {
      const double sx = (grid.sample_lon(key, i) - gt0) / 0.02;
      const float va = ra.f32()[j * grid.width() + i], vh = rh.f32()[j * grid.width() + i];
      ASSERT_FALSE(std::isnan(va)) << i << ", " << j;
      if (std::abs(sx - (vx + 0.5)) < 2) {
        voided += std::isnan(vh) || vh != va;
        continue;  // within reach of the void
      }
      ASSERT_EQ(std::memcmp(&va, &vh, sizeof va), 0) << i << ", " << j << ": " << va << " " << vh;
      ++compared;
    }
  }
  EXPECT_GT(compared, 300);
  EXPECT_GT(voided, 0);  // the void had an effect
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
