// Geographic grids as NetCDF and GRIB often come: no CRS, longitudes 0..360,
// gridline-registered (outer samples centred on the poles). relief build takes
// them as WGS84 and wraps the eastern half to -180..0; a grid without a CRS
// whose extent cannot be longitudes and latitudes still needs --src-crs.
#include <gtest/gtest.h>

#include <gdal.h>

#include <cmath>

#include "gdal_env.h"
#include "relief/ingest/build.h"
#include "relief/tiles/store.h"
#include "test_support.h"

namespace relief::ingest {
namespace {

// A 5-degree global grid without CRS whose samples hold their own longitude
// in 0..355, written as GeoTIFF.
std::string write_grid(const std::filesystem::path& file, double west, double north) {
  init_gdal();
  GDALDriverH driver = GDALGetDriverByName("GTiff");
  const int w = 72, h = 37;
  GDALDatasetH ds = GDALCreate(driver, file.c_str(), w, h, 1, GDT_Float32, nullptr);
  double gt[6] = {west, 5, 0, north, 0, -5};
  GDALSetGeoTransform(ds, gt);
  std::vector<float> v(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) v[static_cast<size_t>(y) * w + x] = static_cast<float>(5 * x);
  }
  EXPECT_EQ(GDALRasterIO(GDALGetRasterBand(ds, 1), GF_Write, 0, 0, w, h, v.data(), w, h,
                         GDT_Float32, 0, 0),
            CE_None);
  GDALClose(ds);
  return file.string();
}

TEST(LongitudeWrap, AGlobalGridInZeroTo360WithoutCrsIsTakenAsIs) {
  testing::ScratchDir dir("longitude_wrap");
  // Gridline-registered: sample centres at 0, 5, .. 355 and 90, 85, .. -90.
  const std::string grid = write_grid(dir / "grid.tif", -2.5, 92.5);
  BuildOptions o;
  o.inputs = {grid};
  o.output = dir / "store";
  o.tile_log2_height = 5;
  ThreadExecutor executor;
  NullProgress progress;
  auto report = build_store(o, executor, progress);
  ASSERT_TRUE(report) << report.error().message;
  EXPECT_NE(report->manifest.sources.at(0).crs.find("assumed"), std::string::npos);
  auto store = tiles::Store::open(dir / "store");
  ASSERT_TRUE(store) << store.error().message;
  const int finest = store->manifest().max_level;
  // East of Greenwich the grid's own longitudes; west of it, 360 + longitude.
  for (const auto& [lon, expected] :
       {std::pair{10.0, 10.0}, std::pair{100.0, 100.0}, std::pair{-170.0, 190.0},
        std::pair{-20.0, 340.0}, std::pair{-100.0, 260.0}}) {
    auto v = store->sample(lon, 12.5, finest);
    ASSERT_TRUE(v && *v) << lon;
    EXPECT_NEAR(**v, expected, 2.6) << lon;  // bilinear between 5-degree samples
  }
}

TEST(LongitudeWrap, AGridWithoutCrsOutsideGeographicBoundsStillNeedsSrcCrs) {
  testing::ScratchDir dir("longitude_wrap_utm");
  const std::string grid = write_grid(dir / "utm.tif", 500000, 4650000);  // metres
  BuildOptions o;
  o.inputs = {grid};
  o.output = dir / "store";
  ThreadExecutor executor;
  NullProgress progress;
  auto report = build_store(o, executor, progress);
  ASSERT_FALSE(report);
  EXPECT_NE(report.error().message.find("--src-crs"), std::string::npos) << report.error().message;
  EXPECT_FALSE(std::filesystem::exists(dir / "store" / "manifest.json"));
}

}  // namespace
}  // namespace relief::ingest
