// Terrain-RGB and Terrarium tiles of a real store (N42E001): pixels checked
// against heights computed independently from the store's samples
// (expected_heights.h), the level rule, availability and TileJSON.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <nlohmann/json.hpp>
#include <random>

#include "expected_heights.h"
#include "relief/tiles/codec.h"
#include "relief/tiles/store.h"
#include "relief/web/raster_tiles.h"
#include "test_support.h"

namespace relief::web {
namespace {

using testing::bilinear_height;
using testing::level_for_pixel;
using testing::pixel_centre;

RasterTileOptions options(int tile_size, int max_zoom = -1,
                          std::optional<geo::GeoBox> bbox = std::nullopt) {
  RasterTileOptions o;
  o.tile_size = tile_size, o.max_zoom = max_zoom, o.bbox = bbox;
  return o;
}

class RasterTiles : public testing::SmallStoreSuite {
 protected:
  static std::shared_ptr<const tiles::Store> open_store() {
    auto opened = tiles::Store::open(store());
    EXPECT_TRUE(opened.has_value());
    return std::make_shared<const tiles::Store>(std::move(*opened));
  }
  static RasterTiler tiler(RasterTileOptions o = {}) {
    auto t = RasterTiler::create(open_store(), o);
    EXPECT_TRUE(t.has_value()) << t.error().message;
    return std::move(*t);
  }
};

tiles::Raster decode_png(const std::vector<std::byte>& png, int n) {
  auto r = tiles::decode(tiles::Codec::Png, png, tiles::SampleType::UInt8, 4, n, n);
  EXPECT_TRUE(r.has_value());
  return std::move(*r);
}

Rgb rgb_at(const tiles::Raster& r, int i, int j) {
  const auto p = r.u8().subspan((static_cast<size_t>(j) * r.width() + i) * 4, 4);
  EXPECT_EQ(p[3], 255) << "DEM pixels are opaque";
  return {p[0], p[1], p[2]};
}

// Random pixels inside the data of random tiles of zoom z: the decoded PNG
// and the tiler's heights against the independent bilinear height.
void check_zoom(const RasterTiler& t, const tiles::Store& s, int z, DemEncoding e, int& checked) {
  const int n = t.tile_size();
  const double step = e == DemEncoding::TerrainRgb ? 0.1 : 1.0 / 256;
  // A few tiles (each made once), many pixels.
  auto keys = t.available_tiles(z);
  ASSERT_FALSE(keys.empty()) << z;
  const geo::GeoBox data = s.manifest().extent;
  std::mt19937 random(static_cast<unsigned>(z * 31 + n));
  std::shuffle(keys.begin(), keys.end(), random);
  keys.resize(std::min<size_t>(keys.size(), 3));
  std::map<XyzKey, std::pair<std::vector<double>, tiles::Raster>> made_tiles;
  int found = 0;
  for (int attempt = 0; attempt < 100000 && found < 12; ++attempt) {
    const XyzKey k = keys[random() % keys.size()];
    const int i = static_cast<int>(random() % n), j = static_cast<int>(random() % n);
    const auto p = pixel_centre(k.z, k.x, k.y, n, i, j);
    if (p.lon < data.west || p.lon > data.east || p.lat < data.south || p.lat > data.north)
      continue;
    const auto expected = bilinear_height(s, level_for_pixel(s, z, n, p.lat), p);
    if (!expected) continue;
    ++found;
    SCOPED_TRACE(k.to_string() + " pixel " + std::to_string(i) + "," + std::to_string(j));
    auto made = made_tiles.find(k);
    if (made == made_tiles.end()) {
      auto heights = t.heights(k);
      auto png = t.dem_png_tile(k, e);
      ASSERT_TRUE(heights.has_value() && png.has_value());
      made = made_tiles.emplace(k, std::pair{std::move(*heights), decode_png(*png, n)}).first;
    }
    const auto& [heights, decoded] = made->second;
    EXPECT_NEAR(heights[static_cast<size_t>(j) * n + i], *expected, 1e-6);
    // Half a step of the encoding, and rounding of the interpolation.
    EXPECT_NEAR(decode_height(e, rgb_at(decoded, i, j)), *expected, step / 2 + 1e-3);
  }
  EXPECT_EQ(found, 12) << "zoom " << z << ": too few pixels with data";
  checked += found;
}

TEST_F(RasterTiles, PixelsAreBilinearHeightsOfTheLevelTheirRowReads) {
  auto store = open_store();
  int checked = 0;
  for (const int n : {256, 512}) {
    // Two zooms beyond the natural maximum: upsampled from the finest level.
    const RasterTiler t = tiler(options(n, n == 256 ? 13 : 12));
    for (const int z : {6, 9, 10, 11, 13}) {
      if (n == 512 && z == 13) continue;
      check_zoom(t, *store, z, DemEncoding::TerrainRgb, checked);
      check_zoom(t, *store, z, DemEncoding::Terrarium, checked);
    }
  }
  EXPECT_EQ(checked, 12 * 2 * 9);
}

TEST_F(RasterTiles, TheLevelRule) {
  const RasterTiler t = tiler();
  EXPECT_EQ(t.source_level(11, 42.5), 10);  // 11 + 8 - 9, cos 42.5° > 1/2
  EXPECT_EQ(t.source_level(10, 42.5), 9);
  EXPECT_EQ(t.source_level(0, 0.3), 0);
  EXPECT_EQ(t.source_level(5, 59.9), 4);  // cos > 1/2
  EXPECT_EQ(t.source_level(5, 60.1), 5);  // cos < 1/2: one level finer
  EXPECT_EQ(t.source_level(5, 80.0), 6);  // 1/cos 80° = 5.8: two
  EXPECT_EQ(t.source_level(5, -80.0), 6);
  EXPECT_EQ(t.source_level(20, 42.5), 10) << "beyond the finest level: upsampled";
  const RasterTiler big = tiler(options(512));
  EXPECT_EQ(big.source_level(10, 42.5), 10);
  EXPECT_EQ(big.source_level(0, 0.3), 0);
}

TEST_F(RasterTiles, NoDataIsZeroMetresAndOpaque) {
  const RasterTiler t = tiler();
  // Zoom 8 tile (128, 94) spans lon 0..1.40625: its west column is west of
  // the data (lon 0.999583..2.000417).
  const XyzKey k{8, 128, 94};
  auto heights = t.heights(k);
  ASSERT_TRUE(heights.has_value());
  EXPECT_TRUE(std::isnan((*heights)[0]));
  for (const auto e : {DemEncoding::TerrainRgb, DemEncoding::Terrarium}) {
    auto png = t.dem_png_tile(k, e);
    ASSERT_TRUE(png.has_value());
    const tiles::Raster r = decode_png(*png, 256);
    EXPECT_EQ(rgb_at(r, 0, 0), encode_height(e, 0));
    EXPECT_EQ(rgb_at(r, 0, 255), encode_height(e, 0));
    EXPECT_NE(rgb_at(r, 255, 100), encode_height(e, 0));
  }
}

TEST_F(RasterTiles, TilesMeetingTheExtentUpToTheNaturalMaxZoom) {
  const RasterTiler t = tiler();
  // Level 10 is read from zoom 11 on at 256 pixels (from 10 at 512), as
  // the extent's latitudes (42-43°) are below 60°.
  EXPECT_EQ(t.natural_max_zoom(), 11);
  EXPECT_EQ(t.max_zoom(), 11);
  EXPECT_EQ(tiler(options(512)).max_zoom(), 10);
  const geo::GeoBox extent = open_store()->manifest().extent;
  for (int z = 0; z <= 11; ++z) {
    const auto keys = t.available_tiles(z);
    size_t expected = 0;
    const uint32_t n = 1u << z;
    for (uint32_t y = 0; y < n && z <= 8; ++y) {
      for (uint32_t x = 0; x < n; ++x) {
        const bool meets = XyzKey{z, x, y}.bounds().intersects(extent);
        EXPECT_EQ(t.available({z, x, y}), meets) << z << "/" << x << "/" << y;
        expected += meets;
      }
    }
    if (z <= 8) {
      EXPECT_EQ(keys.size(), expected) << z;
    }
    for (const XyzKey& k : keys) EXPECT_TRUE(k.bounds().intersects(extent)) << k.to_string();
  }
  EXPECT_TRUE(t.available_tiles(12).empty());
  EXPECT_FALSE(t.dem_png_tile({12, 2053, 1505}, DemEncoding::TerrainRgb).has_value());
  EXPECT_FALSE(t.available({3, 0, 0}));
  EXPECT_FALSE(t.dem_png_tile({3, 0, 0}, DemEncoding::TerrainRgb).has_value());
  // A bbox narrows it.
  const RasterTiler part = tiler(options(256, -1, geo::GeoBox{1.6, 42.6, 1.7, 42.7}));
  EXPECT_LT(part.available_tiles(11).size(), t.available_tiles(11).size());
  EXPECT_FALSE(
      RasterTiler::create(open_store(), options(256, -1, geo::GeoBox{5, 5, 6, 6})).has_value());
  EXPECT_FALSE(RasterTiler::create(open_store(), options(300)).has_value());
}

TEST_F(RasterTiles, TileJson) {
  const auto j = nlohmann::json::parse(tiler().tile_json("n42", DemEncoding::Terrarium));
  EXPECT_EQ(j["tilejson"], "2.2.0");
  EXPECT_EQ(j["tiles"], nlohmann::json::array({"{z}/{x}/{y}.png"}));
  EXPECT_EQ(j["scheme"], "xyz");
  EXPECT_EQ(j["minzoom"], 0);
  EXPECT_EQ(j["maxzoom"], 11);
  EXPECT_EQ(j["encoding"], "terrarium");
  EXPECT_EQ(j["tileSize"], 256);
  EXPECT_NEAR(j["bounds"][0].get<double>(), 0.999583, 1e-6);
  EXPECT_NEAR(j["bounds"][3].get<double>(), 43.000417, 1e-6);
  const auto big =
      nlohmann::json::parse(tiler(options(512)).tile_json("n42", DemEncoding::TerrainRgb));
  EXPECT_EQ(big["encoding"], "mapbox");
  EXPECT_EQ(big["tileSize"], 512);
  EXPECT_EQ(big["maxzoom"], 10);
  EXPECT_FALSE(nlohmann::json::parse(tiler().tile_json("n42", std::nullopt)).contains("encoding"));
}

TEST_F(RasterTiles, AnElevationStoreHasNoImagery) {
  const RasterTiler t = tiler();
  EXPECT_TRUE(t.holds_elevation());
  auto r = t.imagery_png_tile({0, 0, 0});
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("elevation"), std::string::npos) << r.error().message;
}

}  // namespace
}  // namespace relief::web
