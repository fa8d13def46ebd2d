// Terrain-RGB and Terrarium pixels (their boundaries, clamps and steps,
// decoded with MapLibre's unpack factors too) and the Web Mercator
// geometry of XYZ tiles' pixel centres.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "relief/web/dem_encoding.h"
#include "relief/web/web_mercator.h"

namespace relief::web {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// MapLibre's DEMData.unpack with the factors of dem_data.ts, not relief's decoder.
double maplibre_unpack(DemEncoding e, Rgb p) {
  const double mapbox[4] = {6553.6, 25.6, 0.1, 10000.0};
  const double terrarium[4] = {256.0, 1.0, 1.0 / 256.0, 32768.0};
  const double* f = e == DemEncoding::TerrainRgb ? mapbox : terrarium;
  return p.r * f[0] + p.g * f[1] + p.b * f[2] - f[3];
}

TEST(DemEncoding, TerrainRgbBoundariesAndClamps) {
  const auto e = DemEncoding::TerrainRgb;
  EXPECT_EQ(encode_height(e, -10000), (Rgb{0, 0, 0}));
  EXPECT_EQ(encode_height(e, 0), (Rgb{1, 134, 160}));  // v = 100000
  EXPECT_EQ(encode_height(e, kNaN), (Rgb{1, 134, 160})) << "nodata is 0 m";
  EXPECT_EQ(encode_height(e, -10001), (Rgb{0, 0, 0})) << "below the range";
  EXPECT_EQ(encode_height(e, -1e30), (Rgb{0, 0, 0}));
  EXPECT_EQ(encode_height(e, 2e6), (Rgb{255, 255, 255})) << "above the range";
  EXPECT_EQ(encode_height(e, std::numeric_limits<double>::infinity()), (Rgb{255, 255, 255}));
  EXPECT_DOUBLE_EQ(decode_height(e, {255, 255, 255}), 1667721.5);
  EXPECT_DOUBLE_EQ(decode_height(e, {0, 0, 0}), -10000);
  const Rgb everest = encode_height(e, 8848.86);  // v = round(188488.6) = 188489
  EXPECT_EQ(everest, (Rgb{2, 224, 73}));
  EXPECT_NEAR(decode_height(e, everest), 8848.9, 1e-9);
  EXPECT_NEAR(maplibre_unpack(e, everest), 8848.9, 1e-9);
}

TEST(DemEncoding, TerrariumBoundariesAndClamps) {
  const auto e = DemEncoding::Terrarium;
  EXPECT_EQ(encode_height(e, -32768), (Rgb{0, 0, 0}));
  EXPECT_EQ(encode_height(e, 0), (Rgb{128, 0, 0}));
  EXPECT_EQ(encode_height(e, kNaN), (Rgb{128, 0, 0})) << "nodata is 0 m";
  EXPECT_EQ(encode_height(e, -10000), (Rgb{88, 240, 0}));
  EXPECT_EQ(encode_height(e, -40000), (Rgb{0, 0, 0})) << "below the range";
  EXPECT_EQ(encode_height(e, 40000), (Rgb{255, 255, 255})) << "above the range";
  EXPECT_DOUBLE_EQ(decode_height(e, {255, 255, 255}), 32767 + 255.0 / 256);
  const Rgb everest = encode_height(e, 8848.86);  // v = round(10653916.16)
  EXPECT_EQ(everest, (Rgb{162, 144, 220}));
  EXPECT_DOUBLE_EQ(decode_height(e, everest), 8848.859375);
  EXPECT_DOUBLE_EQ(maplibre_unpack(e, everest), 8848.859375);
}

// Every height in range comes back within half a step, as MapLibre reads it.
TEST(DemEncoding, RoundTripsWithinHalfAStep) {
  std::mt19937 random(3);
  for (const auto& [e, lo, hi, step] :
       {std::tuple{DemEncoding::TerrainRgb, -10000.0, 1667721.5, 0.1},
        std::tuple{DemEncoding::Terrarium, -32768.0, 32767.99, 1.0 / 256}}) {
    std::uniform_real_distribution<double> height(lo, hi), near_zero(-20, 9000);
    for (int k = 0; k < 20000; ++k) {
      const double h = k % 2 ? height(random) : near_zero(random);
      const Rgb p = encode_height(e, h);
      ASSERT_NEAR(decode_height(e, p), h, step / 2 + 1e-9 * std::abs(h)) << h;
      ASSERT_NEAR(maplibre_unpack(e, p), decode_height(e, p), 1e-6) << h;
    }
  }
}

TEST(DemEncoding, FormatNames) {
  EXPECT_EQ(dem_encoding_from_format("terrain-rgb"), DemEncoding::TerrainRgb);
  EXPECT_EQ(dem_encoding_from_format("terrarium"), DemEncoding::Terrarium);
  EXPECT_EQ(dem_encoding_from_format("xyz"), std::nullopt);
  EXPECT_EQ(maplibre_name(DemEncoding::TerrainRgb), "mapbox");
  EXPECT_EQ(maplibre_name(DemEncoding::Terrarium), "terrarium");
}

double lat_of(double my) {
  return std::atan(std::sinh(std::numbers::pi * (1 - 2 * my))) * 180 / std::numbers::pi;
}

TEST(WebMercator, PixelCentresAtZoomZeroAndOne) {
  const XyzKey root{0, 0, 0};
  EXPECT_DOUBLE_EQ(pixel_lon(root, 256, 0), -180 + 360 * 0.5 / 256);
  EXPECT_DOUBLE_EQ(pixel_lon(root, 256, 127), -0.703125);
  EXPECT_DOUBLE_EQ(pixel_lon(root, 256, 128), 0.703125);
  EXPECT_DOUBLE_EQ(pixel_lon(root, 256, 255), 179.296875);
  EXPECT_DOUBLE_EQ(pixel_lat(root, 256, 0), lat_of(0.5 / 256));
  EXPECT_NEAR(pixel_lat(root, 256, 0), 84.9901, 1e-4);
  EXPECT_DOUBLE_EQ(pixel_lat(root, 256, 127), -pixel_lat(root, 256, 128));
  EXPECT_NEAR(pixel_lat(root, 256, 128), -0.703107, 1e-6);  // not 0.703125: Mercator
  // Pixel (i, j) of tile (1, x, y) is pixel (256 x + i, 256 y + j) of a
  // 512-pixel root tile.
  for (const auto [x, y, i, j] : {std::array{1u, 0u, 0u, 255u}, std::array{0u, 1u, 17u, 3u}}) {
    const XyzKey k{1, x, y};
    EXPECT_DOUBLE_EQ(pixel_lon(k, 256, static_cast<int>(i)),
                     pixel_lon(root, 512, static_cast<int>(256 * x + i)));
    EXPECT_DOUBLE_EQ(pixel_lat(k, 256, static_cast<int>(j)),
                     pixel_lat(root, 512, static_cast<int>(256 * y + j)));
  }
  EXPECT_DOUBLE_EQ(pixel_lon({1, 1, 0}, 256, 0), 360 * (1 + 0.5 / 256) / 2 - 180);
  EXPECT_DOUBLE_EQ(pixel_lat({1, 1, 0}, 256, 255), lat_of((255.5 / 256) / 2));
}

TEST(WebMercator, TileBoundsAndTheTilesMeetingABox) {
  const geo::GeoBox world = XyzKey{0, 0, 0}.bounds();
  EXPECT_DOUBLE_EQ(world.west, -180);
  EXPECT_DOUBLE_EQ(world.east, 180);
  EXPECT_NEAR(world.north, kMercatorMaxLatitude, 1e-12);
  EXPECT_NEAR(world.south, -kMercatorMaxLatitude, 1e-12);
  EXPECT_NEAR(mercator_my(kMercatorMaxLatitude), 0, 1e-12);
  for (const double my : {0.1, 0.37, 0.5, 0.93})
    EXPECT_NEAR(mercator_my(mercator_lat(my)), my, 1e-12);
  const geo::GeoBox b = XyzKey{2, 2, 1}.bounds();
  EXPECT_DOUBLE_EQ(b.west, 0);
  EXPECT_DOUBLE_EQ(b.east, 90);
  EXPECT_NEAR(b.south, 0, 1e-12);
  EXPECT_NEAR(b.north, 66.51326044311186, 1e-9);

  // (x0, y0, x1, y1), or all 99 when no tile meets the box.
  const auto range = [](int z, const geo::GeoBox& box) {
    const auto r = xyz_tiles_meeting(z, box);
    return r ? std::array{r->x0, r->y0, r->x1, r->y1} : std::array{99u, 99u, 99u, 99u};
  };
  const geo::GeoBox n42{0.999583, 41.999583, 2.000417, 43.000417};
  EXPECT_EQ(range(0, n42), (std::array{0u, 0u, 0u, 0u}));
  EXPECT_EQ(range(1, n42), (std::array{1u, 0u, 1u, 0u}));
  // At zoom 8 tiles are 1.40625° wide: 0.999583..2.000417 meets columns 128
  // and 129; rows 94 and 95 (tile 95 ends at 42.03°, above 41.999583).
  EXPECT_EQ(range(8, n42), (std::array{128u, 94u, 129u, 95u}));
  // A box edge on a tile edge does not bring in the tile beyond.
  EXPECT_EQ(range(1, {0, 10, 10, 20}), (std::array{1u, 0u, 1u, 0u}));
  // Beyond the square world's edge: nothing.
  EXPECT_EQ(range(3, {0, 86, 10, 89}), (std::array{99u, 99u, 99u, 99u}));
  EXPECT_TRUE(XyzKey(3, 7, 7).valid());
  EXPECT_FALSE(XyzKey(3, 8, 0).valid());
}

}  // namespace
}  // namespace relief::web
